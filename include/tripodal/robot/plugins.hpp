// The plugin set an application owns: one Registry (core/registry.hpp) per family — behaviors,
// controllers, modules (CModule: navigation, HRI, application modules), resources, hardware,
// process types — in which the types a robot profile names are found. The application builds it
// (register_all for the built-in areas, builtin/register_all.hpp; its own types; shared-library
// plugins, robot/plugin_library.hpp) and passes it to the robot and to every tool; there is no
// process-wide registry.
#pragma once

#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/registry.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/processes/module.hpp"
#include "tripodal/processes/process_registry.hpp"

namespace tripodal {

/// What the robot gives a resource type's factory: the instance name, its parameters, and the
/// hardware whose device the resource's driver reads.
struct ResourceConfig {
  std::string name;
  ParameterSet parameters;  ///< resolved against the type's manifest
  SourceLocation where;
  CHardware* hardware = nullptr;  ///< the robot's hardware (built before its resources); nullptr: none
};
/// Resource types (sensor drivers: CResource subclasses) by name. The robot adds each to the
/// reactive loops' resource table; the loop polls it every cycle (CResource::on_poll).
using ResourceRegistry = Registry<CResource, const ResourceConfig&>;

/// The application's plugin set. Movable, not copyable (a factory may own state).
struct RobotPlugins {
  BehaviorRegistry behaviors;
  ControllerRegistry controllers;
  ModuleRegistry modules{"module type"};
  ResourceRegistry resources{"resource type"};
  HardwareRegistry hardware{"hardware type"};
  /// Process types: "net" (a plain CProcess) and the application's CProcess subclasses.
  ProcessTypeRegistry processes;
};

}  // namespace tripodal
