// LifecycleRecorder: keeps the task and process life cycle with times — task started, each process
// started/succeeded/failed, recoveries, task succeeded/failed — and optionally what the supervisor
// did inside the processes (behaviors activated and deactivated, firings, faults). For logs, tests
// (the same robot, task and events give the same trace) and reports.
#pragma once

#include <string>
#include <vector>

#include "tripodal/planner/planner.hpp"
#include "tripodal/processes/process_supervisor.hpp"

namespace tripodal {

struct LifecycleEntry {
  Time time{};
  std::string text;
};

class LifecycleRecorder final : public TaskObserver, public SupervisorObserver {
 public:
  /// `details`: also record behaviors, firings and faults seen by the supervisor.
  explicit LifecycleRecorder(bool details = false) : details_(details) {}

  [[nodiscard]] const std::vector<LifecycleEntry>& entries() const noexcept { return entries_; }
  /// One line per entry: "    12.300 s  process X1 PrCleaning(section=A) failed: localization fault".
  [[nodiscard]] std::string str() const;
  void clear() noexcept { entries_.clear(); }
  /// Adds a line from outside the planner and supervisor (e.g. the simulator's injected faults),
  /// so one log tells the whole story in time order.
  void note(Time t, std::string text) { add(t, std::move(text)); }

  // TaskObserver
  void on_command_refused(std::string_view command, std::string_view answer, Time now) override;
  void on_task_started(const TaskReport& task, const Plan& plan, Time now) override;
  void on_process_started(const ProcessRecord& p) override;
  void on_process_succeeded(const ProcessRecord& p) override;
  void on_process_failed(const ProcessRecord& p) override;
  void on_recovery(const RecoveryRecord& r) override;
  void on_task_succeeded(const TaskReport& task) override;
  void on_task_failed(const TaskReport& task) override;

  // SupervisorObserver (recorded only with details)
  void on_behavior_activated(std::string_view run, std::string_view behavior, const ParameterValues& params, Time now) override;
  void on_behavior_deactivated(std::string_view run, std::string_view behavior, Time now) override;
  void on_firing(std::string_view run, const PetriNet& net, const Firing& firing) override;
  void on_fault(std::string_view source, std::string_view reason, Time now) override;
  /// Recorded with or without details: the operator changed what a process does.
  void on_net_reloaded(std::string_view run, const CProcess& process, std::string_view marking, Time now) override;

 private:
  void add(Time t, std::string text) { entries_.push_back(LifecycleEntry{t, std::move(text)}); }
  bool details_;
  std::vector<LifecycleEntry> entries_;
};

}  // namespace tripodal
