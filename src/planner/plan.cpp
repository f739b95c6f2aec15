#include "tripodal/planner/plan.hpp"

#include <map>
#include <optional>

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
std::string PlanNetIds::branch_standby(std::size_t s, std::size_t b) { return standby(s) + "_" + std::to_string(b); }
std::string PlanNetIds::executing(std::size_t s, std::size_t b) {
  return "X" + std::to_string(s) + (b == 0 ? std::string() : "_" + std::to_string(b));
}
std::string PlanNetIds::branch_done(std::size_t s, std::size_t b) {
  return "D" + std::to_string(s) + "_" + std::to_string(b);
}
std::string PlanNetIds::module_node(const std::string& executing_place, const std::string& module_node_id) {
  return executing_place + "." + module_node_id;
}
std::string PlanNetIds::success_event(const std::string& executing_place) { return executing_place + ".success"; }
std::string PlanNetIds::fault_event(const std::string& executing_place) { return executing_place + ".fault"; }

PetriNet default_module_net(const std::string& process) {
  PetriNet m;
  m.id = process + "Module";
  m.name = process;
  m.description = "Process module of " + process + " (high-level configuration, the shape of Fig. 2)";
  m.level = NetLevel::high;
  m.add_place({.id = "P0", .description = "Standby", .initial_tokens = 1});
  Place executing{.id = "P1", .description = "Executing the process " + process};
  executing.process = ProcessRef{process, {}};
  m.add_place(std::move(executing));
  Place done{.id = "P2", .description = "Completing the process " + process};
  done.outcome = Outcome::success;
  m.add_place(std::move(done));
  Place fault{.id = "P3", .description = "Fault: the process " + process + " failed"};
  fault.outcome = Outcome::fault;
  fault.fault_message = "process failed";
  m.add_place(std::move(fault));
  m.add_transition({.id = "t0", .description = "Planner starts the process " + process});
  m.add_transition({.id = "t1", .description = "Planner completes the process " + process, .event = "P1.success"});
  m.add_transition({.id = "t2", .description = "Process supervisor (PS) posts the fault message of " + process, .event = "P1.fault"});
  m.add_arc("P0", "t0");
  m.add_arc("t0", "P1");
  m.add_arc("P1", "t1");
  m.add_arc("t1", "P2");
  m.add_arc("P1", "t2");
  m.add_arc("t2", "P3");
  return m;
}

namespace {

struct ModuleRoles {
  std::optional<PlaceIndex> standby, executing, success;
};

ModuleRoles roles_of(const PetriNet& m) {
  ModuleRoles r;
  for (PlaceIndex p = 0; p < m.places().size(); ++p) {
    const Place& place = m.place(p);
    if (place.process) r.executing = p;
    else if (place.initial_tokens > 0) r.standby = p;
    if (place.outcome == Outcome::success) r.success = p;
  }
  return r;
}

const SourceLocation& at(const PetriNet& net, const SourceLocation& where) { return where.file.empty() ? net.where : where; }

}  // namespace

void check_module_net(const PetriNet& module, std::string_view process, Diagnostics& diagnostics) {
  const std::string what = "process module of " + std::string(process) + ": ";
  if (module.level != NetLevel::high) {
    diagnostics.error(module.where, what + "a process module is a high-level net (level=\"high\"), as in Fig. 2");
  }
  std::size_t executing = 0, marked = 0, success = 0, fault = 0;
  std::string executing_id;
  for (const Place& p : module.places()) {
    if (p.process) {
      ++executing;
      executing_id = p.id;
      if (p.process->process != process) {
        diagnostics.error(at(module, p.where), what + "place '" + p.id + "' runs process '" + p.process->process +
                                                   "'; the module's executing place must run '" + std::string(process) + "'");
      }
      if (p.initial_tokens > 0 || p.outcome != Outcome::none) {
        diagnostics.error(at(module, p.where), what + "the executing place '" + p.id + "' must be neither marked initially nor an outcome");
      }
    } else if (p.initial_tokens > 0) {
      ++marked;
      if (p.initial_tokens != 1 || p.outcome != Outcome::none) {
        diagnostics.error(at(module, p.where), what + "the standby place '" + p.id + "' must hold one token and be no outcome");
      }
    }
    if (p.behavior) {
      diagnostics.error(at(module, p.where), what + "place '" + p.id + "' binds behavior '" + p.behavior->behavior +
                                                 "': behaviors belong in the process's low-level net");
    }
    success += p.outcome == Outcome::success ? 1 : 0;
    fault += p.outcome == Outcome::fault ? 1 : 0;
  }
  if (executing != 1) {
    diagnostics.error(module.where, what + "expected exactly one place that runs the process (<process name=\"" +
                                        std::string(process) + "\">), found " + std::to_string(executing));
  }
  if (marked != 1) {
    diagnostics.error(module.where, what + "expected exactly one standby place (the one marked initially), found " + std::to_string(marked));
  }
  if (success != 1) {
    diagnostics.error(module.where, what + "expected exactly one success place (outcome=\"success\"), found " + std::to_string(success));
  }
  if (fault == 0) diagnostics.error(module.where, what + "expected at least one fault place (outcome=\"fault\"), found none");
  for (const Transition& t : module.transitions()) {
    if (t.guard) {
      diagnostics.error(at(module, t.where), what + "transition '" + t.id + "' has a guard; the plan's net has no parameters to test");
    }
    if (!t.event.empty() && executing == 1 && t.event != PlanNetIds::success_event(executing_id) &&
        t.event != PlanNetIds::fault_event(executing_id)) {
      diagnostics.error(at(module, t.where), what + "transition '" + t.id + "' waits for event '" + t.event + "'; the planner posts only '" +
                                                 PlanNetIds::success_event(executing_id) + "' and '" +
                                                 PlanNetIds::fault_event(executing_id) + "'");
    }
  }
}

