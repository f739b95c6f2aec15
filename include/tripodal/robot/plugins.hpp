// The robot's plugin registries: one Registry (core/registry.hpp) per family — behaviors,
// controllers, modules (CModule: navigation, HRI, application modules), hardware — in which the
// types a robot profile names are found. An application adds its own types next to the built-in
// ones before it assembles a robot.
#pragma once

#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/registry.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/processes/module.hpp"
#include "tripodal/processes/process_registry.hpp"

namespace tripodal {

/// What the robot gives a resource type's factory: the instance name and its parameters.
struct ResourceConfig {
  std::string name;
  ParameterSet parameters;  ///< resolved against the type's manifest
  SourceLocation where;
};
/// Resource types (sensor drivers: CResource subclasses) by name. The robot adds each to the
/// reactive loops' resource table; the loop polls it every cycle (CResource::on_poll).
using ResourceRegistry = Registry<CResource, const ResourceConfig&>;

struct RobotPlugins {
  BehaviorRegistry behaviors;
  ControllerRegistry controllers;
  ModuleRegistry modules{"module type"};
  ResourceRegistry resources{"resource type"};
  HardwareRegistry hardware{"hardware type"};
  /// Process types: "net" (a plain CProcess) and the application's CProcess subclasses.
  ProcessTypeRegistry processes;

  /// The framework's own types: the built-in and navigation behaviors, the differential, omni and
  /// mecanum controllers, and the navigation modules (GridMaps, SectionSplitter, Localizer,
  /// PathPlanner, CoveragePlanner). Hardware types live below the robot: the simulator's is added
  /// with sim::register_sim_hardware().
  [[nodiscard]] static RobotPlugins with_builtins();
};

}  // namespace tripodal
