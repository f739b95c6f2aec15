// Robot: one Tripodal robot assembled from its profile and run on one path. It owns everything the
// profile names — the hardware (hardware slot), the resources its sensors publish, the controllers
// and the reactive control loops (ControlLoop: resources -> behaviors -> coordinator -> controller at
// each loop's period), the modules of the sequencing loop (navigation, HRI, application modules),
// the process supervisor and the planner — and drives them by its clock: on simulated time with
// run_until() (the caller's thread), or in real time with start() (a LoopRunner thread per reactive
// loop, one thread for the sequencing loop). The same code runs either way. It refuses to start when
// an input lacks exactly one provider or a layering rule is broken.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/planner/planner.hpp"
#include "tripodal/processes/module.hpp"
#include "tripodal/processes/process_registry.hpp"
#include "tripodal/processes/process_supervisor.hpp"
#include "tripodal/reactive/control_loop.hpp"
#include "tripodal/robot/layering.hpp"
#include "tripodal/robot/plugins.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal {

/// A value that replaces the profile's: parameter `parameter` of module `module` (a module,
/// controller or the hardware, by instance name) — e.g. a run's seed.
struct ParameterOverride {
  std::string module;
  std::string parameter;
  std::string value;
};

struct RobotOptions {
  SupervisorOptions supervisor;
  PlannerOptions planner;
  std::vector<ParameterOverride> parameters;
  /// Loads a process net; default: load_net_or_throw checking behavior names against the profile.
  std::function<PetriNet(const std::filesystem::path&)> load_net;
};

/// The configuration of the base controller the profile's hardware drives (the controller of the
/// first loop that has one, read from the reactive configuration its entry names), as the robot
/// gives it to its hardware (HardwareConfig::base): what a simulator of the base in another process
/// needs. nullopt when no loop drives a controller; throws ConfigError (located) for a bad entry.
/// Controller types are checked against `controllers`: the application's registry when it has
/// types of its own (RobotPlugins::controllers).
[[nodiscard]] std::optional<ControllerConfig> base_controller_config(
    const RobotProfile& profile, const ControllerRegistry& controllers);

/// Every start-up check of Robot::assemble that builds no instance, as `tripodal describe` runs
/// them: the tasks and recovery rules, one provider per input and the layering rules
/// (describe_robot), every type registered — a type only declared in the profile (layer, inputs,
/// outputs) draws the diagram of a design: a warning here, an error at assembly —, the process
/// nets loaded and each behavior
/// they bind listed under the profile's behaviors (and not a safety one), behaviors named by their
/// type, the controllers' reactive configurations read through `plugins.controllers`. Problems go
/// to `d`, located in the profile or the file they are in; returns the diagram.
[[nodiscard]] RobotDescription check_robot(const RobotProfile& profile, const RobotPlugins& plugins, Diagnostics& d);

class Robot final {
 public:
  /// Builds the robot. Throws ConfigError listing every problem, located: those of check_robot()
  /// (unknown types, the closest registered name suggested; types declared in the profile but not
  /// registered; missing or duplicate providers, layering violations, nets that do not load,
  /// processes binding behaviors the robot lacks, task templates or recovery rules naming unknown
  /// processes), then hardware, resources and modules that do not configure or start.
  static std::unique_ptr<Robot> assemble(const RobotProfile& profile, const RobotPlugins& plugins, Clock& clock,
                                         RobotOptions options = {});
  ~Robot();
  Robot(const Robot&) = delete;
  Robot& operator=(const Robot&) = delete;

  /// A task command in plain words (CPlanner::command).
  CommandAnswer command(std::string_view text);

  /// Simulated time: runs, in time order on the caller's thread, everything due up to `until` —
  /// the hardware advanced to each instant, then the sequencing loop when due, then each reactive
  /// loop when due — and leaves the clock at `until`. Requires the robot's clock to be a SimClock
  /// (std::logic_error otherwise) and the robot not started.
  void run_until(Time until);
  void run_for(Duration d);
  /// Real time: starts the hardware, a LoopRunner per reactive loop and the sequencing thread.
  void start();
  /// Stops the threads and the hardware; idempotent.
  void stop() noexcept;
  [[nodiscard]] bool started() const noexcept;

  /// One period of the sequencing loop at the clock's time (what run_until() and the sequencing
  /// thread call): the reactive loops' reports in, the modules' update, the planner or the
  /// supervisor, the navigation data out. The loops' changes of one period apply together.
  void step_sequencing();

  [[nodiscard]] const RobotDescription& description() const noexcept;
  [[nodiscard]] CPlanner& planner() noexcept;
  [[nodiscard]] CProcessSupervisor& supervisor() noexcept;
  [[nodiscard]] const ProcessRegistry& processes() const noexcept;
  /// The reactive loop running the behaviors (the profile's first loop).
  [[nodiscard]] ControlLoop& behavior_loop() noexcept;
  /// The reactive loop `name`; nullptr when there is none.
  [[nodiscard]] ControlLoop* loop(std::string_view name) noexcept;
  [[nodiscard]] CHardware* hardware() noexcept;
  [[nodiscard]] const ResourceTable& resources() const noexcept;
  /// The navigation data the sequencing loop publishes (as of its last period).
  [[nodiscard]] const NavigationData& navigation() const noexcept;
  /// Whether the behavior `name` is active (activated by the supervisor, not yet finished).
  [[nodiscard]] bool behavior_active(std::string_view name) const noexcept;
  /// The module instance `name`; nullptr when there is none.
  [[nodiscard]] CModule* module(std::string_view name) noexcept;
  /// The first module of type T; nullptr when there is none.
  template <class T>
  [[nodiscard]] T* module() noexcept {
    for (CModule* m : modules()) {
      if (auto* t = dynamic_cast<T*>(m)) return t;
    }
    return nullptr;
  }
  [[nodiscard]] std::vector<CModule*> modules() const;

  struct Impl;

 private:
  explicit Robot(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal
