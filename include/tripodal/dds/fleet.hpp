// The fleet planner: a task split into units (rooms, or sections of a room) shared among robots
// that each run in their own process on DDS (tripodal::dds area, above RobotBridge;
// docs/distribution.md, "A fleet"). FleetPlanner is the logic alone (assignment, follow-up,
// reassignment of a silent robot's work, the one result), testable without DDS; DdsFleet connects
// it to the robots' tripodal/task and tripodal/events topics and their liveliness.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/dds/participant.hpp"

namespace tripodal::dds {

/// One share of the fleet's task: a task text a robot's planner accepts on its own.
struct FleetUnit {
  std::string name;      ///< "A" (a section), "3211" (a room)
  std::string task;      ///< what the robot is told: "clean the section A"
  double area_m2 = 1.0;  ///< the unit's weight in the balance (> 0)
  double x_m = 0.0, y_m = 0.0;  ///< where it is (its centroid), for the nearest robot on ties
};

/// A robot of the fleet: its DDS namespace (rt/<name>/tripodal/task) and where it starts.
struct FleetRobot {
  std::string name;
  double x_m = 0.0, y_m = 0.0;
  std::string ns{};  ///< its DDS namespace (a fleet file may give one); empty: the name
};

/// The balanced assignment: units by decreasing area, each to the robot with the least area so far;
/// among robots within `tie_m2` of the least, the one nearest (straight line from its start or its
/// last unit's centroid), then the first. Returns, per robot (in the order given), the indices of
/// its units in the order to do them. Robots with `eligible[i] == false` get nothing (empty span:
/// all eligible). Throws std::invalid_argument without robots or with a unit of area <= 0.
[[nodiscard]] std::vector<std::vector<std::size_t>> assign_units(std::span<const FleetUnit> units, std::span<const FleetRobot> robots,
                                                                 std::span<const bool> eligible = {}, double tie_m2 = 1e-6);

/// A TaskCommand the planner wants published to one robot (rt/<robot>/tripodal/task).
struct FleetCommand {
  std::string robot;
  std::uint32_t id = 0;
  std::string command;  ///< "start", "pause", "resume" or "cancel"
  std::string task;
  std::string unit;
};

struct FleetReassignment {
  std::string unit, from, to;
  double at_s = 0.0;   ///< since the planner was created, on its clock
  std::string reason;  ///< "robot3 went silent (liveliness lost)"
};

struct FleetUnitResult {
  std::string name, task;
  std::string state;  ///< "done", "failed", "not done"
  std::string robot;  ///< who did it (done), who failed it (failed), who had it last (not done; empty: nobody)
  std::vector<std::string> assigned;  ///< every robot it was given to, in order
  double started_s = -1.0, finished_s = -1.0;  ///< on the robot that did (or failed) it; -1: never
  std::string detail;  ///< the failure's reason
};

struct FleetResult {
  bool succeeded = false;  ///< every unit done
  std::string reason;      ///< why not
  std::vector<FleetUnitResult> units;
  std::vector<FleetReassignment> reassignments;
  std::vector<std::string> silent;  ///< "robot3 at 12.4 s: liveliness lost"
  std::vector<std::string> back;    ///< "robot3 at 40.1 s (silent 30.2 s)": robots that came back
  std::size_t done_twice = 0;       ///< units a second robot also finished (target 0)
  std::size_t cancelled = 0;        ///< units a robot was told to stop because another finished it first
  double duration_s = 0.0;
  [[nodiscard]] std::size_t done() const noexcept;
  /// One line per unit, reassignment and silent robot, and a summary line.
  [[nodiscard]] std::string text() const;
  [[nodiscard]] std::string json() const;
};

struct FleetOptions {
  /// A robot whose task topic has no reader this long after the start never came: it counts as
  /// silent and its units go to the others.
  Duration startup_timeout{std::chrono::seconds(60)};
  /// A start command without an answer this long is sent again, with the same id (the first
  /// answer to an id counts, later ones are ignored).
  Duration answer_timeout{std::chrono::seconds(5)};
  /// A ready robot with nothing left to do is sent "pause" (its simulation stops spending CPU the
  /// others need), and "resume" before a unit reassigned to it.
  bool pause_idle = true;
  /// A ready robot with nothing left to do takes, before it is paused, the last unit not begun of
  /// the robot with the most area not begun (a reassignment too): the balance made at the start
  /// or at a silence is by area, not by how fast each robot turns out to be.
  bool take_when_idle = true;
  /// How long a silent robot keeps its units before they go to the others: a robot that is back
  /// within it (a short network partition) goes on as if nothing happened. 0: at once.
  Duration silence_grace{0};
};

/// The fleet's logic, fed by its caller (DdsFleet, or a test): which robot is ready, what each
/// robot reports, which went silent; poll() says which commands to send. Not thread-safe: one
/// thread drives it. Times are the clock's, from construction.
class FleetPlanner {
 public:
  /// Assigns every unit (assign_units). Throws std::invalid_argument without robots or units,
  /// with two robots or two units of one name, or a unit of area <= 0.
  FleetPlanner(std::vector<FleetRobot> robots, std::vector<FleetUnit> units, const Clock& clock, FleetOptions options = {});

