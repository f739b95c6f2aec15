// Test support: a control loop built from a reactive configuration's loop, the way the robot builds
// its loops in Robot::assemble but without a robot, for the tests of the reactive layer and the
// simulator. Not part of the installed API: an application gets its loops from a Robot.
#pragma once

#include <memory>
#include <utility>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/reactive/control_loop.hpp"
#include "tripodal/reactive/reactive_config.hpp"

namespace tripodal::test {

/// The loop `config` describes: its coordinator, and its controller (created through `registry` on
/// `hardware`, which must outlive the loop; may be null when the loop has no controller).
/// ConfigError for an unknown controller name or a controller without hardware.
inline std::unique_ptr<ControlLoop> make_control_loop(const ReactiveConfig& reactive, const LoopConfig& config,
                                                      ResourceTable& resources, HardwareInterface* hardware,
                                                      const ControllerRegistry& registry) {
  std::unique_ptr<CController> controller;
  if (!config.controller.empty()) {
    const ControllerConfig* cc = reactive.find_controller(config.controller);
    if (cc == nullptr)
      throw ConfigError(config.where, "loop '" + config.name + "': unknown controller '" + config.controller + "'");
    if (hardware == nullptr) {
      throw ConfigError(config.where,
                        "loop '" + config.name + "': controller '" + config.controller + "' needs a hardware interface");
    }
    controller = registry.create(*cc, *hardware);
  }
  ControlLoopOptions options;
  options.name = config.name;
  options.period = config.period;
  options.max_behaviors = config.max_behaviors;
  return std::make_unique<ControlLoop>(options, resources, CBehaviorCoordinator(config.coordinator), std::move(controller));
}

}  // namespace tripodal::test
