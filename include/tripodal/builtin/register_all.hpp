// The framework's built-in plugin types, registered into the plugin set an application owns: the
// top of the area graph below the application, the one place that knows every area's register
// function. An application builds its RobotPlugins, calls register_all(), adds its own types (or
// loads them from shared libraries: robot/plugin_library.hpp) and passes the set to the robot and
// to every tool.
#pragma once

#include <memory>

#include "tripodal/robot/plugins.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal {

/// Registers the types of every built-in area into `plugins`: behaviors (built-in, navigation,
/// gesture; behaviors area), the board's actuator behaviors and BoardMonitor (board), the
/// differential, omni and mecanum controllers (controllers), the navigation modules (navi), the
/// HRI module "Hri" (hri) and the simulated hardware types "sim" and "board" (sim). With `world`,
/// every robot built on simulated hardware runs in that world (as `tripodal run --world` does);
/// otherwise the hardware's parameter `world` names the file. Throws std::invalid_argument when
/// `plugins` already holds one of these names (register once, then add the application's).
void register_all(RobotPlugins& plugins, std::shared_ptr<const sim::World> world = nullptr);

/// A plugin set with register_all() applied: `RobotPlugins p = builtin_plugins(); p.behaviors.add<Mine>();`
[[nodiscard]] RobotPlugins builtin_plugins(std::shared_ptr<const sim::World> world = nullptr);

}  // namespace tripodal
