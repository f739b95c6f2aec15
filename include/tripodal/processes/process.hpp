// CProcess: a process module of the sequencing layer — a low-level configuration net of behaviors,
// its typed parameters and its fault recovery information (paper, section 3.1). The process
// supervisor runs it; its result is always success, or a fault with a message for the planner.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/petri_net.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/processes/recovery_rule.hpp"

namespace tripodal {

/// How one run of a process ended, as the supervisor reports it to the planner.
struct ProcessResult {
  std::string run;      ///< the run id the process was started under (the planner's place, "X0")
  std::string process;  ///< "PrCleaning"
  bool success = false;
  std::string message;  ///< the fault message ("localization fault"); empty on success
  std::string place;    ///< the outcome place reached; empty when the fault did not come from the net
  Time started{};
  Time finished{};
};

/// What configuration says about one process: its net, configured parameter values (text, typed
/// by the net's declarations) and the recovery rules that belong to it.
struct ProcessDefinition {
  std::string name;
  std::string type = "net";  ///< the registered factory that builds it; "net" is a plain CProcess
  PetriNet net;
  /// Its process module in high-level configuration (paper, Fig. 2: configs/petri/
  /// PrCleaning-module.xml), which the planner composes into the plan's net; none: the default
  /// module of that shape (planner/plan.hpp, default_module_net). Its shape is the planner's
  /// business (check_module_net, run when the robot is assembled and when a plan is composed).
  std::optional<PetriNet> module;
  std::vector<BindingParam> parameters;
  std::vector<RecoveryRule> recovery;
  SourceLocation where;
};

/// The parameters of one run, or why they could not be bound.
struct BoundParameters {
  bool ok = false;
  ParameterValues values;
  std::string error;  ///< when !ok: "PrCleaning: parameter 'section' is required"
};

/// A process module. Plain processes are entirely configuration; an application derives from it
/// (and registers a factory type) to compute parameters at start, e.g. a goal pose from a room.
class CProcess {
 public:
  /// Checks the definition and throws ConfigError listing every problem, located: a configured
  /// parameter the net does not declare or whose text does not parse as the declared type, a
  /// behavior binding parameter "$name" that names no declared parameter, a net without any
  /// outcome place (its result could never be reported), a high-level net.
  explicit CProcess(ProcessDefinition definition);
  virtual ~CProcess() = default;
  CProcess(const CProcess&) = delete;
  CProcess& operator=(const CProcess&) = delete;

  /// The manifest of the "net" type: a process given entirely by configuration.
  static const ModuleManifest& static_manifest();

  [[nodiscard]] const std::string& name() const noexcept { return definition_.name; }
  /// This process as a module of the sequencing layer: its name, kind process, the parameters its
  /// net declares (types, defaults, descriptions) and, in the description, the behaviors it binds.
  /// Built at construction, so a derived process type has it the same way.
  [[nodiscard]] const ModuleManifest& manifest() const noexcept { return manifest_; }
  [[nodiscard]] const std::string& type() const noexcept { return definition_.type; }
  [[nodiscard]] const PetriNet& net() const noexcept { return definition_.net; }
  /// The configured process module net; nullptr when the default is used.
  [[nodiscard]] const PetriNet* module() const noexcept { return definition_.module ? &*definition_.module : nullptr; }
  [[nodiscard]] const std::vector<RecoveryRule>& recovery() const noexcept { return definition_.recovery; }
  [[nodiscard]] const std::vector<BindingParam>& configured_parameters() const noexcept { return definition_.parameters; }
  [[nodiscard]] const SourceLocation& where() const noexcept { return definition_.where; }
  /// The behaviors its places bind, sorted, without duplicates.
  [[nodiscard]] std::vector<std::string> behaviors() const;

  /// The typed parameters of one run: the net's defaults, overridden by the configured values,
  /// overridden by `step` (the plan's values), then adjusted by the derived class. Never throws:
  /// a problem is returned as an error (an undeclared name, a value that does not parse, a
  /// required parameter without value).
  [[nodiscard]] BoundParameters bind(const std::vector<BindingParam>& step) const;

 protected:
  /// Hook for derived processes, called by bind() with the merged values; return an error text to
  /// refuse the run. The default accepts.
  virtual std::string on_bind(ParameterValues& values) const;

 private:
  ProcessDefinition definition_;
  ModuleManifest manifest_;
};

/// The parameters a behavior binding passes: literal values as strings, "$name" replaced by the
/// run's typed parameter. Returns false (with `error`) for a "$name" the run does not have.
bool resolve_binding_params(const std::vector<BindingParam>& params, const ParameterValues& run,
                            ParameterValues& out, std::string& error);

}  // namespace tripodal
