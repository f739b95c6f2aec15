// CModule: the one base of the robot's modules outside the reactive loop — navigation modules
// (CNaviModules: maps, localizers, path and coverage planners, the section splitter), HRI and
// application modules. The robot runs them in its sequencing loop: each period they read the
// sensors and what the reactive layer reported, publish navigation data for the behaviors, and post
// events to the process supervisor; they also see which behaviors the supervisor activates, so a
// planner module can serve the behavior that needs it, and may answer the planner's questions.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/registry.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/resources/resource.hpp"

namespace tripodal {

class CHardware;
class CModule;

/// An event a module posts: the name a net's transition waits for ("localizer.lost"), and why.
struct ModuleEvent {
  Time stamp{};
  std::string name;
  std::string message;  ///< for logs and fault messages
  friend bool operator==(const ModuleEvent&, const ModuleEvent&) = default;
};

/// A behavior the process supervisor has just activated, with the parameters its net gave.
struct BehaviorActivation {
  std::string_view behavior;      ///< "BhAutoMove"
  const ParameterValues& params;  ///< as the net gives them (text literals not yet typed)
  Time now{};
  const ModuleManifest* manifest = nullptr;  ///< the behavior type's, to type the parameters

  /// The parameters typed and completed with the manifest's defaults (ConfigError when they do
  /// not resolve; the behavior itself then fails its activation).
  [[nodiscard]] ParameterSet resolved() const;
};

/// The answer to a question of the planner ("sections" of a room).
struct KnowledgeAnswer {
  bool ok = false;
  std::vector<std::string> items;
  std::string error;
};

/// The other modules of the robot, for a module that builds on one (the path planner on the
/// maps): found by type.
class ModuleDirectory {
 public:
  virtual ~ModuleDirectory() = default;
  /// Every module instance, in profile order.
  [[nodiscard]] virtual std::vector<CModule*> all() const = 0;
  /// The first module of type T (dynamic type), nullptr when the robot has none.
  template <class T>
  [[nodiscard]] T* find() const {
    for (CModule* m : all()) {
      if (auto* t = dynamic_cast<T*>(m)) return t;
    }
    return nullptr;
  }
};

/// What a module sees and writes during one period of the sequencing loop (or a hook). Built by
/// the robot; events, facts and the heartbeat are handed to the process supervisor under the
/// module's name after the call.
struct ModuleContext {
  Time now{};
  const ResourceTable* resources = nullptr;      ///< the reactive loop's sensors (read, never written)
  NavigationData* navigation = nullptr;          ///< what the reactive loop's behaviors will see next
  NavigationFeedback feedback;                   ///< what the path-following behavior reported last
  CHardware* hardware = nullptr;                 ///< the robot's hardware (nullptr: none)
  const ModuleDirectory* modules = nullptr;
  std::uint32_t* path_ids = nullptr;             ///< the robot's path id counter
  std::filesystem::path profile_dir;             ///< relative file parameters are relative to it

  std::vector<ModuleEvent> events;               ///< posted to the running processes' nets
  /// Fact changes for the nets' guards (`charging`, `battery_percent`), in order; the supervisor
  /// keeps the latest value of each, so a process started later reads it too.
  std::vector<std::pair<std::string, Value>> facts;
  bool heartbeat = false;                        ///< the module is alive (supervisor watchdog)
  /// Whether the planner runs a task (set by the robot before each update): a panel's start
  /// button starts one only when none runs.
  bool task_running = false;
  /// Task commands in plain words the module asks for while no task runs (the panel's start
  /// button, BoardMonitor's start_task): after the modules' update the robot gives them to the
  /// planner as Robot::command would; a refusal is the planner's ("command refused" in the life cycle).
  std::vector<std::string> commands;

  void post(std::string event, std::string message = {}) { events.push_back({now, std::move(event), std::move(message)}); }
  /// Asks the planner for a task (see `commands`).
  void command(std::string text) { commands.push_back(std::move(text)); }
  /// Sets a fact the running processes' nets declare. A type that sets facts lists them among its
  /// manifest's outputs: the profile check (check_robot) finds there who provides a fact a net reads.
  void set_fact(std::string name, Value value) { facts.emplace_back(std::move(name), std::move(value)); }
  /// A fresh id for a path published in navigation->path_id.
  [[nodiscard]] std::uint32_t new_path_id() noexcept { return path_ids != nullptr ? ++*path_ids : 1; }
};

/// Base of robot modules. Public methods are non-virtual and call protected hooks; a hook that
/// throws during update() or a behavior hook becomes the module's fault event
/// ("<module>.fault"), never a crash of the robot.
class CModule {
 public:
  virtual ~CModule() = default;
  CModule(const CModule&) = delete;
  CModule& operator=(const CModule&) = delete;

  /// The static manifest of the module type (name = registered type, layer, inputs, outputs,
  /// parameters).
  [[nodiscard]] const ModuleManifest& manifest() const noexcept { return do_manifest(); }
  [[nodiscard]] std::string_view type_name() const noexcept { return manifest().name; }

  /// Resolves params against the manifest (ConfigError listing every problem, located at
  /// `where`), then calls on_configure(). May be called again to reconfigure.
  void configure(const ParameterValues& params = {}, const SourceLocation& where = {});
  [[nodiscard]] bool configured() const noexcept { return configured_; }
  /// Where the module was configured (the profile entry): relative file parameters resolve
  /// against its folder, and start-up errors are located there.
  [[nodiscard]] const SourceLocation& where() const noexcept { return where_; }
  /// Once every module is configured: finds the modules and hardware it builds on. Throws
  /// ConfigError when one it needs is missing.
  void start(ModuleContext& context) { on_start(context); }
  /// One period of the sequencing loop. May throw (a fault).
  void update(ModuleContext& context) {
    if (configured_) on_update(context);
  }
  /// The process supervisor activated / deactivated a behavior.
  void behavior_activated(const BehaviorActivation& activation, ModuleContext& context) {
    if (configured_) on_behavior_activated(activation, context);
  }
  void behavior_deactivated(std::string_view behavior, ModuleContext& context) {
    if (configured_) on_behavior_deactivated(behavior, context);
  }
  /// The module's answer to a planner question it provides (its manifest lists `function` as an
  /// output, e.g. the section splitter's "sections"); nullopt when it has none.
  [[nodiscard]] std::optional<KnowledgeAnswer> answer(std::string_view function, std::string_view argument,
                                                      const NavigationData& navigation) const {
    return on_answer(function, argument, navigation);
  }

 protected:
  CModule() = default;
  [[nodiscard]] virtual const ModuleManifest& do_manifest() const noexcept = 0;
  virtual void on_configure(const ParameterSet& /*params*/) {}
  virtual void on_start(ModuleContext& /*context*/) {}
  virtual void on_update(ModuleContext& /*context*/) {}
  virtual void on_behavior_activated(const BehaviorActivation& /*activation*/, ModuleContext& /*context*/) {}
  virtual void on_behavior_deactivated(std::string_view /*behavior*/, ModuleContext& /*context*/) {}
  [[nodiscard]] virtual std::optional<KnowledgeAnswer> on_answer(std::string_view /*function*/, std::string_view /*argument*/,
                                                                 const NavigationData& /*navigation*/) const {
    return std::nullopt;
  }

 private:
  bool configured_ = false;
  SourceLocation where_;
};

/// Module types (CModule subclasses with a default constructor) by name.
using ModuleRegistry = Registry<CModule>;

}  // namespace tripodal
