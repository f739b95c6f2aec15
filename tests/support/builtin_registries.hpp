// The built-in behavior and controller types for the tests of the areas below the robot, which
// create single behaviors and controllers without a robot or a plugin set: one registry of each
// family, filled once by the area's register function, read-only afterwards.
#pragma once

#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/controller_config.hpp"

namespace tripodal::test {

inline const BehaviorRegistry& builtin_behaviors() {
  static const BehaviorRegistry registry = [] {
    BehaviorRegistry r;
    register_behaviors(r);
    return r;
  }();
  return registry;
}

inline const ControllerRegistry& builtin_controllers() {
  static const ControllerRegistry registry = [] {
    ControllerRegistry r;
    register_builtin_controllers(r);
    return r;
  }();
  return registry;
}

}  // namespace tripodal::test
