#include "tripodal/planner/planner.hpp"

#include <algorithm>
#include <sstream>

#include <spdlog/spdlog.h>

namespace tripodal {

std::string_view to_string(TaskState s) noexcept {
  switch (s) {
    case TaskState::idle: return "idle";
    case TaskState::running: return "running";
    case TaskState::succeeded: return "succeeded";
    case TaskState::failed: return "failed";
  }
  return "?";
}

namespace {

std::string stamp(Time t) { return format_seconds(t) + " s"; }

std::string step_text(const ProcessStep& s) {
  std::string out = s.process + "(";
  for (std::size_t i = 0; i < s.params.size(); ++i) {
    out += (i ? ", " : "") + s.params[i].name + "=" + s.params[i].value;
  }
  return out + ")";
}

}  // namespace

std::string TaskReport::str() const {
  std::ostringstream o;
  o << "task '" << task << "' (\"" << command << "\"): " << to_string(state);
  if (!reason.empty()) o << ": " << reason;
  o << "\n  started " << stamp(started);
  if (finished) o << ", finished " << stamp(*finished);
  o << "\n  plan: " << initial_plan << '\n';
  for (const ProcessRecord& p : processes) {
    o << "  " << stamp(p.started) << "  " << p.run << ' ' << step_text(p.step);
    if (!p.finished) {
      o << " running\n";
    } else if (p.success) {
      o << " succeeded at " << stamp(*p.finished) << '\n';
    } else {
      o << " failed at " << stamp(*p.finished) << ": " << p.message << '\n';
    }
  }
  for (const RecoveryRecord& r : recoveries) {
    o << "  " << stamp(r.time) << "  recovery: " << r.reason << "; plan: " << r.new_plan << '\n';
  }
  return o.str();
}

struct CPlanner::Impl {
  const TaskLibrary& tasks;
  const RecoveryPolicy& recovery;
  const TaskKnowledge& knowledge;
  const ProcessRegistry& processes;
  CProcessSupervisor& supervisor;
  const Clock& clock;
  PlannerOptions options;
  std::vector<TaskObserver*> observers;

  TaskReport report;
  Plan plan;  // what the current net runs
  std::unique_ptr<Engine> net;
  std::map<std::string, std::pair<std::size_t, std::size_t>, std::less<>> stage_of;  // X place -> (stage, branch)
  std::map<std::string, std::size_t, std::less<>> record_of;  // running X place -> report.processes index
  std::vector<std::string> pending;  // events for the high-level net
  std::optional<std::pair<std::string, std::string>> failure;  // (X place, message): first fault in this net
  std::map<std::string, RecoveryPolicy, std::less<>> own_policies;  // per process: its own rules
  std::map<const RecoveryRule*, int> fired;
  std::optional<std::string> ending;  // a rule's `then: end`: the reason the task fails once the inserted processes are done

  Impl(const TaskLibrary& t, const RecoveryPolicy& r, const TaskKnowledge& k, const ProcessRegistry& p,
       CProcessSupervisor& s, const Clock& c, PlannerOptions o)
      : tasks(t), recovery(r), knowledge(k), processes(p), supervisor(s), clock(c), options(o) {}

  void build_net(Time now) {
    PetriNet n = plan_to_net(plan, "plan", [this](std::string_view name) -> const PetriNet* {
      const CProcess* p = processes.find(name);
      return p != nullptr ? p->module() : nullptr;
    });
    stage_of.clear();
    for (std::size_t s = 0; s < plan.stages.size(); ++s) {
      for (std::size_t b = 0; b < plan.stages[s].steps.size(); ++b) stage_of[PlanNetIds::executing(s, b)] = {s, b};
    }
    EngineOptions eo;
    eo.start_time = now;
    net = std::make_unique<Engine>(n, ParameterValues{}, eo);
    failure.reset();
    pending.clear();
  }

  ProcessRecord& record(const std::string& run) { return report.processes.at(record_of.at(run)); }

  void process_ended(const std::string& run, bool success, const std::string& message, Time now) {
    auto it = record_of.find(run);
    if (it == record_of.end()) return;  // not ours (another user of the supervisor)
    ProcessRecord& p = report.processes.at(it->second);
    p.finished = now;
    p.success = success;
    p.message = message;
    record_of.erase(it);
    if (success) {
      for (TaskObserver* o : observers) o->on_process_succeeded(p);
      pending.push_back(PlanNetIds::success_event(run));
    } else {
      for (TaskObserver* o : observers) o->on_process_failed(p);
      pending.push_back(PlanNetIds::fault_event(run));
      if (!failure) failure = std::make_pair(run, message);
    }
  }

