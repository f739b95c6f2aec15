#include "tripodal/processes/process_supervisor.hpp"

#include <algorithm>
#include <exception>
#include <map>

#include <spdlog/spdlog.h>

#include "tripodal/core/net_loader.hpp"

namespace tripodal {

namespace {

std::string done_event(std::string_view behavior) { return done_event_name(behavior); }
std::string failed_event(std::string_view behavior) { return failed_event_name(behavior); }

bool same_binding(const std::vector<BindingParam>& a, const std::vector<BindingParam>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const BindingParam& x, const BindingParam& y) { return x.name == y.name && x.value == y.value; });
}

}  // namespace

// One running process: its engine and the behaviors its marked places hold active.
struct CProcessSupervisor::Run {
  struct Active {
    PlaceIndex place = 0;
    std::string behavior;
    Time since{};
    bool done_posted = false;
    bool failure_posted = false;
  };

  // Forwards the engine's firings to the supervisor's observers with the run's id.
  struct Forwarder final : EngineObserver {
    Run* run = nullptr;
    const std::vector<SupervisorObserver*>* observers = nullptr;

   protected:
    void on_firing(const Firing& f) override {
      for (SupervisorObserver* o : *observers) o->on_firing(run->id, run->engine->net(), f);
    }
  };

  std::string id;
  const CProcess* process = nullptr;
  ParameterValues params;
  std::unique_ptr<Engine> engine;
  Time started{};
  std::vector<Active> active;
  std::map<std::string, std::string, std::less<>> failure_messages;  // failure event -> message
  Forwarder forwarder;
  bool finished = false;
  std::unique_ptr<CProcess> reloaded;      // the edited process after a reload (`process` points at it)
  std::vector<std::string> pending_events;  // behavior failures of a reload's activations, for the next step
};

struct CProcessSupervisor::Inbox {
  struct Watch {
    Duration timeout{0};
    std::string event;
    Time last{};
    bool fired = false;
  };
  std::mutex mutex;
  std::vector<std::string> events;
  std::vector<std::pair<std::string, Value>> facts;
  struct Fault {
    std::string source;
    std::string reason;
    std::string event;  // "<source>.fault" unless the reporter named another
  };
  std::vector<Fault> faults;
  // The latest value of every fact set (supervisor thread only): a process started after a fact
  // was set reads it, not its net's default (the robot docked before PrDockCharge started).
  std::map<std::string, Value, std::less<>> latest_facts;
  std::map<std::string, Watch, std::less<>> watches;
};

CProcessSupervisor::CProcessSupervisor(BehaviorHost& behaviors, const Clock& clock, SupervisorOptions options)
    : behaviors_(behaviors), clock_(clock), options_(options), inbox_(std::make_unique<Inbox>()) {
  if (options_.max_rounds_per_step == 0) options_.max_rounds_per_step = 1;
}

CProcessSupervisor::~CProcessSupervisor() {
  // Leave no behavior running behind a destroyed supervisor.
  const Time now = clock_.now();
  for (auto& r : runs_) {
    for (auto& a : r->active) {
      try {
        behaviors_.deactivate(a.behavior, now);
      } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor must not throw
      }
    }
  }
}

bool CProcessSupervisor::start(std::string run, const CProcess& process, ParameterValues params, std::string* error) {
  if (running(run)) {
    if (error) *error = "a process is already running as '" + run + "'";
    return false;
  }
  auto r = std::make_unique<Run>();
  r->id = std::move(run);
  r->process = &process;
  r->params = std::move(params);
  const Time now = clock_.now();
  r->started = now;
  EngineOptions eo = options_.engine;
  eo.start_time = now;
  try {
    r->engine = std::make_unique<Engine>(process.net(), r->params, eo);
  } catch (const std::exception& e) {
    if (error) *error = process.name() + ": " + e.what();
    return false;
  }
  for (const auto& [name, value] : inbox_->latest_facts) {
    if (!r->engine->fact_id(name)) continue;
    try {
      r->engine->set_fact(name, value);
    } catch (const std::exception&) {  // NOLINT(bugprone-empty-catch): reported when it was set
    }
  }
  r->forwarder.run = r.get();
  r->forwarder.observers = &observers_;
  r->engine->add_observer(r->forwarder);
  for (SupervisorObserver* o : observers_) o->on_run_started(r->id, process, r->params, now);
  runs_.push_back(std::move(r));
  return true;
}

