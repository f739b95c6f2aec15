// CPlanner: the planner executive of the deliberate layer. It understands a task command with the
// TaskLibrary, runs the plan's high-level net (plan_to_net), starts each process module through the
// process supervisor, feeds the processes' outcomes back into the net, and on a fault applies the
// recovery rules at a quiet point of the net (paper, section 3.1). Life cycle: TaskObserver.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/planner/plan.hpp"
#include "tripodal/planner/recovery.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/processes/process_registry.hpp"
#include "tripodal/processes/process_supervisor.hpp"

namespace tripodal {

/// One process run as the task report lists it.
struct ProcessRecord {
  std::string run;      ///< the high-level net's executing place, e.g. "X1"
  ProcessStep step;     ///< the process and its plan parameters
  Time started{};
  std::optional<Time> finished;
  bool success = false;
  std::string message;  ///< fault message
};

struct RecoveryRecord {
  Time time{};
  std::string failed_process;
  std::string fault;   ///< the fault message
  std::string reason;  ///< the decision, e.g. "fault \"localization fault\" of PrCleaning: insert PrGlobalLocalization, then retry (1/2)"
  std::string new_plan;  ///< to_string of the remaining plan
};

enum class TaskState { idle, running, succeeded, failed };
[[nodiscard]] std::string_view to_string(TaskState s) noexcept;

/// What became of a task: the report the planner gives at the end (and while it runs).
struct TaskReport {
  std::string task;     ///< template name
  std::string command;  ///< the user's words
  TaskState state = TaskState::idle;
  std::string reason;   ///< why it failed
  std::string initial_plan;
  Time started{};
  std::optional<Time> finished;
  std::vector<ProcessRecord> processes;
  std::vector<RecoveryRecord> recoveries;
  /// Multi-line human-readable form.
  [[nodiscard]] std::string str() const;
};

/// The planner's answer to a command.
struct CommandAnswer {
  bool accepted = false;
  std::string text;  ///< what will be done, or why nothing will
};

/// Sees the task life cycle. Every hook defaults to doing nothing.
class TaskObserver {
 public:
  virtual ~TaskObserver() = default;
  TaskObserver() = default;
  TaskObserver(const TaskObserver&) = default;
  TaskObserver& operator=(const TaskObserver&) = default;

  virtual void on_command_refused(std::string_view /*command*/, std::string_view /*answer*/, Time /*now*/) {}
  virtual void on_task_started(const TaskReport& /*task*/, const Plan& /*plan*/, Time /*now*/) {}
  virtual void on_process_started(const ProcessRecord& /*p*/) {}
  virtual void on_process_succeeded(const ProcessRecord& /*p*/) {}
  virtual void on_process_failed(const ProcessRecord& /*p*/) {}
  virtual void on_recovery(const RecoveryRecord& /*r*/) {}
  virtual void on_task_succeeded(const TaskReport& /*task*/) {}
  virtual void on_task_failed(const TaskReport& /*task*/) {}
};

struct PlannerOptions {
  /// The most (high-level step, supervisor step) exchanges one step() may take at one instant.
  std::size_t max_exchanges_per_step = 64;
};

/// Runs one task at a time. Single-threaded: command(), step() and cancel() from one thread.
class CPlanner final {
 public:
  /// Keeps references to every argument; they must outlive the planner.
  CPlanner(const TaskLibrary& tasks, const RecoveryPolicy& recovery, const TaskKnowledge& knowledge,
           const ProcessRegistry& processes, CProcessSupervisor& supervisor, const Clock& clock,
           PlannerOptions options = {});
  ~CPlanner();
  CPlanner(const CPlanner&) = delete;
  CPlanner& operator=(const CPlanner&) = delete;

  /// Understands `command` and, when it can be planned and every process of the plan exists and
  /// accepts its parameters, starts the task (the processes start at the next step()). Otherwise
  /// nothing runs and the answer says what was understood and what is possible. A command while
  /// a task runs is refused.
  CommandAnswer command(std::string_view command);

  /// Runs the task at the clock's time: steps the high-level net, starts and stops processes,
  /// steps the supervisor, feeds "<X>.success" / "<X>.fault" back, and when the net reaches its
  /// fault place with no process running (a quiet point) applies the recovery rules: the
  /// remaining plan gets a new net, or the task fails with a report.
  void step();

  /// Stops the running task: its processes are stopped and it fails with `reason`.
  void cancel(std::string_view reason = "cancelled");

  [[nodiscard]] TaskState state() const noexcept;
  [[nodiscard]] bool busy() const noexcept { return state() == TaskState::running; }
  /// The current (or last) task's report.
  [[nodiscard]] const TaskReport& report() const noexcept;
  /// The plan the current high-level net runs (after recoveries: the remaining plan).
  [[nodiscard]] const Plan& current_plan() const noexcept;
  /// The current high-level net's engine; nullptr when no task runs.
  [[nodiscard]] const Engine* net_engine() const noexcept;
  /// The earliest time anything is due (a delay in the high-level or a process net).
  [[nodiscard]] std::optional<Time> next_deadline() const noexcept;

  void add_observer(TaskObserver& observer);
  void remove_observer(const TaskObserver& observer) noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal
