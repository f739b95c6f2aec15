#include "tripodal/planner/recovery.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>

#include "../common/yaml_reader.hpp"

namespace tripodal {

namespace {

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

RecoveryPolicy parse(const std::string& text, const std::string& file,
                     const std::function<bool(std::string_view)>& is_known_process) {
  const YAML::Node root = yaml::parse(text, file);
  Diagnostics d;
  yaml::Reader r(file, d);
  std::vector<RecoveryRule> rules;
  if (!r.expect_keys(root, {"recovery"}, "the recovery rules file")) throw ConfigError(d);
  const YAML::Node list = r.require(root, "recovery", "the recovery rules file", "a list of rules");
  if (!list || !r.expect_list(list, "'recovery'")) throw ConfigError(d);
  for (const auto& rule_node : list) {
    RecoveryRule rule;
    rule.where = r.at(rule_node);
    if (!r.expect_keys(rule_node, {"fault", "process", "insert", "then", "max_retries"}, "a recovery rule")) continue;
    if (const YAML::Node v = rule_node["fault"]) rule.fault = r.text(v, "'fault'").value_or("");
    if (const YAML::Node v = rule_node["process"]) {
      rule.process = r.text(v, "'process'").value_or("");
      if (!rule.process.empty() && is_known_process && !is_known_process(rule.process)) {
        r.error(v, "unknown process '" + rule.process + "'");
      }
    }
    if (const YAML::Node v = rule_node["then"]) {
      if (auto a = r.choice(v, "'then'", {"retry", "skip", "abort"})) {
        rule.then = *a == "retry" ? RecoveryAction::retry : *a == "skip" ? RecoveryAction::skip : RecoveryAction::abort;
      }
    }
    if (const YAML::Node v = rule_node["max_retries"]) {
      if (auto n = r.integer(v, "'max_retries'", 0, 1000000)) rule.max_retries = static_cast<int>(*n);
    }
    if (const YAML::Node v = rule_node["insert"]; v && r.expect_list(v, "'insert'")) {
      for (const auto& s : v) {
        if (!s.IsMap() || s.size() != 1) {
          r.error(s, "an inserted step must be a map with one key, the process name: {PrGlobalLocalization: {}}");
          continue;
        }
        const auto step_kv = *s.begin();
        ProcessStep step{step_kv.first.as<std::string>(), {}};
        if (is_known_process && !is_known_process(step.process)) r.error(step_kv.first, "unknown process '" + step.process + "'");
        if (step_kv.second.IsMap()) {
          for (const auto& p : step_kv.second) {
            const std::string name = p.first.as<std::string>();
            if (auto value = r.text(p.second, "parameter '" + name + "'")) step.params.push_back({name, *value, r.at(p.second)});
          }
        } else if (!step_kv.second.IsNull()) {
          r.expect_map(step_kv.second, "the parameters of '" + step.process + "'");
        }
        rule.insert.push_back(std::move(step));
      }
    }
    if (!rule_node["fault"]) r.error(rule_node, "a recovery rule: missing 'fault' (the fault message it handles)");
    rules.push_back(std::move(rule));
  }
  if (d.has_errors()) throw ConfigError(d);
  return RecoveryPolicy(std::move(rules));
}

}  // namespace

RecoveryPolicy RecoveryPolicy::load(const std::filesystem::path& file,
                                    const std::function<bool(std::string_view)>& is_known_process) {
  return parse(yaml::read_file(file), file.string(), is_known_process);
}

RecoveryPolicy RecoveryPolicy::load_from_string(std::string_view yaml, std::string_view name,
                                                const std::function<bool(std::string_view)>& is_known_process) {
  return parse(std::string(yaml), std::string(name), is_known_process);
}

int RecoveryPolicy::find_rule(const ProcessStep& failed, std::string_view message) const {
  for (std::size_t i = 0; i < rules_.size(); ++i) {
    const auto& r = rules_[i];
    if (iequals(r.fault, message) && (r.process.empty() || r.process == failed.process)) return static_cast<int>(i);
  }
  return -1;
}

RecoveryDecision RecoveryPolicy::decide(const ProcessStep& failed, std::string_view message, int times_fired) const {
  RecoveryDecision d;
  const int i = find_rule(failed, message);
  if (i < 0) {
    d.reason = "no recovery rule for fault \"" + std::string(message) + "\" of " + failed.process;
    return d;
  }
  const RecoveryRule& rule = rules_[static_cast<std::size_t>(i)];
  d.rule = &rule;
  if (times_fired >= rule.max_retries) {
    d.reason = "retry limit reached: \"" + rule.fault + "\" recovered " + std::to_string(times_fired) + " time(s) (max_retries " +
               std::to_string(rule.max_retries) + "), " + failed.process + " failed again";
    return d;
  }
  d.action = rule.then;
  d.insert = rule.insert;
  std::string inserted;
  for (const auto& s : rule.insert) inserted += (inserted.empty() ? "" : ", ") + s.process;
  d.reason = "fault \"" + std::string(message) + "\" of " + failed.process + ": " +
             (inserted.empty() ? std::string() : "insert " + inserted + ", then ") +
             (rule.then == RecoveryAction::retry ? "retry" : rule.then == RecoveryAction::skip ? "skip" : "abort") + " (" +
             std::to_string(times_fired + 1) + "/" + std::to_string(rule.max_retries) + ")";
  return d;
}

Plan RecoveryPolicy::remaining_plan(const Plan& plan, std::size_t failed_stage, const RecoveryDecision& decision) {
  Plan out;
  out.task = plan.task;
  out.command = plan.command;
  if (decision.action == RecoveryAction::abort || failed_stage >= plan.stages.size()) return out;
  for (const auto& step : decision.insert) out.stages.push_back(PlanStage{{step}});
  const std::size_t from = decision.action == RecoveryAction::retry ? failed_stage : failed_stage + 1;
  for (std::size_t s = from; s < plan.stages.size(); ++s) out.stages.push_back(plan.stages[s]);
  return out;
}

}  // namespace tripodal
