// CProcessSupervisor: the core component of the sequencing layer that runs process modules. It
// executes each running process's low-level net on an Engine, activates the behaviors of marked
// places (parameters resolved from the process), turns behavior status and module events into net
// events, and reports each process's result — success, or a fault with its message — to the
// planner. Semantics and event names: docs/processes.md.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/processes/behavior_host.hpp"
#include "tripodal/processes/process.hpp"

namespace tripodal {

/// Sees the life of the processes a supervisor runs. Called synchronously from the supervisor's
/// thread; must not call back into the supervisor. Every hook defaults to doing nothing.
class SupervisorObserver {
 public:
  virtual ~SupervisorObserver() = default;
  SupervisorObserver() = default;
  SupervisorObserver(const SupervisorObserver&) = default;
  SupervisorObserver& operator=(const SupervisorObserver&) = default;

  virtual void on_run_started(std::string_view /*run*/, const CProcess& /*process*/,
                                  const ParameterValues& /*params*/, Time /*now*/) {}
  virtual void on_run_finished(const ProcessResult& /*result*/) {}
  virtual void on_behavior_activated(std::string_view /*run*/, std::string_view /*behavior*/,
                                     const ParameterValues& /*params*/, Time /*now*/) {}
  virtual void on_behavior_deactivated(std::string_view /*run*/, std::string_view /*behavior*/, Time /*now*/) {}
  /// A firing of a process net; `firing` views are valid during the call only.
  virtual void on_firing(std::string_view /*run*/, const PetriNet& /*net*/, const Firing& /*firing*/) {}
  /// An event no running process consumed.
  virtual void on_event_dropped(std::string_view /*event*/, Time /*now*/) {}
  /// A module or behavior failed at run time (threw, reported failure, stopped answering).
  virtual void on_fault(std::string_view /*source*/, std::string_view /*reason*/, Time /*now*/) {}
  /// The net of a running process was replaced by an edited one at a quiet marking
  /// (CProcessSupervisor::reload); `marking` is the carried marking, "P1=1, P3=1".
  virtual void on_net_reloaded(std::string_view /*run*/, const CProcess& /*process*/, std::string_view /*marking*/,
                               Time /*now*/) {}
};

/// What CProcessSupervisor::reload did, or why it refused.
struct ReloadResult {
  bool accepted = false;
  /// Refused only because the run is not at a quiet marking now (it may be at a later step).
  bool not_quiet = false;
  /// Refused: every reason, located (FILE:LINE:COL of the edited net where there is one).
  /// Accepted: the loader's warnings, if any.
  Diagnostics diagnostics;
  /// Accepted: the marking carried over, by place id ("P1=1, P3=1").
  std::string marking;
};

struct SupervisorOptions {
  /// An active behavior that reports a last step older than this has stopped answering and fails.
  /// Zero disables the behavior watchdog.
  Duration behavior_watchdog{0};
  /// Rounds of (events -> step -> activations) one step() may take at one instant before it
  /// gives up (each round consumes the events the previous one produced).
  std::size_t max_rounds_per_step = 16;
  EngineOptions engine;
};

/// Runs process modules. Not thread-safe except for post_event, set_fact, heartbeat and
/// report_module_fault, which modules may call from any thread (they queue for the next step()).
class CProcessSupervisor final {
 public:
  CProcessSupervisor(BehaviorHost& behaviors, const Clock& clock, SupervisorOptions options = {});
  ~CProcessSupervisor();
  CProcessSupervisor(const CProcessSupervisor&) = delete;
  CProcessSupervisor& operator=(const CProcessSupervisor&) = delete;

  /// Starts `process` under the id `run` (unique among running processes) with bound parameters
  /// (CProcess::bind). Nothing fires until the next step(). Returns false with `error` when the
  /// run id is in use or the engine refuses the parameters. The process must outlive the run.
  bool start(std::string run, const CProcess& process, ParameterValues params, std::string* error = nullptr);
  /// Stops a running process: its behaviors are deactivated and it ends with a fault "stopped:
  /// <reason>" (reported like any other result). False when no such run is running.
  bool stop(std::string_view run, std::string_view reason = "stopped by the planner");

