// Robot: a whole Tripodal robot assembled from a robot profile — its modules created by type from
// the registries, its behaviors, processes, task templates and recovery rules, and the core
// components (planner, process supervisor, configurations, behavior coordinator). It refuses to
// start when an input lacks exactly one provider or a layering rule is broken.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/planner/planner.hpp"
#include "tripodal/processes/behavior_set.hpp"
#include "tripodal/processes/process_registry.hpp"
#include "tripodal/processes/process_supervisor.hpp"
#include "tripodal/robot/layering.hpp"
#include "tripodal/robot/module.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal {

struct RobotOptions {
  SupervisorOptions supervisor;
  PlannerOptions planner;
  /// Sampling period the behaviors are stepped with by Robot::step().
  Duration period{std::chrono::milliseconds(100)};
  /// Registers application process types (CProcess subclasses) before the profile's processes
  /// are built.
  std::function<void(ProcessRegistry&)> register_process_types;
  /// Loads a process net; default: load_net_or_throw checking behavior names against the profile.
  std::function<PetriNet(const std::filesystem::path&)> load_net;
  /// What behaviors see in their context (BehaviorContext): the resources and navigation data
  /// the robot program keeps up to date (not owned; nullptr: none) and the base's capabilities.
  const ResourceTable* resources = nullptr;
  const NavigationData* navigation = nullptr;
  BaseCapabilities base;
};

class Robot final {
 public:
  /// Builds the robot. Throws ConfigError listing every problem, located: unknown module types,
  /// modules without a factory, missing or duplicate providers, layering violations, nets that do
  /// not load, processes binding behaviors the robot lacks, task templates or recovery rules
  /// naming unknown processes.
  static std::unique_ptr<Robot> assemble(const RobotProfile& profile, const RobotCatalog& catalog, const Clock& clock,
                                         RobotOptions options = {});
  ~Robot();
  Robot(const Robot&) = delete;
  Robot& operator=(const Robot&) = delete;

  /// A task command in plain words (CPlanner::command).
  CommandAnswer command(std::string_view text);
  /// One period at the clock's time: modules update (an exception becomes a module fault), the
  /// active behaviors step and the coordinator fuses their commands, then the planner steps the
  /// plan and the supervisor.
  void step();

  [[nodiscard]] const RobotDescription& description() const noexcept;
  [[nodiscard]] CPlanner& planner() noexcept;
  [[nodiscard]] CProcessSupervisor& supervisor() noexcept;
  [[nodiscard]] BehaviorSet& behaviors() noexcept;
  [[nodiscard]] const ProcessRegistry& processes() const noexcept;
  [[nodiscard]] const CBehaviorCoordinator& coordinator() const noexcept;
  /// The module instance `name`; nullptr when there is none (or it is a behavior or controller).
  [[nodiscard]] RobotModule* module(std::string_view name) noexcept;

  struct Impl;

 private:
  explicit Robot(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal
