// Robot modules that are neither behaviors nor controllers — navigation modules (maps, localizers,
// section splitter), HRI, resources and application modules — as the robot assembles them: a
// manifest (layer, inputs, outputs) and a factory registered by type name, a per-period update,
// and a port through which the module posts events and faults to the process supervisor.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/processes/process_supervisor.hpp"

namespace tripodal {

/// A module's line to the process supervisor, stamped with the module's name.
class ModulePort {
 public:
  ModulePort() = default;
  ModulePort(CProcessSupervisor& supervisor, std::string module) : supervisor_(&supervisor), module_(std::move(module)) {}

  /// Posts an event to the running processes' nets ("localizer.lost").
  void post_event(std::string event) const;
  /// Tells the supervisor's watchdog the module is alive.
  void heartbeat() const;
  /// The module failed at run time; becomes the event "<module>.fault".
  void report_fault(std::string reason) const;
  void set_fact(std::string name, Value value) const;
  [[nodiscard]] const std::string& module() const noexcept { return module_; }
  [[nodiscard]] bool connected() const noexcept { return supervisor_ != nullptr; }

 private:
  CProcessSupervisor* supervisor_ = nullptr;
  std::string module_;
};

/// Configuration of one module instance, as the robot profile gives it.
struct ModuleConfig {
  std::string name;
  std::string type;
  std::map<std::string, std::string, std::less<>> parameters;  ///< text; the module parses them
  SourceLocation where;
};

/// Base of robot modules. Public methods call protected hooks; update() runs every robot period
/// and may throw: the robot turns an exception into a module fault, never a crash.
class RobotModule {
 public:
  virtual ~RobotModule() = default;
  RobotModule(const RobotModule&) = delete;
  RobotModule& operator=(const RobotModule&) = delete;

  void attach(ModulePort port) {
    port_ = std::move(port);
    on_attach();
  }
  void update(Time now) { on_update(now); }
  /// The module's answer to a planner question it provides (its manifest lists `function` as an
  /// output, e.g. the section splitter's "sections"); nullopt when it has none.
  [[nodiscard]] std::optional<TaskKnowledge::ListResult> answer(std::string_view function, std::string_view argument) const {
    return on_answer(function, argument);
  }

 protected:
  RobotModule() = default;
  [[nodiscard]] const ModulePort& port() const noexcept { return port_; }
  virtual void on_attach() {}
  virtual void on_update(Time /*now*/) {}
  [[nodiscard]] virtual std::optional<TaskKnowledge::ListResult> on_answer(std::string_view /*function*/,
                                                                           std::string_view /*argument*/) const {
    return std::nullopt;
  }

 private:
  ModulePort port_;
};

/// Module types by name: a manifest and a factory. Applications register theirs; the robot
/// profile names them.
class ModuleRegistry {
 public:
  using Factory = std::function<std::unique_ptr<RobotModule>(const ModuleConfig&)>;
  /// Throws std::invalid_argument for an empty or duplicate name. A type registered without a
  /// factory can be described and checked but not started.
  void add(ModuleManifest manifest, Factory factory);
  [[nodiscard]] bool contains(std::string_view type) const noexcept;
  [[nodiscard]] const ModuleManifest* manifest(std::string_view type) const noexcept;
  [[nodiscard]] bool can_create(std::string_view type) const noexcept;
  /// Throws ConfigError at config.where for an unknown type or one without a factory, and lets
  /// the factory's own ConfigError through.
  [[nodiscard]] std::unique_ptr<RobotModule> create(const ModuleConfig& config) const;
  [[nodiscard]] std::vector<std::string> names() const;

 private:
  struct Entry {
    ModuleManifest manifest;
    Factory factory;
  };
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace tripodal
