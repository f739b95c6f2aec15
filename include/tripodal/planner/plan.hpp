// A plan of the deliberate layer: the sequence (and parallel groups) of process modules that
// carries out one task, and its high-level configuration net. The planner builds a Plan from a
// task template, turns it into a net by series and parallel composition of the processes' module
// nets (paper, Fig. 2: configs/petri/PrCleaning-module.xml), and rewrites the
// remaining Plan when a process fails (recovery), so the running plan is always a net that can be
// inspected, drawn and analysed.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/petri_net.hpp"
#include "tripodal/processes/process_step.hpp"

namespace tripodal {

/// A stage runs one step, or several steps in parallel (it ends when all have succeeded).
struct PlanStage {
  std::vector<ProcessStep> steps;
  [[nodiscard]] bool parallel() const noexcept { return steps.size() > 1; }
};

struct Plan {
  std::string task;  ///< the template that produced it, e.g. "clean"
  std::string command;  ///< the user's words
  std::vector<PlanStage> stages;
};

/// Human-readable one-line form: "PrAutoMove(goal=A) -> PrCleaning(section=A) -> ...".
[[nodiscard]] std::string to_string(const Plan& plan);

/// Ids of the nodes plan_to_net generates for stage `s` (0-based) and branch `b`, and the events
/// the planner posts when the process in an executing place ends.
struct PlanNetIds {
  static std::string standby(std::size_t s);                   ///< "S<s>": before stage s
  static std::string branch_standby(std::size_t s, std::size_t b);  ///< parallel stages: "S<s>_<b>"
  static std::string executing(std::size_t s, std::size_t b);  ///< "X<s>" or "X<s>_<b>"
  static std::string branch_done(std::size_t s, std::size_t b);  ///< parallel stages: "D<s>_<b>"
  /// Any other node of the module instantiated at an executing place: "X1.t0", "X1.P5".
  static std::string module_node(const std::string& executing_place, const std::string& module_node_id);
  static std::string success_event(const std::string& executing_place);  ///< "<place>.success"
  static std::string fault_event(const std::string& executing_place);    ///< "<place>.fault"
  static constexpr const char* kDone = "DONE";    ///< success outcome: the task is complete
  static constexpr const char* kFault = "FAULT";  ///< fault outcome: a process failed
};

/// The process module of `process` in high-level configuration when none is configured: the
/// shape of the paper's Fig. 2 / Table 1 (P0 standby, P1 executing the process, P2 completed, P3
/// fault; t0 starts it, t1 takes "P1.success", t2 takes "P1.fault"), fault message "process failed".
[[nodiscard]] PetriNet default_module_net(const std::string& process);

/// Checks that `module` is a process module of `process` the planner can compose (paper, Fig. 2):
/// a high-level net; exactly one place refers to a process, and it is `process` (the executing
/// place E); exactly one place is marked initially, with one token, and it is not E (standby);
/// exactly one success place and at least one fault place; no behavior bindings, no guards (the
/// plan's net has no parameters); events only "<E>.success" and "<E>.fault", which the planner
/// posts when the process ends. Appends one located error per problem.
void check_module_net(const PetriNet& module, std::string_view process, Diagnostics& diagnostics);

/// The module net of a process, or nullptr for the default one.
using ModuleNetOf = std::function<const PetriNet*(std::string_view process)>;

/// The high-level net of a plan: each step is its process's module net (`module_of`, checked
/// with check_module_net; default_module_net when it gives nullptr), composed in series (a
/// module's success place is the next module's standby) and in parallel (fork and join).
/// Stage s: standby place S<s> (S0 holds the token) is the module's standby; its executing place
/// is X<s> and refers to the process with the step's parameters; its success place is S<s+1>
/// (DONE after the last stage); every fault place is FAULT (message "process failed": the
/// failing process's own message travels with the fault, whatever the module's place says);
/// every other node is "X<s>.<id>" with the module's description, and the module's events
/// "<E>.success" / "<E>.fault" become "X<s>.success" / "X<s>.fault". A parallel stage forks from
/// S<s> (transition fork<s>) into one standby S<s>_<b> per branch; each branch's success place is
/// D<s>_<b>, and join<s> moves on when all are marked.
[[nodiscard]] PetriNet plan_to_net(const Plan& plan, const std::string& net_id = "plan", const ModuleNetOf& module_of = {});

}  // namespace tripodal
