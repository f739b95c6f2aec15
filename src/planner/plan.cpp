#include "tripodal/planner/plan.hpp"

namespace tripodal {

std::string to_string(const Plan& plan) {
  std::string out;
  auto step_text = [](const ProcessStep& step) {
    std::string s = step.process + '(';
    for (std::size_t i = 0; i < step.params.size(); ++i) {
      if (i > 0) s += ", ";
      s += step.params[i].name + '=' + step.params[i].value;
    }
    return s + ')';
  };
  for (std::size_t s = 0; s < plan.stages.size(); ++s) {
    if (s > 0) out += " -> ";
    const auto& stage = plan.stages[s];
    if (stage.parallel()) out += '[';
    for (std::size_t b = 0; b < stage.steps.size(); ++b) {
      if (b > 0) out += " || ";
      out += step_text(stage.steps[b]);
    }
    if (stage.parallel()) out += ']';
  }
  return out.empty() ? std::string("(empty plan)") : out;
}

std::string PlanNetIds::standby(std::size_t s) { return "S" + std::to_string(s); }
std::string PlanNetIds::executing(std::size_t s, std::size_t b) {
  return "X" + std::to_string(s) + (b == 0 ? std::string() : "_" + std::to_string(b));
}
std::string PlanNetIds::branch_done(std::size_t s, std::size_t b) {
  return "D" + std::to_string(s) + "_" + std::to_string(b);
}
std::string PlanNetIds::success_event(const std::string& executing_place) { return executing_place + ".success"; }
std::string PlanNetIds::fault_event(const std::string& executing_place) { return executing_place + ".fault"; }

PetriNet plan_to_net(const Plan& plan, const std::string& net_id) {
  PetriNet net;
  net.id = net_id;
  net.name = plan.task.empty() ? net_id : plan.task;
  net.description = plan.command.empty() ? to_string(plan) : "Task \"" + plan.command + "\": " + to_string(plan);
  net.level = NetLevel::high;

  Place done{.id = PlanNetIds::kDone, .description = "Task completed"};
  done.outcome = Outcome::success;
  Place fault{.id = PlanNetIds::kFault, .description = "A process failed; the planner decides the recovery"};
  fault.outcome = Outcome::fault;
  fault.fault_message = "process failed";

  const std::size_t n = plan.stages.size();
  for (std::size_t s = 0; s < n; ++s) {
    net.add_place({.id = PlanNetIds::standby(s),
                   .description = "Standby before " + plan.stages[s].steps.front().process,
                   .initial_tokens = s == 0 ? 1u : 0u});
  }
  net.add_place(done);
  net.add_place(fault);
  auto next_place = [&](std::size_t s) { return s + 1 < n ? PlanNetIds::standby(s + 1) : std::string(PlanNetIds::kDone); };
  if (n == 0) {
    net.place(*net.find_place(PlanNetIds::kDone)).initial_tokens = 1;
    return net;
  }

  for (std::size_t s = 0; s < n; ++s) {
    const PlanStage& stage = plan.stages[s];
    const std::string start = "start" + std::to_string(s);
    net.add_transition({.id = start, .description = stage.parallel() ? "Planner starts the parallel group"
                                                                       : "Planner starts the process " +
                                                                             stage.steps.front().process});
    net.add_arc(PlanNetIds::standby(s), start);
    std::string join;
    if (stage.parallel()) {
      join = "join" + std::to_string(s);
      net.add_transition({.id = join, .description = "Every process of the group completed"});
      net.add_arc(join, next_place(s));
    }
    for (std::size_t b = 0; b < stage.steps.size(); ++b) {
      const ProcessStep& step = stage.steps[b];
      const std::string x = PlanNetIds::executing(s, b);
      Place executing{.id = x, .description = "Executing the process " + step.process};
      executing.process = ProcessRef{step.process, step.params};
      net.add_place(std::move(executing));
      net.add_arc(start, x);
      const std::string ok = "ok" + x.substr(1);
      const std::string ko = "ko" + x.substr(1);
      net.add_transition({.id = ok,
                          .description = "Planner completes the process " + step.process,
                          .event = PlanNetIds::success_event(x)});
      net.add_transition({.id = ko,
                          .description = "Process supervisor posts the fault of " + step.process,
                          .event = PlanNetIds::fault_event(x)});
      net.add_arc(x, ok);
      net.add_arc(x, ko);
      net.add_arc(ko, PlanNetIds::kFault);
      if (stage.parallel()) {
        const std::string d = PlanNetIds::branch_done(s, b);
        net.add_place({.id = d, .description = step.process + " completed, waiting for the group"});
        net.add_arc(ok, d);
        net.add_arc(d, join);
      } else {
        net.add_arc(ok, next_place(s));
      }
    }
  }
  return net;
}

}  // namespace tripodal
