// Configuration of the reactive layer from YAML: the base controllers and the control loops
// (period, controller, coordinator inputs and locks, real-time options). Loading turns the file
// into typed structs once; every problem of the file is reported with file:line:col.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/reactive/control_loop.hpp"

namespace tripodal {

struct LoopConfig {
  std::string name;
  Duration period{std::chrono::milliseconds(10)};
  std::string controller;           ///< name of a configured controller; empty = none
  LoopTimingOptions timing;         ///< realtime_priority, cpu
  std::size_t max_behaviors = 16;
  CoordinatorConfig coordinator;
  SourceLocation where;
};

struct ReactiveConfig {
  std::vector<ControllerConfig> controllers;
  std::vector<LoopConfig> loops;
  [[nodiscard]] const ControllerConfig* find_controller(std::string_view name) const noexcept;
  [[nodiscard]] const LoopConfig* find_loop(std::string_view name) const noexcept;
};

/// Parses `text` (a YAML document; `file` names it in messages). Throws ConfigError listing
/// every problem: unknown keys, values of the wrong type, a negative or zero radius, a missing
/// wheel geometry, an unknown controller type, a loop naming an unknown controller, duplicate
/// names. Controller types are checked against `registry`.
[[nodiscard]] ReactiveConfig parse_reactive_config(std::string_view text, const std::string& file,
                                                   const ControllerRegistry& registry);
/// Reads and parses the file at `path`; ConfigError also when it cannot be read.
[[nodiscard]] ReactiveConfig load_reactive_config(const std::string& path, const ControllerRegistry& registry);

}  // namespace tripodal
