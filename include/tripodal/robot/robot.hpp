// Robot: one Tripodal robot assembled from its profile and run on one path. It owns everything the
// profile names — the hardware (hardware slot), the resources its sensors publish, the controllers
// and the reactive control loops (ControlLoop: resources -> behaviors -> coordinator -> controller at
// each loop's period), the modules of the sequencing loop (navigation, HRI, application modules),
// the process supervisor and the planner — and drives them by its clock: on simulated time with
// run_until() (the caller's thread), or on wall-clock time with start() (a thread per reactive loop,
// one for the sequencing loop, each watching its deadlines). The same code runs either way: the
// modules read the resources through one snapshot in both. It refuses to start when
// an input lacks exactly one provider or a layering rule is broken.
#pragma once

#include <cstdint>
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
[[nodiscard]] std::optional<ControllerConfig> base_controller_config(const RobotProfile& profile,
                                                                     const ControllerRegistry& controllers);

/// Every start-up check of Robot::assemble that builds no instance, as `tripodal describe` runs
/// them: the tasks and recovery rules, one provider per input and the layering rules
/// (describe_robot), every type registered — a type only declared in the profile (layer, inputs,
/// outputs) draws the diagram of a design: a warning here, an error at assembly —, the process
/// nets loaded and each behavior
/// they bind listed under the profile's behaviors (and not a safety one), behaviors named by their
/// type, the controllers' reactive configurations read through `plugins.controllers`. Problems go
/// to `d`, located in the profile or the file they are in; returns the diagram.
[[nodiscard]] RobotDescription check_robot(const RobotProfile& profile, const RobotPlugins& plugins, Diagnostics& d);

/// What the wall-clock runtime (Robot::start) is given besides the profile's loop settings.
struct RealtimeOptions {
  /// Called on the sequencing thread after each of its periods, under the sequencing lock: where a
  /// program observes the sequencing layer's state (planner, active behaviors, navigation data)
  /// without racing it. Must not call start() or stop().
  std::function<void(Time now)> after_sequencing;
};

/// How one of the robot's periodic threads kept its deadlines (Robot::timing()).
struct LoopTimingReport {
  std::string name;  ///< a reactive loop's name, or "sequencing"
  Duration period{0};
  Duration budget{0};
  std::uint64_t cycles = 0;
  std::uint64_t overruns = 0;         ///< cycles ending later than deadline + budget
  std::uint64_t skipped_ticks = 0;    ///< ticks of the grid missed after an overrun
  std::uint64_t deadline_faults = 0;  ///< runs of deadline_overruns overruns: "<loop>.deadline" posted
  Duration period_error_p50{0}, period_error_p99{0}, period_error_max{0};  ///< wake time - deadline
  Duration execution_p99{0}, execution_max{0};
  bool realtime = false;  ///< SCHED_FIFO granted
  std::string warning;    ///< what the thread asked and was refused (empty: all granted)
};

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
  /// Wall-clock time: starts the hardware and one thread per reactive loop and one for the
  /// sequencing loop (its modules, the supervisor and the planner), each at absolute deadlines of
  /// the robot's clock (a ScaledClock runs a simulated robot faster than real time) with the
  /// profile's loop settings (SCHED_FIFO, CPU, mlockall where permitted; timing() names what was
  /// refused). The behavior loop's thread also advances the hardware (a simulator's physics)
  /// before each cycle and hands its resources to the sequencing layer through a lock-free
  /// snapshot after it. A run of overruns posts "<loop>.deadline" (or "sequencing.deadline") as a
  /// fault. Throws std::logic_error when already started.
  void start(RealtimeOptions options = {});
  /// Stops the threads (the sequencing thread first, then the loops) and the hardware; idempotent.
  void stop() noexcept;
  /// Each periodic thread's deadline record of the last start(): the reactive loops in profile
  /// order, then "sequencing". Complete after stop(); empty before the first start().
  [[nodiscard]] std::vector<LoopTimingReport> timing() const;
  /// What the threads asked of the system and were refused, one line each (SCHED_FIFO, CPU,
  /// mlockall); any thread, once start() has returned (until the next start()).
  [[nodiscard]] std::vector<std::string> realtime_warnings() const;
  [[nodiscard]] bool started() const noexcept;

  /// One period of the sequencing loop at the clock's time (what run_until() and the sequencing
  /// thread call): the reactive loops' reports and deadline faults in, the resource snapshot
  /// refreshed, the modules' update, the planner or the supervisor, the navigation data out. The
  /// loops' changes of one period apply together.
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
  /// The reactive loops' resources (written on the behavior loop's thread).
  [[nodiscard]] const ResourceTable& resources() const noexcept;
  /// The sequencing layer's copy of them (what modules read): refreshed each sequencing period.
  [[nodiscard]] const ResourceTable& sequencing_resources() const noexcept;
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
