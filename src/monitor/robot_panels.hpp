// The monitor page's panels (docs/monitor.md): the status of the robot on /status — task, behaviors,
// the coordinator's winner and command, resources, battery, coverage, the control board's link, what
// the HRI displays, the operator console's state. Private to the monitor, for its topics
// (robot_topics.cpp).
#pragma once

#include <nlohmann/json.hpp>

#include "robot_topics.hpp"

namespace tripodal::monitor {

/// The /status message at `now` (`t_s`, its seconds).
[[nodiscard]] nlohmann::json status_panel(Robot& robot, Time now, double t_s, const MonitorExtras& extras,
                                          const ConsoleState& console);

}  // namespace tripodal::monitor
