// A plan of the deliberate layer: the sequence (and parallel groups) of process modules that
// carries out one task, and its high-level configuration net. The planner builds a Plan from a
// task template, turns it into a net by series and parallel composition, and rewrites the
// remaining Plan when a process fails (recovery), so the running plan is always a net that can be
// inspected, drawn and analysed.
#pragma once

#include <string>
#include <vector>

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
  static std::string executing(std::size_t s, std::size_t b);  ///< "X<s>" or "X<s>_<b>"
  static std::string branch_done(std::size_t s, std::size_t b);  ///< parallel stages: "D<s>_<b>"
  static std::string success_event(const std::string& executing_place);  ///< "<place>.success"
  static std::string fault_event(const std::string& executing_place);    ///< "<place>.fault"
  static constexpr const char* kDone = "DONE";    ///< success outcome: the task is complete
  static constexpr const char* kFault = "FAULT";  ///< fault outcome: a process failed
};

/// The high-level net of a plan, by series composition of the paper's process module (Fig. 2:
/// standby -> executing -> completed, or fault) and parallel composition (fork and join).
/// Stage s: standby place S<s> (S0 holds the token); a start transition (immediate) moves it to
/// the executing place(s), each referring to its process with its parameters; the event
/// "<X>.success" completes a step, "<X>.fault" moves the token to FAULT (message "process failed";
/// the supervisor's actual message travels with the fault). After the last stage, DONE.
[[nodiscard]] PetriNet plan_to_net(const Plan& plan, const std::string& net_id = "plan");

}  // namespace tripodal