bool CProcessSupervisor::stop(std::string_view run, std::string_view reason) {
  for (auto it = runs_.begin(); it != runs_.end(); ++it) {
    if ((*it)->id == run) {
      finish(**it, false, "stopped: " + std::string(reason), {}, clock_.now());
      runs_.erase(it);
      return true;
    }
  }
  return false;
}

void CProcessSupervisor::finish(Run& run, bool success, std::string message, std::string place, Time now) {
  if (run.finished) return;
  run.finished = true;
  // Stop the behaviors first: a process that ended must not keep commanding the base.
  while (!run.active.empty()) deactivate(run, run.active.back().place, now);
  ProcessResult result{run.id, run.process->name(), success, std::move(message), std::move(place), run.started, now};
  if (success) {
    spdlog::debug("process {} ({}) succeeded", run.process->name(), run.id);
  } else {
    spdlog::info("process {} ({}) failed: {}", run.process->name(), run.id, result.message);
  }
  for (SupervisorObserver* o : observers_) o->on_run_finished(result);
  results_.push_back(std::move(result));
}

void CProcessSupervisor::activate(Run& run, PlaceIndex place, Time now, std::vector<std::string>& events) {
  const Place& p = run.engine->net().place(place);
  if (!p.behavior) return;  // a process reference in a low-level net has nothing to activate here
  const std::string& name = p.behavior->behavior;
  auto fail = [&](const std::string& why) {
    const std::string msg = "behavior " + name + " failed: " + why;
    for (SupervisorObserver* o : observers_) o->on_fault(name, why, now);
    run.failure_messages[failed_event(name)] = msg;
    events.push_back(failed_event(name));
  };
  ParameterValues params;
  std::string error;
  if (!resolve_binding_params(p.behavior->params, run.params, params, error)) {
    fail(error);
    return;
  }
  if (!behaviors_.has(name)) {
    fail("the robot has no behavior '" + name + "'");
    return;
  }
  // A behavior held by another run's place moves to this one (the newest activation wins).
  for (auto& other : runs_) {
    if (other.get() == &run) continue;
    auto it = std::find_if(other->active.begin(), other->active.end(), [&](const Run::Active& a) { return a.behavior == name; });
    if (it != other->active.end()) other->active.erase(it);
  }
  try {
    behaviors_.activate(name, params, now);
  } catch (const std::exception& e) {
    fail(std::string("activation threw: ") + e.what());
    return;
  } catch (...) {
    fail("activation threw an unknown exception");
    return;
  }
  auto same = std::find_if(run.active.begin(), run.active.end(), [&](const Run::Active& a) { return a.behavior == name; });
  if (same != run.active.end()) run.active.erase(same);
  run.active.push_back(Run::Active{place, name, now});
  for (SupervisorObserver* o : observers_) o->on_behavior_activated(run.id, name, params, now);
}

void CProcessSupervisor::deactivate(Run& run, PlaceIndex place, Time now) {
  auto it = std::find_if(run.active.begin(), run.active.end(), [&](const Run::Active& a) { return a.place == place; });
  if (it == run.active.end()) return;
  const std::string name = it->behavior;
  run.active.erase(it);
  try {
    behaviors_.deactivate(name, now);
  } catch (const std::exception& e) {
    for (SupervisorObserver* o : observers_) o->on_fault(name, std::string("deactivation threw: ") + e.what(), now);
  } catch (...) {
    for (SupervisorObserver* o : observers_) o->on_fault(name, "deactivation threw an unknown exception", now);
  }
  for (SupervisorObserver* o : observers_) o->on_behavior_deactivated(run.id, name, now);
}

