// RobotHarness: the test kit for a whole robot — its processes, navigation modules, behaviors and
// controllers assembled from its profile — run on a recorded trace. Open loop (replay): the trace
// is the robot's hardware and the recorded world does not react to the robot. Closed loop: the
// robot starts where the trace starts in a simulated world that reacts. Either way a test gives a
// task in plain words and asserts on the RunLog (commands, processes, behaviors, events).
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/world.hpp"
#include "tripodal/testing/behavior_harness.hpp"
#include "tripodal/testing/trace_hardware.hpp"

namespace tripodal::testing {

struct RobotHarnessOptions {
  RobotOptions robot;  ///< parameter overrides, supervisor and planner options
  /// The trace's odometry channel of recorded map_from_base poses: the localizer's ground truth in
  /// a replay, and the start pose of a closed-loop run (empty: the first odometry reading's pose).
  std::string localization_channel;
  /// Replay: the world whose map the robot takes when its profile names none. Closed loop: the
  /// simulated world (required); the robot starts at the trace's recorded start pose in it.
  std::shared_ptr<const sim::World> world;
  /// The footprint and laser mount of RunLog::never_drives_toward_obstacle_closer_than.
  double robot_radius_m = 0.25;
  Pose2D laser_in_body;
  /// Shared-library plugins added to the plugin set before the profile's own `plugins:` list
  /// (docs/plugins.md); the harness loads both, as `tripodal run --plugin` does.
  std::vector<std::filesystem::path> plugins;
};

class RobotHarness final {
 public:
  enum class Mode { replay, closed_loop };

  /// Assembles the robot of `profile` (its hardware slot replaced: by the trace for a replay, by
  /// the simulator in options.world for a closed loop) with `plugins` and the trace's recorded
  /// start. Loads options.plugins and the profile's `plugins:` into `plugins` first. Throws what
  /// Robot::assemble throws, ConfigError for a refused plugin, trace::TraceIoError /
  /// TraceFormatError, and std::invalid_argument (a missing world or channel, a trace without a
  /// pose to start from).
  RobotHarness(Mode mode, const RobotProfile& profile, RobotPlugins plugins, const std::filesystem::path& trace,
               RobotHarnessOptions options = {});
  ~RobotHarness();
  RobotHarness(const RobotHarness&) = delete;
  RobotHarness& operator=(const RobotHarness&) = delete;

  /// A task in plain words (the planner's command); recorded as event "task.refused" if refused.
  CommandAnswer command(std::string_view text);

  /// Runs the robot one behavior-loop period at a time until `until` (trace time; a replay stops at
  /// the end of the trace whatever `until`), by default the end of the trace (one period past its
  /// last record), or, when stop_when_idle, the end of the task. Can be called again to continue. Throws
  /// std::runtime_error when the trace turns out corrupt mid-replay (naming the byte offset).
  const RunLog& run(std::optional<Time> until = std::nullopt, bool stop_when_idle = true);

  [[nodiscard]] Robot& robot() noexcept { return *robot_; }
  [[nodiscard]] const RunLog& log() const noexcept { return log_; }
  [[nodiscard]] Mode mode() const noexcept { return mode_; }
  /// Trace time now (the robot's clock, shifted in a closed loop where the simulation starts at 0).
  [[nodiscard]] Time now() const noexcept;
  [[nodiscard]] Time start_time() const noexcept { return summary_.first; }
  [[nodiscard]] Time end_time() const noexcept { return summary_.last; }
  /// Where the robot started: the recorded pose of the trace's start.
  [[nodiscard]] const Pose2D& start_pose() const noexcept { return start_pose_; }

 private:
  class Observer;
  void record_step();

  Mode mode_;
  RobotHarnessOptions options_;
  trace::TraceSummary summary_;
  Pose2D start_pose_;
  Duration offset_{0};  // trace time = robot time + offset_
  SimClock clock_;
  RobotPlugins plugins_;  // the robot creates behaviors from them at each activation
  RunLog log_;
  std::unique_ptr<Observer> observer_;
  std::unique_ptr<Robot> robot_;
  TraceHardware* trace_hw_ = nullptr;
  const LaserResource* laser_ = nullptr;
};

}  // namespace tripodal::testing
