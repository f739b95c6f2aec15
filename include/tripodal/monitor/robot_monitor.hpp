// RobotMonitor: attaches a MonitorServer to a Robot (monitor area, above robot). On the thread
// that drives the robot, between periods, update() answers the operator's requests (a task in
// plain words, pause, resume, cancel, breakpoints on places; the RKMS administration and the
// touch screen's questions when the robot has an HRI) and publishes the topics: pose, path,
// map and sections, cleaned cells, laser, the running nets and their markings, the task and
// process life cycle, and a status line (behaviors, coordinator winner, velocity, battery,
// coverage, resources' age). Publishing copies into the server's outbox; it never waits on a client.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/geometry.hpp"
#include "tripodal/hri/hri_service.hpp"
#include "tripodal/monitor/monitor_server.hpp"
#include "tripodal/robot/robot.hpp"

namespace tripodal::monitor {

struct RobotMonitorOptions {
  bool start_paused = false;  ///< nothing fires until the operator resumes (attach first)
  /// Least wall time between two publications of the periodic topics (0: every update()).
  double min_interval_s = 0.05;
  /// Least wall time between two maps of cleaned cells (larger than the others).
  double cleaned_interval_s = 0.5;
  /// Manual drive stops when no drive command came for this long (wall time): the dead-man switch.
  double drive_deadman_s = 0.5;
  /// A reload of an edited net that is valid but comes while its run is not quiet is tried again
  /// at each update() (between periods) for this long (wall time), then refused. Less than the
  /// server's answer_timeout_s.
  double reload_wait_s = 2.0;
  /// Where the operator's "map save NAME" writes NAME.yaml and NAME.pgm (live mapping, a
  /// MapBuilder module); empty: saving is refused.
  std::filesystem::path map_dir;
  /// The robot's HRI for the RKMS administration and the touch page (docs/monitor.md); nullptr:
  /// the first module of the robot that implements HriService (the HRI module of its profile,
  /// which names the knowledge file), if any. Must outlive the monitor.
  HriService* hri = nullptr;
  /// Which robot this is, for an operator watching a fleet: its name (the profile's) and how the
  /// fleet reaches it ("DDS domain 78, namespace 'robot1', secured as 'robot1' (keys ...)"; empty:
  /// not on DDS). On /status as `robot` and `identity` (null when empty).
  std::string robot_name;
  std::string identity;
};

/// What the application knows beyond the robot: the simulator's true pose, the measured coverage
/// and the cleaned cells (a mask over the map's grid, row-major).
struct MonitorExtras {
  std::optional<Pose2D> true_pose;
  std::optional<double> coverage;
  const std::vector<std::uint8_t>* cleaned_mask = nullptr;
};

class RobotMonitor final {
 public:
  /// Advertises the topics on `server` (which must not be started yet), observes the robot's
  /// planner and supervisor, and adds the input and lock "operator" to the behavior loop's
  /// coordinator (so: before the robot's threads start, if they do). Robot, clock (the robot's) and server must outlive the monitor.
  RobotMonitor(Robot& robot, const Clock& clock, MonitorServer& server, RobotMonitorOptions options = {});
  ~RobotMonitor();
  RobotMonitor(const RobotMonitor&) = delete;
  RobotMonitor& operator=(const RobotMonitor&) = delete;

  /// On the robot's thread, between periods: operator requests, then the topics that are due.
  void update(const MonitorExtras& extras = {});
  /// Whether the run should hold (operator pause, start paused, a breakpoint was reached). The
  /// driving loop keeps calling update() while paused.
  [[nodiscard]] bool paused() const noexcept;
  void pause(const std::string& reason);
  void resume();
  /// Places ("P1" or a place's name in any net, "PrCleaning.P1" in one net) where the run pauses
  /// when they become marked. Throws std::invalid_argument for a place of 0 or more than 256 bytes
  /// or a 65th breakpoint (the operator's budget, docs/monitor.md "Budgets").
  void set_breakpoint(std::string place, bool on);
  [[nodiscard]] std::vector<std::string> breakpoints() const;
  /// The HRI the RKMS and touch ops reach, when the application builds it after the monitor
  /// (RobotMonitorOptions::hri otherwise); nullptr: none (those ops answer 404). Call it from the
  /// thread that calls update(); `hri` must outlive the monitor or be replaced first.
  void set_hri(HriService* hri) noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal::monitor