  /// The robot's task topic has a reader: commands may go to it.
  void robot_ready(std::string_view robot);
  /// An event the robot published (tripodal/events): command_accepted / command_refused for a
  /// command of ours (source "task_command/<id>"), task_succeeded / task_failed (detail: the task).
  void robot_event(std::string_view robot, std::string_view kind, std::string_view source, std::string_view detail);
  /// The robot went silent (its liveliness lost, its process gone): its unit in hand and those it
  /// had not begun go to the robots still alive.
  void robot_silent(std::string_view robot, std::string_view reason);
  /// The robot is heard again (its liveliness regained after a partition). Within the grace time
  /// nothing changes. After it, the robot is used again: the unit it had in hand (it went on with
  /// it, unaware) is taken back from the robot it was given to when that one has not begun it;
  /// when both run it, the first to finish it keeps it and the other is told to cancel. A robot
  /// whose process ended is not back.
  void robot_back(std::string_view robot);
  /// The robot's process ended: it will not be back.
  void robot_gone(std::string_view robot);

  /// The commands to send now: the next unit of each ready robot without one in hand (after a
  /// "resume" when it was paused; one taken from another's queue when it has none,
  /// FleetOptions::take_when_idle), a start not answered within answer_timeout again, "pause" to a
  /// robot with nothing left (FleetOptions::pause_idle). Also applies the startup timeout.
  [[nodiscard]] std::vector<FleetCommand> poll();
  /// Every unit done or failed, or no robot left alive to do the rest.
  [[nodiscard]] bool finished() const noexcept;
  [[nodiscard]] FleetResult result() const;

  /// What happened, one line each ("12.3 s robot3 went silent ..."), for the caller to print; taken
  /// lines are not returned again.
  [[nodiscard]] std::vector<std::string> take_log();
  /// The units a robot has still to do (in hand first), by name; for tests and the log.
  [[nodiscard]] std::vector<std::string> queue_of(std::string_view robot) const;
  [[nodiscard]] bool alive(std::string_view robot) const;
  /// Whether robot_ready() came for it.
  [[nodiscard]] bool ready(std::string_view robot) const;
  /// When the robot was sent the unit it has in hand (elapsed_s()), nullopt when it has none.
  [[nodiscard]] std::optional<double> busy_since_s(std::string_view robot) const;
  /// Seconds on the clock since construction.
  [[nodiscard]] double elapsed_s() const noexcept;

 private:
  struct Robot;
  struct Unit;
  [[nodiscard]] double seconds() const noexcept;
  Robot* find(std::string_view robot);
  [[nodiscard]] const Robot* find(std::string_view robot) const;
  void note(std::string line);
  void finish_unit(Robot& r, bool ok, std::string_view detail);
  void redistribute(std::vector<std::size_t> units, const std::string& from, const std::string& reason);
  void take_queued(Robot& idle);
  void declare_silent(Robot& r);
  std::size_t done_twice_ = 0, cancelled_ = 0;
  std::vector<std::string> back_;
  std::vector<FleetCommand> pending_;  // commands decided outside poll() (a cancel), sent by the next poll()

  const Clock& clock_;
  FleetOptions options_;
  Time start_;
  std::vector<FleetRobot> robot_info_;
  std::vector<FleetUnit> unit_info_;
  std::vector<std::unique_ptr<Robot>> robots_;
  std::vector<Unit> units_;
  std::vector<FleetReassignment> reassignments_;
  std::vector<std::string> silent_;
  std::vector<std::string> log_;
  std::uint32_t next_id_ = 1;

 public:
  ~FleetPlanner();
  FleetPlanner(const FleetPlanner&) = delete;
  FleetPlanner& operator=(const FleetPlanner&) = delete;
};

struct DdsFleetOptions {
  std::uint32_t domain_id = 0;
  Network network = Network::loopback;
  /// The fleet's own participant lease (how long the robots wait for the fleet); the robots'
  /// leases are theirs (their profiles' participant_lease_s), and decide how soon a dead robot
  /// is seen.
  std::chrono::milliseconds participant_lease{std::chrono::seconds(10)};
  /// DDS Security: the fleet tool's identity (security.hpp, fleet_identity); unset, not secured.
  /// Its robots must then be secured by the same CA (their profiles' dds: security).
  std::optional<SecurityFiles> security{};
};

/// The fleet planner on DDS: a participant, per robot a TaskCommand publisher on
/// rt/<robot>/tripodal/task and an Event subscriber on rt/<robot>/tripodal/events whose lost
/// liveliness (the robot's process died and its lease ran out, or it left) is the robot going
/// silent. Events arrive on Cyclone DDS threads and reach the planner in update(), on the caller's
/// thread. Throws DdsError when the participant or a topic cannot be created.
class DdsFleet {
 public:
  DdsFleet(FleetPlanner& planner, std::span<const FleetRobot> robots, const DdsFleetOptions& options = {});
  ~DdsFleet();
  DdsFleet(const DdsFleet&) = delete;
  DdsFleet& operator=(const DdsFleet&) = delete;
  /// Hands what arrived to the planner, then publishes the commands it asks for.
  void update();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal::dds
