// The behavior test kit: replays a recorded trace into resources on a simulated clock, steps
// behaviors through a behavior coordinator as the reactive layer does, and records what they did so
// a Catch2 (or any) test can assert on commands, statuses and events over time. Catch2-free.
#pragma once

#include <cstddef>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/trace/rosbag.hpp"
#include "tripodal/trace/trace_replay.hpp"

namespace tripodal::testing {

/// The outcome of an assertion helper: passed or not, and why in words (times, values, limits).
/// Streams its explanation, so `REQUIRE(run.command_never_exceeds(...))` prints it on failure.
struct CheckResult {
  bool passed = false;
  std::string explanation;
  explicit operator bool() const noexcept { return passed; }
  friend std::ostream& operator<<(std::ostream& os, const CheckResult& r) {
    return os << (r.passed ? "passed: " : "FAILED: ") << r.explanation;
  }
};

/// Per-axis magnitude limits a command must stay within (absolute values; infinite = unbounded).
struct CommandLimits {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double max_vx_m_s = kInf;
  double max_vy_m_s = kInf;
  double max_wz_rad_s = kInf;
};

struct HarnessOptions {
  Duration period = std::chrono::milliseconds(50);  ///< behavior sampling period, simulated clock
  BaseCapabilities base;                            ///< what BehaviorContext::base reports
  /// max_age of every resource created for a trace channel (0: a reading never goes stale, which
  /// suits sparse logs; set it to the live robot's value to test stale-data handling).
  Duration resource_max_age{0};
  CoordinationMode mode = CoordinationMode::priority;
  /// Footprint and laser mount the obstacle check uses (see never_drives_toward_obstacle_closer_than).
  double robot_radius_m = 0.25;
  Pose2D laser_in_body;
  std::string laser;  ///< laser resource for the obstacle check; empty = the first laser channel
  /// An odometry channel whose pose is the localizer's map_from_base (NavigationData, localized
  /// once it has a reading), e.g. "laser_pose" of an imported corrected CARMEN log. Empty: the
  /// behaviors see localized = false.
  std::string localization_channel;
};

/// What one behavior did in one period.
struct BehaviorSample {
  std::optional<Twist2D> command;
  std::optional<VelocityEnvelope> envelope;
  BehaviorStatus status = BehaviorStatus::idle;
};

/// One sampling period of a run.
struct StepRecord {
  Time t{};
  Twist2D command;  ///< the coordinator's fused command: what the controller would execute
  bool safety_limited = false;
  bool all_expired = false;
  /// Free distance from the footprint to the nearest laser return in the corridor the footprint
  /// sweeps along the commanded translation (infinite: no translation, no laser or no return).
  double clearance_m = std::numeric_limits<double>::infinity();
  std::vector<BehaviorSample> behaviors;  ///< in order of attachment
};

/// Something that happened: "<Behavior>.done", "<Behavior>.failed" (detail: the reason), or an
/// event record of the trace ("trace:<name>"). A whole robot (RobotHarness) adds the events its
/// process nets consumed or dropped ("localizer.lost"), "<Process>.started|succeeded|failed",
/// "task.started|succeeded|failed|refused", "recovery" and "fault:<source>" (detail: the reason).
struct HarnessEvent {
  Time t{};
  std::string name;
  std::string detail;
};

/// Everything a run produced, with the assertion helpers. Times are trace time (the stamps of the
/// trace's records; the run starts at the first record's stamp).
class RunLog final {
 public:
  [[nodiscard]] const std::vector<StepRecord>& steps() const noexcept { return steps_; }
  [[nodiscard]] const std::vector<HarnessEvent>& events() const noexcept { return events_; }
  /// Command records found in the trace (a recorded run's commands), in trace order.
  [[nodiscard]] const std::vector<trace::CommandRecord>& recorded_commands() const noexcept { return recorded_; }
  [[nodiscard]] const std::vector<std::string>& behavior_names() const noexcept { return names_; }
  /// Index of the attached behavior called `name` (its type name or coordinator input name).
  [[nodiscard]] std::optional<std::size_t> behavior_index(std::string_view name) const noexcept;

  /// Every fused command stays within `limits` (each axis by magnitude, 1e-9 tolerance).
  [[nodiscard]] CheckResult command_never_exceeds(const CommandLimits& limits) const;
  /// The behavior's status became succeeded at a step stamped at or before `t`.
  [[nodiscard]] CheckResult succeeds_before(std::string_view behavior, Time t) const;
  /// The behavior never reported failure.
  [[nodiscard]] CheckResult never_fails(std::string_view behavior) const;
  /// No fused command translates (speed above min_speed_m_s) toward a laser return whose clearance
  /// from the footprint along the motion is below `distance_m`.
  [[nodiscard]] CheckResult never_drives_toward_obstacle_closer_than(double distance_m,
                                                                      double min_speed_m_s = 1e-6) const;
  /// An event named `name` happened at or before `t`.
  [[nodiscard]] CheckResult event_before(std::string_view name, Time t) const;
  /// No event named `name` happened (e.g. "PrAutoMove.failed", "task.failed").
  [[nodiscard]] CheckResult event_never_happens(std::string_view name) const;
  /// The fused commands equal `expected` (stamp and twist, bit for bit), in order.
  [[nodiscard]] CheckResult commands_equal(const std::vector<trace::CommandRecord>& expected) const;

