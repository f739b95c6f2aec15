#include "tripodal/planner/lifecycle_recorder.hpp"

#include <fmt/format.h>


namespace tripodal {

namespace {

std::string step_text(const ProcessStep& s) {
  std::string out = s.process + "(";
  for (std::size_t i = 0; i < s.params.size(); ++i) out += (i ? ", " : "") + s.params[i].name + "=" + s.params[i].value;
  return out + ")";
}

std::string value_text(const Value& v) { return std::holds_alternative<std::string>(v) ? std::get<std::string>(v) : to_string(v); }

}  // namespace

std::string LifecycleRecorder::str() const {
  std::string out;
  for (const LifecycleEntry& e : entries_) out += fmt::format("{:>10} s  {}\n", format_seconds(e.time), e.text);
  return out;
}

void LifecycleRecorder::on_command_refused(std::string_view command, std::string_view answer, Time now) {
  add(now, "command refused: \"" + std::string(command) + "\": " + std::string(answer));
}
void LifecycleRecorder::on_task_started(const TaskReport& task, const Plan& plan, Time now) {
  add(now, "task " + task.task + " started (\"" + task.command + "\"): " + to_string(plan));
}
void LifecycleRecorder::on_process_started(const ProcessRecord& p) {
  add(p.started, "process " + p.run + " " + step_text(p.step) + " started");
}
void LifecycleRecorder::on_process_succeeded(const ProcessRecord& p) {
  add(p.finished.value_or(p.started), "process " + p.run + " " + p.step.process + " succeeded");
}
void LifecycleRecorder::on_process_failed(const ProcessRecord& p) {
  add(p.finished.value_or(p.started), "process " + p.run + " " + p.step.process + " failed: " + p.message);
}
void LifecycleRecorder::on_recovery(const RecoveryRecord& r) { add(r.time, "recovery: " + r.reason + "; plan: " + r.new_plan); }
void LifecycleRecorder::on_task_succeeded(const TaskReport& task) {
  add(task.finished.value_or(task.started), "task " + task.task + " succeeded");
}
void LifecycleRecorder::on_task_failed(const TaskReport& task) {
  add(task.finished.value_or(task.started), "task " + task.task + " failed: " + task.reason);
}

void LifecycleRecorder::on_behavior_activated(std::string_view run, std::string_view behavior, const ParameterValues& params, Time now) {
  if (!details_) return;
  std::string p;
  for (const auto& [k, v] : params) p += (p.empty() ? "" : ", ") + k + "=" + value_text(v);
  add(now, "  " + std::string(run) + " activate " + std::string(behavior) + "(" + p + ")");
}
void LifecycleRecorder::on_behavior_deactivated(std::string_view run, std::string_view behavior, Time now) {
  if (details_) add(now, "  " + std::string(run) + " deactivate " + std::string(behavior));
}
void LifecycleRecorder::on_firing(std::string_view run, const PetriNet& net, const Firing& f) {
  if (!details_) return;
  std::string text = "  " + std::string(run) + " " + net.id + " fire " + std::string(f.transition_id);
  if (!f.event.empty()) text += " [" + std::string(f.event) + "]";
  add(f.time, std::move(text));
}
void LifecycleRecorder::on_fault(std::string_view source, std::string_view reason, Time now) {
  if (details_) add(now, "  fault " + std::string(source) + ": " + std::string(reason));
}

void LifecycleRecorder::on_net_reloaded(std::string_view run, const CProcess& process, std::string_view marking, Time now) {
  add(now, "process " + std::string(run) + " " + process.name() + " net reloaded from " + process.net().where.file.str() +
               " at a quiet marking (" + std::string(marking) + ")");
}

}  // namespace tripodal