  void start_process(const std::string& run, const ProcessRef& ref, Time now) {
    auto sb = stage_of.find(run);
    ProcessStep step{ref.process, ref.params};
    if (sb != stage_of.end()) step = plan.stages[sb->second.first].steps[sb->second.second];
    report.processes.push_back(ProcessRecord{run, step, now, std::nullopt, false, {}});
    record_of[run] = report.processes.size() - 1;
    for (TaskObserver* o : observers) o->on_process_started(report.processes.back());
    const CProcess* proc = processes.find(ref.process);
    if (proc == nullptr) {
      process_ended(run, false, "the robot has no process '" + ref.process + "'", now);
      return;
    }
    BoundParameters bound = proc->bind(ref.params);
    if (!bound.ok) {
      process_ended(run, false, bound.error, now);
      return;
    }
    std::string error;
    if (!supervisor.start(run, *proc, std::move(bound.values), &error)) process_ended(run, false, error, now);
  }

  void stop_all(const std::string& why, Time now) {
    for (auto it = record_of.begin(); it != record_of.end();) {
      const std::string run = it->first;
      ++it;
      supervisor.stop(run, why);
    }
    for (ProcessResult& r : supervisor.take_results()) process_ended(r.run, r.success, r.message, now);
  }

  void end_task(bool success, std::string reason, Time now) {
    if (!success) stop_all(reason, now);
    report.state = success ? TaskState::succeeded : TaskState::failed;
    report.reason = std::move(reason);
    report.finished = now;
    net.reset();
    pending.clear();
    if (success) {
      spdlog::info("task '{}' succeeded", report.task);
      for (TaskObserver* o : observers) o->on_task_succeeded(report);
    } else {
      spdlog::info("task '{}' failed: {}", report.task, report.reason);
      for (TaskObserver* o : observers) o->on_task_failed(report);
    }
  }

  // Steps the high-level net and the supervisor until neither has anything more to say at `now`.
  bool exchange(Time now) {
    for (std::size_t i = 0; i < options.max_exchanges_per_step; ++i) {
      std::vector<std::string_view> views(pending.begin(), pending.end());
      const StepResult& r = net->step(now, std::span<const std::string_view>(views));
      pending.clear();
      if (!r.ok()) {
        end_task(false, "the plan's net stopped: " + r.error, now);
        return false;
      }
      const std::vector<PlaceIndex> activated = r.activated;
      const std::vector<PlaceIndex> deactivated = r.deactivated;
      const PetriNet& n = net->net();
      for (PlaceIndex p : deactivated) {
        const std::string& id = n.place(p).id;
        if (supervisor.running(id)) supervisor.stop(id, "its place in the plan was left");
      }
      for (PlaceIndex p : activated) {
        const Place& place = n.place(p);
        if (place.process) start_process(place.id, *place.process, now);
      }
      supervisor.step();
      for (ProcessResult& res : supervisor.take_results()) process_ended(res.run, res.success, res.message, now);
      if (pending.empty()) return true;
    }
    end_task(false, "the plan's net and the processes kept exchanging events at one instant", now);
    return false;
  }