  /// The status of a behavior at the last step stamped at or before t (idle before the first).
  [[nodiscard]] BehaviorStatus status_at(std::string_view behavior, Time t) const;

 private:
  friend class BehaviorHarness;
  friend class RobotHarness;
  [[nodiscard]] std::optional<std::size_t> require_index(std::string_view behavior, CheckResult& out) const;
  std::vector<StepRecord> steps_;
  std::vector<HarnessEvent> events_;
  std::vector<trace::CommandRecord> recorded_;
  std::vector<std::string> names_;
};

/// Free distance from a footprint of radius `robot_radius_m` to the nearest return of `scan` in the
/// corridor it sweeps moving along `command`'s translation (infinite: no translation or no return).
[[nodiscard]] double footprint_clearance_m(const LaserScan& scan, const Pose2D& laser_in_body, double robot_radius_m,
                                           const Twist2D& command) noexcept;

/// Loads a trace, attaches behaviors with parameters and steps them on a simulated clock: every
/// period, the trace's records stamped up to now are published into resources named as their
/// channels, each behavior is stepped (activated at the first step), its command or envelope goes to
/// a CBehaviorCoordinator, and the fused command is recorded.
class BehaviorHarness final {
 public:
  explicit BehaviorHarness(HarnessOptions options = {});
  ~BehaviorHarness();
  BehaviorHarness(const BehaviorHarness&) = delete;
  BehaviorHarness& operator=(const BehaviorHarness&) = delete;

  /// Opens `trace` and creates one resource per sensor channel (a first pass over the file reads
  /// the channel declarations). A rosbag2 bag (folder, .mcap or .db3) is converted first with the
  /// default topic mapping (docs/rosbag.md). Throws trace::TraceIoError / trace::TraceFormatError
  /// (with the byte offset), trace::BagFormatError. Must precede attach().
  void load_trace(const std::filesystem::path& trace);

  /// Attaches a behavior, activated with `params` at the first step (ConfigError then names
  /// `where`). input.name defaults to the behavior's type name; use role safety for overrides such
  /// as BhAvoidObstacle. Returns the behavior. Throws std::logic_error after run() started.
  CBehavior& attach(std::unique_ptr<CBehavior> behavior, ParameterValues params = {},
                    CoordinatorInputConfig input = {}, SourceLocation where = {});

  /// Steps until the trace is exhausted (one period past its last record), `until` (trace time)
  /// is reached, or, when stop_when_done, every normal behavior left running. Can be called again
  /// to continue. Returns the log so far.
  const RunLog& run(std::optional<Time> until = std::nullopt, bool stop_when_done = false);

  [[nodiscard]] const RunLog& log() const noexcept { return log_; }
  [[nodiscard]] const ResourceTable& resources() const noexcept { return table_; }
  /// Trace time of the next step.
  [[nodiscard]] Time now() const noexcept { return now_; }
  /// The trace's first stamp (valid after load_trace).
  [[nodiscard]] Time start_time() const noexcept { return start_; }
  /// Stamp of the trace's last whole record: run() ends one period after it.
  [[nodiscard]] Time end_time() const noexcept { return last_record_; }
  /// Empty, or the reader's warning for a trace cut inside a record (a recorder killed mid-write):
  /// "FILE: truncated at byte N (...)". Such a trace is replayed up to its last whole record.
  [[nodiscard]] const std::string& trace_warning() const noexcept { return warning_; }

 private:
  class Sink;
  struct Attached;
  void step_once();
  [[nodiscard]] double clearance_along(const Twist2D& command) const noexcept;

  HarnessOptions options_;
  ResourceTable table_;
  NavigationData navi_;
  std::unique_ptr<trace::TraceSource> source_;  // before replay_: the replay reads its file
  std::unique_ptr<trace::TraceReplay> replay_;
  std::unique_ptr<Sink> sink_;
  std::unique_ptr<CBehaviorCoordinator> coordinator_;
  std::vector<Attached> attached_;
  const LaserResource* laser_ = nullptr;
  const OdometryResource* localization_ = nullptr;
  RunLog log_;
  std::string warning_;
  Time start_{};
  Time now_{};
  Time last_record_{};
  bool started_ = false;
};

}  // namespace tripodal::testing
