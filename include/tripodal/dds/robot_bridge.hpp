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

struct RobotBridgeOptions {
  /// The robot's clock is not the wall clock (a simulation, a replay): its time goes out on /clock
  /// for ROS 2 nodes with use_sim_time.
  bool simulated_time = false;
};

class RobotBridge final {
 public:
  /// Creates the participant (the ROS 2 node "<ns>/tripodal" in ros_discovery_info) and the topics
  /// `section` names, and observes the robot's planner and supervisor (the observers the monitor
  /// uses). Robot and clock (the robot's) must outlive the bridge. Throws DdsError when the
  /// participant or a topic cannot be created.
  RobotBridge(Robot& robot, const Clock& clock, const DdsSection& section, const RobotBridgeOptions& options = {});
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
  /// (rt/<ns>/tripodal/markings), "task" (rt/<ns>/tripodal/task), and the global ones: "tf"
  /// (rt/tf), "tf_static" (rt/tf_static), "clock" (rt/clock).
  [[nodiscard]] std::string topic(std::string_view which) const;
  /// Samples written so far on topic `which` (as topic() names them); task: commands taken.
  [[nodiscard]] std::uint64_t count(std::string_view which) const noexcept;
  /// A frame of this robot as tf names it: "base_link" -> "<ns>/base_link" (no prefix without a
  /// namespace), so that several robots share /tf.
  [[nodiscard]] std::string frame(std::string_view name) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal::dds
