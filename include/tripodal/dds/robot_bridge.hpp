// RobotBridge: a running Robot on DDS, configured by its profile's `dds:` section (tripodal::dds
// area, above robot; docs/distribution.md). It publishes the robot's odometry, pose estimate, map,
// events (faults, task and process life cycle) and net markings as ROS 2-compatible topics, and
// hands the task commands it receives to the planner, as the monitor's console does.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "tripodal/core/clock.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::dds {

class RobotBridge final {
 public:
  /// Creates the participant and the topics `section` names, and observes the robot's planner and
  /// supervisor (the observers the monitor uses). Robot and clock (the robot's) must outlive the
  /// bridge. Throws DdsError when the participant or a topic cannot be created.
  RobotBridge(Robot& robot, const Clock& clock, const DdsSection& section);
  ~RobotBridge();
  RobotBridge(const RobotBridge&) = delete;
  RobotBridge& operator=(const RobotBridge&) = delete;

  /// On the thread that drives the robot, between periods (as RobotMonitor::update): the task
  /// commands received since the last call, then odometry, pose and markings when a period of
  /// the section is due, the map when it is first available or changes size.
  /// The observers run on the thread of the robot's sequencing loop, so the robot is driven from
  /// the thread that calls update() (run_until(), as `tripodal run` does), not with
  /// Robot::start()'s threads.
  void update();
  /// Whether a "pause" command holds the run (until "resume"); the driving loop keeps calling
  /// update() while paused.
  [[nodiscard]] bool paused() const noexcept;

  /// The DDS name of one of the bridge's topics: "odom" -> "rt/<ns>/odom"; also "pose"
  /// (rt/<ns>/amcl_pose), "map", "events" (rt/<ns>/tripodal/events), "markings"
  /// (rt/<ns>/tripodal/markings), "task" (rt/<ns>/tripodal/task).
  [[nodiscard]] std::string topic(std::string_view which) const;
  /// Samples written so far on topic `which` (as topic() names them); task: commands taken.
  [[nodiscard]] std::uint64_t count(std::string_view which) const noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal::dds