std::vector<std::string> CProcessSupervisor::step_run(Run& run, std::vector<std::string> events, Time now) {
  std::vector<std::string_view> views;
  std::vector<std::string> first_dropped;
  for (std::size_t round = 0; round < options_.max_rounds_per_step && !run.finished; ++round) {
    views.assign(events.begin(), events.end());
    const StepResult& r = run.engine->step(now, std::span<const std::string_view>(views));
    // Copy what we need: activation below may call back into observers, never into the engine.
    const StepStatus status = r.status;
    const std::string error = r.error;
    const std::vector<std::string> unconsumed = r.unconsumed_events;
    const std::vector<PlaceIndex> activated = r.activated;
    const std::vector<PlaceIndex> deactivated = r.deactivated;
    if (round == 0) first_dropped = unconsumed;
    if (status != StepStatus::ok) {
      finish(run, false, error.empty() ? std::string(to_string(status)) : error, {}, now);
      return first_dropped;
    }
    std::string unhandled;
    for (const std::string& e : unconsumed) {
      auto f = run.failure_messages.find(e);
      if (f != run.failure_messages.end() && unhandled.empty()) unhandled = f->second;
    }
    for (PlaceIndex p : deactivated) deactivate(run, p, now);
    const OutcomeState o = run.engine->outcome();
    if (o.outcome != Outcome::none) {
      finish(run, o.outcome == Outcome::success, std::string(o.message), std::string(o.place_id), now);
      return first_dropped;
    }
    if (!unhandled.empty()) {
      // The net has no transition for this failure: the process cannot go on, so it fails with
      // the behavior's reason rather than waiting forever.
      finish(run, false, unhandled, {}, now);
      return first_dropped;
    }
    events.clear();
    for (PlaceIndex p : activated) activate(run, p, now, events);
    if (events.empty()) return first_dropped;
  }
  if (!run.finished && !events.empty()) {
    finish(run, false, "behavior activations kept failing at one instant (" + std::to_string(options_.max_rounds_per_step) +
                           " rounds)", {}, now);
  }
  return first_dropped;
}

