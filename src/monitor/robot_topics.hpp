// The robot monitor's topics (docs/monitor.md): the channels RobotMonitor advertises on its server
// and what it publishes on them between periods — pose, path, map, laser, the running nets and
// their markings, the life cycle, the status panel, the cleaned cells. Private to the monitor:
// RobotMonitor (robot_monitor.cpp) owns one beside its operator console.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "net_drawing.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/hri/hri_service.hpp"
#include "tripodal/monitor/monitor_server.hpp"
#include "tripodal/monitor/robot_monitor.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/robot/robot.hpp"

namespace tripodal::monitor {

/// A net running now: the task's ("task") or a process run's.
struct NetView {
  std::string run;
  const PetriNet* net = nullptr;
  const Engine* engine = nullptr;
};

/// What the status panel shows of the operator console and the robot's observers.
struct ConsoleState {
  bool paused = false;
  std::string_view pause_reason;
  const std::set<std::string, std::less<>>& breakpoints;
  bool driving = false;
  const std::map<std::string, std::string, std::less<>>& behavior_params;  ///< behavior -> "a=1, b=2"
  const std::map<std::string, std::string, std::less<>>& last_firing;      ///< run -> transition id
  HriService* hri = nullptr;
  std::string_view robot_name;  ///< RobotMonitorOptions::robot_name, identity
  std::string_view identity;
};

class RobotTopics final {
 public:
  /// Advertises the topics on `server` (not started yet).
  RobotTopics(Robot& robot, const Clock& clock, MonitorServer& server);

  /// The nets running now, with their drawings.
  void publish_nets();
  /// The map and its sections, once (a robot without a map: never).
  void publish_map_once();
  /// The life cycle's entries not published yet, but the firings (they travel as markings).
  void publish_lifecycle(const LifecycleRecorder& life);
  /// Pose, path (when it changed), laser (when new), markings and status.
  void publish_periodic(const MonitorExtras& extras, const ConsoleState& console);
  /// The cleaned cells, a bit per cell.
  void publish_cleaned(const std::vector<std::uint8_t>& mask);

 private:
  [[nodiscard]] double now_s() const { return to_seconds(clock_.now()); }
  [[nodiscard]] std::vector<NetView> running_nets() const;
  void publish_map();
  void publish_laser(double t, const NavigationData& nav);
  void publish_markings(double t, const ConsoleState& console);
  void publish_status(double t, const MonitorExtras& extras, const ConsoleState& console);

  Robot& robot_;
  const Clock& clock_;
  MonitorServer& server_;
  NetDrawing drawing_;
  std::uint32_t ch_pose_ = 0, ch_path_ = 0, ch_map_ = 0, ch_cleaned_ = 0, ch_laser_ = 0, ch_nets_ = 0, ch_markings_ = 0,
                ch_lifecycle_ = 0, ch_status_ = 0;
  std::size_t life_published_ = 0;
  std::uint32_t path_id_ = ~0U;
  Time last_scan_{Duration{-1}};
  bool map_sent_ = false;
};

}  // namespace tripodal::monitor
