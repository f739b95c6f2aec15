#include "tripodal/builtin/register_all.hpp"

#include <utility>

#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/board/board_monitor.hpp"
#include "tripodal/board/rplidar_a1.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/hri/hri_robot_module.hpp"
#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/robot/battery_monitor.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/sim_hardware.hpp"

namespace tripodal {

void register_all(RobotPlugins& plugins, std::shared_ptr<const sim::World> world) {
  register_behaviors(plugins.behaviors);
  board::register_board_behaviors(plugins.behaviors);
  register_builtin_controllers(plugins.controllers);
  navi::register_navigation_modules(plugins.modules);
  board::register_board_modules(plugins.modules);
  board::register_rplidar_resource(plugins.resources);
  register_hri_modules(plugins.modules);
  plugins.modules.add<BatteryMonitor>();
  sim::register_sim_board_hardware(plugins.hardware, world);
  sim::register_sim_hardware(plugins.hardware, std::move(world));
}

RobotPlugins builtin_plugins(std::shared_ptr<const sim::World> world) {
  RobotPlugins plugins;
  register_all(plugins, std::move(world));
  return plugins;
}

}  // namespace tripodal