void CProcessSupervisor::step() {
  stepping_ = true;
  struct Done {
    bool& flag;
    ~Done() { flag = false; }
  } done{stepping_};
  const Time now = clock_.now();
  std::vector<std::string> module_events;
  std::vector<std::pair<std::string, Value>> facts;
  std::vector<Inbox::Fault> faults;
  {
    std::lock_guard lock(inbox_->mutex);
    module_events.swap(inbox_->events);
    facts.swap(inbox_->facts);
    faults.swap(inbox_->faults);
    for (auto& [module, w] : inbox_->watches) {
      if (w.fired || w.timeout <= Duration{0} || now - w.last < w.timeout) continue;
      w.fired = true;
      const std::string why = "stopped answering (no heartbeat for " + format_seconds(now - w.last) + " s)";
      if (w.event.empty()) {
        faults.push_back({module, why, module + ".fault"});
      } else {
        for (SupervisorObserver* o : observers_) o->on_fault(module, why, now);
        module_events.push_back(w.event);
      }
    }
  }
  // Module faults: an event each; remembered so that an unhandled one fails the processes.
  std::map<std::string, std::string, std::less<>> fault_messages;
  for (Inbox::Fault& f : faults) {
    for (SupervisorObserver* o : observers_) o->on_fault(f.source, f.reason, now);
    fault_messages.emplace(f.event, "module " + f.source + " failed: " + f.reason);
    module_events.push_back(std::move(f.event));
  }
  for (auto& [name, value] : facts) {
    inbox_->latest_facts.insert_or_assign(name, value);
    for (auto& r : runs_) {
      if (r->engine->fact_id(name)) {
        try {
          r->engine->set_fact(name, value);
        } catch (const std::exception& e) {
          for (SupervisorObserver* o : observers_) o->on_fault(name, std::string("fact rejected: ") + e.what(), now);
        }
      }
    }
  }

  std::map<std::string, std::size_t, std::less<>> consumed;  // module event -> runs that consumed it
  const std::size_t n = runs_.size();
  for (std::size_t i = 0; i < n; ++i) {
    Run& run = *runs_[i];
    if (run.finished) continue;
    // Module events were queued before this step; behavior status is read now, so it comes after.
    std::vector<std::string> events = module_events;
    events.insert(events.end(), run.pending_events.begin(), run.pending_events.end());
    run.pending_events.clear();
    std::vector<std::string> done_offered;
    // Behavior status becomes events of the run that holds the behavior, once per change.
    for (auto& a : run.active) {
      BehaviorReport rep;
      try {
        rep = behaviors_.report(a.behavior);
      } catch (const std::exception& e) {
        rep.state = BehaviorStatus::failed;
        rep.reason = std::string("status query threw: ") + e.what();
      } catch (...) {
        rep.state = BehaviorStatus::failed;
        rep.reason = "status query threw an unknown exception";
      }
      if (rep.state == BehaviorStatus::running && options_.behavior_watchdog > Duration{0} && rep.last_step) {
        const Time last = std::max(*rep.last_step, a.since);
        if (now - last > options_.behavior_watchdog) {
          rep.state = BehaviorStatus::failed;
          rep.reason = "stopped answering (no step for " + format_seconds(now - last) + " s)";
        }
      }
      if (rep.state == BehaviorStatus::succeeded && !a.done_posted) {
        // Level-triggered: offered every step until the net takes it, so a completion that
        // arrives while the net cannot accept it (localization lost) is not lost.
        done_offered.push_back(done_event(a.behavior));
        events.push_back(done_offered.back());
      } else if (rep.state == BehaviorStatus::failed && !a.failure_posted) {
        a.failure_posted = true;
        const std::string reason = rep.reason.empty() ? std::string("no reason given") : rep.reason;
        for (SupervisorObserver* o : observers_) o->on_fault(a.behavior, reason, now);
        run.failure_messages[failed_event(a.behavior)] = "behavior " + a.behavior + " failed: " + reason;
        events.push_back(failed_event(a.behavior));
      }
    }
    const std::vector<std::string> dropped = step_run(run, std::move(events), now);
    for (const std::string& e : done_offered) {
      if (std::find(dropped.begin(), dropped.end(), e) != dropped.end()) continue;
      for (auto& a : run.active) {
        if (done_event(a.behavior) == e) a.done_posted = true;
      }
    }
    for (const std::string& e : module_events) {
      if (std::find(dropped.begin(), dropped.end(), e) == dropped.end()) ++consumed[e];
    }
  }
  for (const std::string& e : module_events) {
    if (consumed.count(e) > 0) continue;
    for (SupervisorObserver* o : observers_) o->on_event_dropped(e, now);
    auto f = fault_messages.find(e);
    if (f == fault_messages.end()) continue;
    // Nobody handles this module's failure: the running processes cannot trust their inputs.
    for (auto& r : runs_) finish(*r, false, f->second, {}, now);
  }
  for (auto it = runs_.begin(); it != runs_.end();) {
    if ((*it)->finished) {
      it = runs_.erase(it);
    } else {
      ++it;
    }
  }
}

std::vector<ProcessResult> CProcessSupervisor::take_results() {
  std::vector<ProcessResult> out;
  out.swap(results_);
  return out;
}

void CProcessSupervisor::post_event(std::string event) {
  std::lock_guard lock(inbox_->mutex);
  inbox_->events.push_back(std::move(event));
}

void CProcessSupervisor::set_fact(std::string name, Value value) {
  std::lock_guard lock(inbox_->mutex);
  inbox_->facts.emplace_back(std::move(name), std::move(value));
}

