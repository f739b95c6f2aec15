// A patrol robot application: the framework's types and those of the plugin its profile names (patrol_plugin.cpp)
// on simulated time; prints the life cycle. Usage: custom_robot [PROFILE [TASK]] (exit 1: the task failed).
#include <spdlog/spdlog.h>

#include <iostream>

#include "tripodal/builtin/register_all.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/robot/plugin_library.hpp"
#include "tripodal/robot/robot.hpp"

using namespace tripodal;

int main(int argc, char** argv) try {
  spdlog::set_level(spdlog::level::warn);  // the life cycle is printed at the end, on simulated time
  const RobotProfile profile = load_robot_profile(argc > 1 ? argv[1] : PATROL_PROFILE);
  RobotPlugins plugins = builtin_plugins();      // the framework's types,
  (void)load_profile_plugins(profile, plugins);  // then those of the profile's plugins: [patrol_plugin.so]
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  std::cout << "base controller: " << robot->behavior_loop().controller()->type_name() << '\n';  // the plugin's patrol_drive
  LifecycleRecorder life;
  robot->planner().add_observer(life);
  std::cout << robot->command(argc > 2 ? argv[2] : "patrol door_2111 and door_2133").text << '\n';
  while (robot->planner().busy() && clock.now() < time_from_seconds(600.0)) robot->run_for(robot->behavior_loop().period());
  const TaskReport report = robot->planner().report();
  std::cout << life.str() << "task " << to_string(report.state) << (report.reason.empty() ? "" : ": " + report.reason) << '\n';
  return report.state == TaskState::succeeded ? 0 : 1;
} catch (const std::exception& e) {  // a profile, net or task file that does not load, a plugin refused: located
  std::cerr << e.what() << '\n';
  return 2;
}