  /// Replaces the net of the running process `run` by an edited one, carrying the marking over by
  /// place id, and records it (SupervisorObserver::on_net_reloaded). Call it between steps (the
  /// thread that steps). Refused, with located diagnostics and nothing changed, when: no such run;
  /// the net does not load (load_net_from_string, `source_name` in the diagnostics; behavior names
  /// checked against the host) or is not a valid process net (CProcess) or does not take the run's
  /// parameters (Engine); a marked place of the running net is missing from the new net or holds
  /// more than the new place's capacity; the carried marking marks an outcome place or enables an
  /// immediate transition in the new net; the run is not quiet (why_not_quiet). The run keeps its
  /// id, bound parameters, start time and the facts both nets declare; the new net's initial
  /// marking is ignored; a delayed transition enabled in the carried marking counts its delay from
  /// the reload. A behavior whose place stays marked with the same binding keeps running (it is not
  /// restarted); the others are deactivated, and the newly bound ones activated.
  ReloadResult reload(std::string_view run, std::string_view text, std::string_view source_name);
  /// The same with a net already loaded.
  ReloadResult reload(std::string_view run, PetriNet net);
  /// Why `run` is not at a quiet marking now, one reason each; empty when quiet. A run is quiet
  /// between steps when nothing is under way that a swap of its net would lose or repeat: no
  /// immediate transition is enabled (the net has settled), no delayed transition is timing its
  /// delay, and no behavior of a marked place has completed or failed without the net having
  /// taken its event yet (a transition mid-action). Inside a step (an observer calling back) a
  /// firing is in progress: never quiet. A run that is not running is not quiet either.
  [[nodiscard]] std::vector<std::string> why_not_quiet(std::string_view run) const;

  /// One supervision step at the clock's time: drains queued module events and facts, checks the
  /// watchdogs, polls the active behaviors, steps every running net (in start order) and
  /// (de)activates behaviors, repeating while new events appear; finished processes deactivate
  /// their behaviors and their results become available through take_results(). Never throws
  /// because of a behavior or module.
  void step();

  /// The results finished since the last call, in the order the processes ended.
  [[nodiscard]] std::vector<ProcessResult> take_results();

  // --- for modules (any thread) ---------------------------------------------------------------
  /// Queues an event for every running process ("localizer.lost").
  void post_event(std::string event);
  /// Queues a fact change for every running process that declares the fact.
  void set_fact(std::string name, Value value);
  /// Watches a module: when no heartbeat arrives for `timeout`, the event `event` (default
  /// "<module>.fault") is posted once until the next heartbeat. The silence counts from now.
  void watch_module(std::string module, Duration timeout, std::string event = {});
  void heartbeat(std::string_view module);
  /// A module failed at run time (threw, returned a failure): posts "<module>.fault". When no
  /// running process consumes it, every running process fails with "module <m> failed: <reason>".
  void report_module_fault(std::string module, std::string reason);
  /// A fault of `source` posted as `event` rather than "<source>.fault" — a loop's missed deadlines
  /// ("motion.deadline"): observers see it as a fault, and when no running process consumes the
  /// event every running process fails with "module <source> failed: <reason>" (the planner's
  /// recovery rules match that message).
  void report_fault(std::string source, std::string event, std::string reason);

  // --- inspection ------------------------------------------------------------------------------
  [[nodiscard]] bool running(std::string_view run) const noexcept;
  [[nodiscard]] bool idle() const noexcept;
  [[nodiscard]] std::vector<std::string> running_runs() const;
  /// Behaviors currently active, by name, sorted.
  [[nodiscard]] std::vector<std::string> active_behaviors() const;
  /// The engine of a running process (for monitors and tests); nullptr when not running.
  [[nodiscard]] const Engine* engine(std::string_view run) const noexcept;
  /// The process a run executes (after a reload, the edited one); nullptr when not running.
  [[nodiscard]] const CProcess* process(std::string_view run) const noexcept;
  /// The earliest delay deadline of any running net.
  [[nodiscard]] std::optional<Time> next_deadline() const noexcept;

  /// Observers are not owned; remove one before destroying it.
  void add_observer(SupervisorObserver& observer);
  void remove_observer(const SupervisorObserver& observer) noexcept;

  struct Run;

 private:
  struct Inbox;
  void finish(Run& run, bool success, std::string message, std::string place, Time now);
  // Returns the events of the first round the net dropped.
  std::vector<std::string> step_run(Run& run, std::vector<std::string> events, Time now);
  void activate(Run& run, PlaceIndex place, Time now, std::vector<std::string>& events);
  void deactivate(Run& run, PlaceIndex place, Time now);

  BehaviorHost& behaviors_;
  const Clock& clock_;
  SupervisorOptions options_;
  std::vector<std::unique_ptr<Run>> runs_;  // start order: the order nets are stepped in
  std::vector<ProcessResult> results_;
  std::vector<SupervisorObserver*> observers_;
  std::unique_ptr<Inbox> inbox_;
  bool stepping_ = false;  // inside step(): an observer calling reload() would swap a net mid-firing
};

}  // namespace tripodal