void CProcessSupervisor::watch_module(std::string module, Duration timeout, std::string event) {
  std::lock_guard lock(inbox_->mutex);
  inbox_->watches[std::move(module)] = Inbox::Watch{timeout, std::move(event), clock_.now(), false};
}

void CProcessSupervisor::heartbeat(std::string_view module) {
  const Time now = clock_.now();
  std::lock_guard lock(inbox_->mutex);
  auto it = inbox_->watches.find(module);
  if (it == inbox_->watches.end()) return;
  it->second.last = now;
  it->second.fired = false;
}

void CProcessSupervisor::report_module_fault(std::string module, std::string reason) {
  std::lock_guard lock(inbox_->mutex);
  std::string event = module + ".fault";
  inbox_->faults.push_back({std::move(module), std::move(reason), std::move(event)});
}

void CProcessSupervisor::report_fault(std::string source, std::string event, std::string reason) {
  std::lock_guard lock(inbox_->mutex);
  inbox_->faults.push_back({std::move(source), std::move(reason), std::move(event)});
}

bool CProcessSupervisor::running(std::string_view run) const noexcept {
  return std::any_of(runs_.begin(), runs_.end(), [&](const auto& r) { return r->id == run && !r->finished; });
}

bool CProcessSupervisor::idle() const noexcept { return runs_.empty(); }

std::vector<std::string> CProcessSupervisor::running_runs() const {
  std::vector<std::string> out;
  for (const auto& r : runs_) out.push_back(r->id);
  return out;
}

std::vector<std::string> CProcessSupervisor::active_behaviors() const {
  std::vector<std::string> out;
  for (const auto& r : runs_) {
    for (const auto& a : r->active) out.push_back(a.behavior);
  }
  std::sort(out.begin(), out.end());
  return out;
}

const Engine* CProcessSupervisor::engine(std::string_view run) const noexcept {
  for (const auto& r : runs_) {
    if (r->id == run) return r->engine.get();
  }
  return nullptr;
}

const CProcess* CProcessSupervisor::process(std::string_view run) const noexcept {
  for (const auto& r : runs_) {
    if (r->id == run) return r->process;
  }
  return nullptr;
}

std::vector<std::string> CProcessSupervisor::why_not_quiet(std::string_view run) const {
  const auto it = std::find_if(runs_.begin(), runs_.end(), [&](const auto& r) { return r->id == run; });
  if (it == runs_.end() || (*it)->finished) return {"no process is running as '" + std::string(run) + "'"};
  if (stepping_) return {"the supervisor is inside a step (a firing in progress): reload between steps"};
  const Run& r = **it;
  const Engine& e = *r.engine;
  std::vector<std::string> why;
  if (const OutcomeState o = e.outcome(); o.outcome != Outcome::none) {
    why.push_back("the net has reached its outcome place " + std::string(o.place_id));
  }
  const PetriNet& net = e.net();
  for (TransitionIndex t = 0; t < net.transitions().size(); ++t) {
    const Transition& tr = net.transition(t);
    if (!tr.event.empty() || !e.is_enabled(t)) continue;  // waiting for its event is the quiet state
    if (tr.delay > Duration{0}) {
      why.push_back("transition " + tr.id + " is timing its delay of " + format_seconds(tr.delay, kExactDigits) +
                    " s: a new net would start it again");
    } else {
      why.push_back("transition " + tr.id + " is enabled and has not fired yet (the net has not settled)");
    }
  }
  for (const Run::Active& a : r.active) {
    BehaviorReport rep;
    try {
      rep = behaviors_.report(a.behavior);
    } catch (...) {
      rep.state = BehaviorStatus::failed;
    }
    if (rep.state == BehaviorStatus::succeeded && !a.done_posted) {
      why.push_back("behavior " + a.behavior + " (place " + net.place(a.place).id + ") has completed and the net has not taken " +
                    done_event(a.behavior) + " yet (a transition mid-action)");
    } else if (rep.state == BehaviorStatus::failed && !a.failure_posted) {
      why.push_back("behavior " + a.behavior + " (place " + net.place(a.place).id + ") has failed and the net has not taken " +
                    failed_event(a.behavior) + " yet (a transition mid-action)");
    }
  }
  if (!r.pending_events.empty()) why.push_back("events of the last reload wait for the next step");
  return why;
}