namespace {

// Adds module `m` to `net` for `step` at executing place `x`; its standby and success places
// become `standby_id` and `success_id` (which the caller has added), its fault places FAULT.
void instantiate(PetriNet& net, const PetriNet& m, const ProcessStep& step, const std::string& x, const std::string& standby_id,
                 const std::string& success_id) {
  const ModuleRoles r = roles_of(m);
  const std::string e = m.place(*r.executing).id;
  const auto id_of = [&](PlaceIndex p) -> std::string {
    if (p == r.standby) return standby_id;
    if (p == r.executing) return x;
    if (p == r.success) return success_id;
    if (m.place(p).outcome == Outcome::fault) return PlanNetIds::kFault;
    return PlanNetIds::module_node(x, m.place(p).id);
  };
  for (PlaceIndex p = 0; p < m.places().size(); ++p) {
    if (p == r.standby || p == r.success || m.place(p).outcome == Outcome::fault) continue;
    Place copy = m.place(p);
    copy.id = id_of(p);
    if (copy.name == m.place(p).id) copy.name.clear();  // a label that only repeated the module's id
    if (p == r.executing) copy.process = ProcessRef{step.process, step.params};
    net.add_place(std::move(copy));
  }
  for (const Transition& t : m.transitions()) {
    Transition copy{.id = PlanNetIds::module_node(x, t.id), .name = t.name == t.id ? std::string() : t.name,
                    .description = t.description, .event = t.event,
                    .guard = t.guard, .delay = t.delay, .priority = t.priority, .where = t.where};
    if (t.event == PlanNetIds::success_event(e)) copy.event = PlanNetIds::success_event(x);
    if (t.event == PlanNetIds::fault_event(e)) copy.event = PlanNetIds::fault_event(x);
    net.add_transition(std::move(copy));
    const std::string tid = PlanNetIds::module_node(x, t.id);
    for (const ArcRef& a : t.inputs) net.add_arc(id_of(a.place), tid, a.weight, ArcKind::normal, a.where);
    for (const ArcRef& a : t.reads) net.add_arc(id_of(a.place), tid, a.weight, ArcKind::read, a.where);
    for (const ArcRef& a : t.inhibitors) net.add_arc(id_of(a.place), tid, a.weight, ArcKind::inhibitor, a.where);
    for (const ArcRef& a : t.outputs) net.add_arc(tid, id_of(a.place), a.weight, ArcKind::normal, a.where);
  }
}

}  // namespace

PetriNet plan_to_net(const Plan& plan, const std::string& net_id, const ModuleNetOf& module_of) {
  PetriNet net;
  net.id = net_id;
  net.name = plan.task.empty() ? net_id : plan.task;
  net.description = plan.command.empty() ? to_string(plan) : "Task \"" + plan.command + "\": " + to_string(plan);
  net.level = NetLevel::high;

  const std::size_t n = plan.stages.size();
  for (std::size_t s = 0; s < n; ++s) {
    net.add_place({.id = PlanNetIds::standby(s),
                   .description = "Standby before " + plan.stages[s].steps.front().process,
                   .initial_tokens = s == 0 ? 1u : 0u});
  }
  Place done{.id = PlanNetIds::kDone, .description = "Task completed", .initial_tokens = n == 0 ? 1u : 0u};
  done.outcome = Outcome::success;
  net.add_place(std::move(done));
  Place fault{.id = PlanNetIds::kFault, .description = "A process failed; the planner decides the recovery"};
  fault.outcome = Outcome::fault;
  fault.fault_message = "process failed";
  net.add_place(std::move(fault));

  // One module net per process type: the configured one (checked once), else the default.
  std::map<std::string, PetriNet, std::less<>> defaults;
  const auto module = [&](const std::string& process) -> const PetriNet& {
    if (const PetriNet* m = module_of ? module_of(process) : nullptr) {
      Diagnostics d;
      check_module_net(*m, process, d);
      if (d.has_errors()) throw ConfigError(d);
      return *m;
    }
    auto it = defaults.find(process);
    if (it == defaults.end()) it = defaults.emplace(process, default_module_net(process)).first;
    return it->second;
  };
  const auto next_place = [&](std::size_t s) { return s + 1 < n ? PlanNetIds::standby(s + 1) : std::string(PlanNetIds::kDone); };
  for (std::size_t s = 0; s < n; ++s) {
    const PlanStage& stage = plan.stages[s];
    if (!stage.parallel()) {
      const ProcessStep& step = stage.steps.front();
      instantiate(net, module(step.process), step, PlanNetIds::executing(s, 0), PlanNetIds::standby(s), next_place(s));
      continue;
    }
    const std::string fork = "fork" + std::to_string(s), join = "join" + std::to_string(s);
    net.add_transition({.id = fork, .description = "Planner starts the parallel group"});
    net.add_transition({.id = join, .description = "Every process of the group completed"});
    net.add_arc(PlanNetIds::standby(s), fork);
    net.add_arc(join, next_place(s));
    for (std::size_t b = 0; b < stage.steps.size(); ++b) {
      const ProcessStep& step = stage.steps[b];
      const std::string standby = PlanNetIds::branch_standby(s, b), branch_done = PlanNetIds::branch_done(s, b);
      net.add_place({.id = standby, .description = "Standby before " + step.process + " (parallel group)"});
      net.add_place({.id = branch_done, .description = step.process + " completed, waiting for the group"});
      net.add_arc(fork, standby);
      net.add_arc(branch_done, join);
      instantiate(net, module(step.process), step, PlanNetIds::executing(s, b), standby, branch_done);
    }
  }
  return net;
}

}  // namespace tripodal