  // At a quiet point after a fault: decide, and either continue with a new net or fail.
  void recover(Time now) {
    const auto [run, message] = failure.value_or(std::make_pair(std::string(), std::string("process failed")));
    auto sb = stage_of.find(run);
    if (sb == stage_of.end()) {
      end_task(false, "a process failed: " + message, now);
      return;
    }
    const std::size_t stage = sb->second.first;
    const ProcessStep step = plan.stages[stage].steps[sb->second.second];
    RecoveryDecision d;
    bool decided = false;
    if (const CProcess* proc = processes.find(step.process); proc != nullptr && !proc->recovery().empty()) {
      auto [it, inserted] = own_policies.try_emplace(step.process, proc->recovery());
      const int i = it->second.find_rule(step, message);
      if (i >= 0) {
        const RecoveryRule* rule = &it->second.rules()[static_cast<std::size_t>(i)];
        d = it->second.decide(step, message, fired[rule]);
        decided = true;
      }
    }
    if (!decided) {
      const int i = recovery.find_rule(step, message);
      const RecoveryRule* rule = i >= 0 ? &recovery.rules()[static_cast<std::size_t>(i)] : nullptr;
      d = recovery.decide(step, message, rule ? fired[rule] : 0);
    }
    if (d.action == RecoveryAction::abort) {
      end_task(false, d.reason, now);
      return;
    }
    if (d.rule) ++fired[d.rule];
    if (d.action == RecoveryAction::end) ending = d.reason;
    plan = RecoveryPolicy::remaining_plan(plan, stage, d);
    RecoveryRecord rec{now, step.process, message, d.reason, to_string(plan)};
    report.recoveries.push_back(rec);
    spdlog::info("planner: {}", d.reason);
    for (TaskObserver* o : observers) o->on_recovery(rec);
    build_net(now);
  }
};

CPlanner::CPlanner(const TaskLibrary& tasks, const RecoveryPolicy& recovery, const TaskKnowledge& knowledge,
                   const ProcessRegistry& processes, CProcessSupervisor& supervisor, const Clock& clock,
                   PlannerOptions options)
    : impl_(std::make_unique<Impl>(tasks, recovery, knowledge, processes, supervisor, clock, options)) {}

CPlanner::~CPlanner() = default;

CommandAnswer CPlanner::command(std::string_view command) {
  Impl& m = *impl_;
  const Time now = m.clock.now();
  auto refuse = [&](std::string text) {
    for (TaskObserver* o : m.observers) o->on_command_refused(command, text, now);
    return CommandAnswer{false, std::move(text)};
  };
  if (busy()) {
    return refuse("busy: task '" + m.report.task + "' (\"" + m.report.command + "\") is running; cancel it first");
  }
  Understanding u = m.tasks.understand(command, m.knowledge);
  if (!u.understood) return refuse(u.explanation);
  for (const PlanStage& stage : u.plan.stages) {
    for (const ProcessStep& step : stage.steps) {
      const CProcess* proc = m.processes.find(step.process);
      if (proc == nullptr) {
        std::string known;
        for (const auto& n : m.processes.names()) known += (known.empty() ? "" : ", ") + n;
        return refuse("understood the task '" + u.task + "' but cannot run it: the robot has no process '" +
                      step.process + "' (it has: " + (known.empty() ? "none" : known) + ")");
      }
      BoundParameters b = proc->bind(step.params);
      if (!b.ok) return refuse("understood the task '" + u.task + "' but cannot run it: " + b.error);
    }
  }
  m.report = TaskReport{};
  m.report.task = u.task;
  m.report.command = std::string(command);
  m.report.state = TaskState::running;
  m.report.started = now;
  m.report.initial_plan = to_string(u.plan);
  m.plan = std::move(u.plan);
  m.fired.clear();
  m.ending.reset();
  m.record_of.clear();
  m.build_net(now);
  spdlog::info("task '{}' started: {}", m.report.task, m.report.initial_plan);
  for (TaskObserver* o : m.observers) o->on_task_started(m.report, m.plan, now);
  return CommandAnswer{true, "task '" + m.report.task + "': " + m.report.initial_plan};
}

void CPlanner::step() {
  Impl& m = *impl_;
  if (m.report.state != TaskState::running || !m.net) return;
  const Time now = m.clock.now();
  // Each recovery gives a new net that may start at once; bound the rounds at one instant.
  for (int round = 0; round < 64; ++round) {
    if (!m.exchange(now)) return;
    const OutcomeState o = m.net->outcome();
    if (o.outcome == Outcome::success) {
      if (m.ending)
        m.end_task(false, *m.ending, now);
      else
        m.end_task(true, {}, now);
      return;
    }
    // A quiet point: the net has reached its fault place and no process of the plan still runs,
    // so the remaining plan can be rewritten without cutting a process short.
    if (o.outcome == Outcome::fault && m.record_of.empty()) {
      m.recover(now);
      if (m.report.state != TaskState::running) return;
      continue;
    }
    return;
  }
  m.end_task(false, "recovery kept failing at one instant", now);
}

void CPlanner::cancel(std::string_view reason) {
  Impl& m = *impl_;
  if (m.report.state != TaskState::running) return;
  m.end_task(false, std::string(reason), m.clock.now());
}

TaskState CPlanner::state() const noexcept { return impl_->report.state; }
const TaskReport& CPlanner::report() const noexcept { return impl_->report; }
const Plan& CPlanner::current_plan() const noexcept { return impl_->plan; }
const Engine* CPlanner::net_engine() const noexcept { return impl_->net.get(); }

std::optional<Time> CPlanner::next_deadline() const noexcept {
  std::optional<Time> best = impl_->supervisor.next_deadline();
  if (impl_->net) {
    auto d = impl_->net->next_deadline();
    if (d && (!best || *d < *best)) best = d;
  }
  return best;
}

void CPlanner::add_observer(TaskObserver& observer) { impl_->observers.push_back(&observer); }
void CPlanner::remove_observer(const TaskObserver& observer) noexcept {
  auto& v = impl_->observers;
  v.erase(std::remove(v.begin(), v.end(), &observer), v.end());
}

}  // namespace tripodal