ReloadResult CProcessSupervisor::reload(std::string_view run, std::string_view text, std::string_view source_name) {
  ReloadResult res;
  LoadOptions lo;
  lo.is_known_behavior = [this](std::string_view b) { return behaviors_.has(b); };
  std::optional<PetriNet> net = load_net_from_string(text, source_name, res.diagnostics, lo);
  if (!net) return res;
  Diagnostics warnings = std::move(res.diagnostics);
  res = reload(run, std::move(*net));
  // The loader's warnings come first, as a reader of the file expects them.
  warnings.append(res.diagnostics);
  res.diagnostics = std::move(warnings);
  return res;
}

ReloadResult CProcessSupervisor::reload(std::string_view run, PetriNet net) {
  ReloadResult res;
  const SourceLocation net_where = net.where;
  const auto it = std::find_if(runs_.begin(), runs_.end(), [&](const auto& r) { return r->id == run && !r->finished; });
  if (it == runs_.end()) {
    std::string running;
    for (const auto& r : runs_) running += (running.empty() ? "" : ", ") + r->id;
    res.diagnostics.error(net_where, "no process is running as '" + std::string(run) + "' (running: " +
                                         (running.empty() ? std::string("none") : running) + ")");
    return res;
  }
  Run& r = **it;
  const Time now = clock_.now();

  // The edited process: the same module in every respect but its net (name, type, configured
  // parameters, recovery rules), checked as configuration is.
  ProcessDefinition d;
  d.name = r.process->name();
  d.type = r.process->type();
  d.net = std::move(net);
  if (const PetriNet* m = r.process->module()) d.module = *m;
  d.parameters = r.process->configured_parameters();
  d.recovery = r.process->recovery();
  d.where = net_where;
  std::unique_ptr<CProcess> edited;
  try {
    edited = std::make_unique<CProcess>(std::move(d));
  } catch (const ConfigError& e) {
    res.diagnostics.append(e.diagnostics());
    return res;
  }

  // The marking, by place id. The new net's initial marking does not count: the instance goes on.
  const Engine& old = *r.engine;
  const PetriNet& old_net = old.net();
  PetriNet carried = edited->net();
  for (PlaceIndex p = 0; p < carried.places().size(); ++p) carried.place(p).initial_tokens = 0;
  const auto marking = old.marking();
  for (PlaceIndex p = 0; p < marking.size(); ++p) {
    if (marking[p] == 0) continue;
    const Place& was = old_net.place(p);
    const auto to = carried.find_place(was.id);
    const std::string tokens = std::to_string(marking[p]) + (marking[p] == 1 ? " token" : " tokens");
    if (!to) {
      res.diagnostics.error(net_where, "place " + was.id + " holds " + tokens + " in the running net (run " + r.id +
                                           ") but is not in the new net: its marking cannot be carried over");
      continue;
    }
    Place& now_place = carried.place(*to);
    if (now_place.capacity && marking[p] > *now_place.capacity) {
      res.diagnostics.error(now_place.where, "place " + was.id + " holds " + tokens + " in the running net, more than its new capacity " +
                                                 std::to_string(*now_place.capacity));
      continue;
    }
    now_place.initial_tokens = marking[p];
    if (!res.marking.empty()) res.marking += ", ";
    res.marking += was.id + "=" + std::to_string(marking[p]);
    if (now_place.outcome != Outcome::none) {
      res.diagnostics.error(now_place.where, "place " + was.id + " is an outcome place in the new net: carrying its marking over would end the process at once");
    }
  }
  if (res.diagnostics.has_errors()) return res;

  EngineOptions eo = options_.engine;
  eo.start_time = now;
  std::unique_ptr<Engine> engine;
  try {
    engine = std::make_unique<Engine>(carried, r.params, eo);
  } catch (const ConfigError& e) {
    res.diagnostics.append(e.diagnostics());
    return res;
  } catch (const std::exception& e) {
    res.diagnostics.error(net_where, std::string("the engine refused the new net: ") + e.what());
    return res;
  }
  // Facts keep their values where the new net declares them with the same type.
  for (const VariableDecl& f : old_net.facts) {
    const auto from = old.fact_id(f.name);
    const auto to = engine->fact_id(f.name);
    if (!from || !to) continue;
    if (const Value* v = old.fact(*from)) {
      try {
        engine->set_fact(*to, *v);
      } catch (const std::exception& e) {
        res.diagnostics.warning(net_where, "fact " + f.name + " starts unknown in the new net: " + e.what());
      }
    }
  }
  const PetriNet& new_net = engine->net();
  for (TransitionIndex t = 0; t < new_net.transitions().size(); ++t) {
    const Transition& tr = new_net.transition(t);
    if (tr.event.empty() && tr.delay == Duration{0} && engine->is_enabled(t)) {
      res.diagnostics.error(tr.where, "transition " + tr.id + " is enabled by the carried marking (" + res.marking +
                                          ") and would fire at once: the marking is not quiet in the new net");
    }
  }
  if (res.diagnostics.has_errors()) return res;
  for (const std::string& why : why_not_quiet(run)) res.diagnostics.error(net_where, "run " + r.id + " is not at a quiet marking: " + why);
  if (res.diagnostics.has_errors()) {
    res.not_quiet = true;
    return res;
  }

  // Settle the new engine at the reload's instant: nothing fires (checked above); its first step
  // reports the bound places of the carried marking, which are matched with the running behaviors.
  const StepResult& first = engine->step(now);
  const std::vector<PlaceIndex> bound = first.activated;
  std::vector<Run::Active> kept;
  std::vector<PlaceIndex> to_activate;
  for (const PlaceIndex p : bound) {
    const Place& np = new_net.place(p);
    if (!np.behavior) continue;
    const auto same = std::find_if(r.active.begin(), r.active.end(), [&](const Run::Active& a) {
      const Place& op = old_net.place(a.place);
      return op.id == np.id && op.behavior && a.behavior == np.behavior->behavior && same_binding(op.behavior->params, np.behavior->params);
    });
    if (same == r.active.end()) {
      to_activate.push_back(p);
      continue;
    }
    Run::Active a = *same;
    a.place = p;
    kept.push_back(std::move(a));
    r.active.erase(same);
  }
  // The behaviors the edited net no longer holds (or holds with another binding) stop first.
  while (!r.active.empty()) deactivate(r, r.active.back().place, now);
  r.active = std::move(kept);
  r.engine->remove_observer(r.forwarder);
  r.engine = std::move(engine);
  r.engine->add_observer(r.forwarder);
  r.reloaded = std::move(edited);
  r.process = r.reloaded.get();
  for (const PlaceIndex p : to_activate) activate(r, p, now, r.pending_events);
  res.accepted = true;
  spdlog::info("process {} ({}) net reloaded at a quiet marking: {}", r.process->name(), r.id, res.marking);
  for (SupervisorObserver* o : observers_) o->on_net_reloaded(r.id, *r.process, res.marking, now);
  return res;
}

std::optional<Time> CProcessSupervisor::next_deadline() const noexcept {
  std::optional<Time> best;
  for (const auto& r : runs_) {
    auto d = r->engine->next_deadline();
    if (d && (!best || *d < *best)) best = d;
  }
  return best;
}

void CProcessSupervisor::add_observer(SupervisorObserver& observer) { observers_.push_back(&observer); }

void CProcessSupervisor::remove_observer(const SupervisorObserver& observer) noexcept {
  observers_.erase(std::remove(observers_.begin(), observers_.end(), &observer), observers_.end());
}

}  // namespace tripodal
