#include "tripodal/planner/recovery.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "tripodal/core/net_loader.hpp"
#include "yaml_util.hpp"

namespace tripodal {

namespace {

using detail::kind_name;
using detail::where;

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

RecoveryPolicy parse(const std::string& text, const std::string& file,
                     const std::function<bool(std::string_view)>& is_known_process) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(SourceLocation{file, e.mark.line + 1, e.mark.column + 1}, e.msg);
  }
  Diagnostics d;
  std::vector<RecoveryRule> rules;
  if (!root.IsMap() || !root["recovery"] || !root["recovery"].IsSequence()) {
    d.error(where(file, root), "expected a map with a 'recovery' list at the top level");
    throw ConfigError(d);
  }
  for (const auto& kv : root) {
    if (kv.first.as<std::string>() != "recovery") {
      d.error(where(file, kv.first), "unknown key '" + kv.first.as<std::string>() + "'; expected: recovery");
    }
  }
  for (const auto& r : root["recovery"]) {
    RecoveryRule rule;
    rule.where = where(file, r);
    if (!r.IsMap()) {
      d.error(rule.where, "a recovery rule must be a map with fault, insert, then, max_retries; not " + kind_name(r));
      continue;
    }
    for (const auto& kv : r) {
      const auto key = kv.first.as<std::string>();
      const YAML::Node v = kv.second;
      if (key == "fault" && v.IsScalar()) {
        rule.fault = v.as<std::string>();
      } else if (key == "process" && v.IsScalar()) {
        rule.process = v.as<std::string>();
        if (is_known_process && !is_known_process(rule.process)) d.error(where(file, v), "unknown process '" + rule.process + "'");
      } else if (key == "then" && v.IsScalar()) {
        const auto a = v.as<std::string>();
        if (a == "retry") rule.then = RecoveryAction::retry;
        else if (a == "skip") rule.then = RecoveryAction::skip;
        else if (a == "abort") rule.then = RecoveryAction::abort;
        else d.error(where(file, v), "unknown action '" + a + "'; expected one of: retry, skip, abort");
      } else if (key == "max_retries" && v.IsScalar()) {
        int n = -1;
        if (!YAML::convert<int>::decode(v, n) || n < 0) {
          d.error(where(file, v), "max_retries must be a whole number >= 0, got '" + v.as<std::string>() + "'");
        } else {
          rule.max_retries = n;
        }
      } else if (key == "insert" && v.IsSequence()) {
        for (const auto& s : v) {
          if (!s.IsMap() || s.size() != 1) {
            d.error(where(file, s), "an inserted step must be a map with one key, the process name: {PrGlobalLocalization: {}}");
            continue;
          }
          const auto step_kv = *s.begin();
          ProcessStep step{step_kv.first.as<std::string>(), {}};
          if (is_known_process && !is_known_process(step.process)) {
            d.error(where(file, step_kv.first), "unknown process '" + step.process + "'");
          }
          if (step_kv.second.IsMap()) {
            for (const auto& p : step_kv.second) {
              if (!p.second.IsScalar()) {
                d.error(where(file, p.second), "parameter '" + p.first.as<std::string>() + "' must be a text");
                continue;
              }
              step.params.push_back({p.first.as<std::string>(), p.second.as<std::string>(), where(file, p.second)});
            }
          } else if (!step_kv.second.IsNull()) {
            d.error(where(file, step_kv.second), "parameters of '" + step.process + "' must be a map");
          }
          rule.insert.push_back(std::move(step));
        }
      } else if (key == "fault" || key == "process" || key == "then" || key == "max_retries" || key == "insert") {
        d.error(where(file, v), "'" + key + "' has the wrong form (" + kind_name(v) + ")");
      } else {
        d.error(where(file, kv.first), "unknown key '" + key + "' in a recovery rule; expected: fault, process, insert, then, max_retries");
      }
    }
    if (rule.fault.empty()) d.error(rule.where, "recovery rule without 'fault' (the fault message it handles)");
    rules.push_back(std::move(rule));
  }
  if (d.has_errors()) throw ConfigError(d);
  return RecoveryPolicy(std::move(rules));
}

}  // namespace

RecoveryPolicy RecoveryPolicy::load(const std::filesystem::path& file,
                                    const std::function<bool(std::string_view)>& is_known_process) {
  std::ifstream in(file);
  if (!in) throw ConfigError(SourceLocation{file.string(), 0, 0}, "cannot open recovery rules file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), file.string(), is_known_process);
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

std::vector<std::string> postable_fault_messages(const PetriNet& net) {
  std::vector<std::string> out;
  const std::vector<bool> markable = structurally_markable(net);
  for (std::size_t i = 0; i < net.places().size(); ++i) {
    const Place& p = net.places()[i];
    if (p.outcome != Outcome::fault || !markable[i]) continue;
    if (std::find(out.begin(), out.end(), p.fault_message) == out.end()) out.push_back(p.fault_message);
  }
  return out;
}

bool is_supervisor_fault_message(std::string_view message) noexcept {
  const auto starts = [&](std::string_view prefix) { return message.substr(0, prefix.size()) == prefix; };
  const auto failed = message.find(" failed: ");
  return starts("stopped: ") || ((starts("behavior ") || starts("module ")) && failed != std::string_view::npos);
}

void check_recovery_rules(const RecoveryPolicy& policy, std::span<const ProcessNet> nets, Diagnostics& diagnostics) {
  std::vector<std::pair<std::string, std::vector<std::string>>> posts;  // process -> its messages
  for (const ProcessNet& p : nets) {
    if (p.net != nullptr) posts.emplace_back(p.process, postable_fault_messages(*p.net));
  }
  const auto has_net = [&](std::string_view process) {
    return std::any_of(posts.begin(), posts.end(), [&](const auto& e) { return e.first == process; });
  };
  // "\"localization fault\" (PrAutoMove, PrCleaning), ..." for the processes `of` accepts
  const auto what_they_post = [&](const std::function<bool(const std::string&)>& of) {
    std::vector<std::pair<std::string, std::string>> seen;  // message, processes
    for (const auto& [process, messages] : posts) {
      if (!of(process)) continue;
      for (const std::string& m : messages) {
        auto it = std::find_if(seen.begin(), seen.end(), [&](const auto& e) { return iequals(e.first, m); });
        if (it == seen.end()) seen.emplace_back(m, process);
        else it->second += ", " + process;
      }
    }
    std::string text;
    for (const auto& [m, processes] : seen) text += (text.empty() ? "\"" : ", \"") + m + "\" (" + processes + ")";
    return text.empty() ? std::string("no fault message at all") : text;
  };
  for (const RecoveryRule& rule : policy.rules()) {
    const std::string which = "recovery rule for \"" + rule.fault + "\"" + (rule.process.empty() ? "" : " of " + rule.process);
    if (!rule.process.empty() && !has_net(rule.process)) {
      diagnostics.error(rule.where, which + " names process '" + rule.process + "', which has no net here");
    } else if (!is_supervisor_fault_message(rule.fault)) {
      const auto applies = [&](const std::string& process) { return rule.process.empty() || process == rule.process; };
      const bool posted = std::any_of(posts.begin(), posts.end(), [&](const auto& e) {
        return applies(e.first) &&
               std::any_of(e.second.begin(), e.second.end(), [&](const std::string& m) { return iequals(m, rule.fault); });
      });
      if (!posted) {
        diagnostics.error(rule.where, which + " can never match: " +
                                          (rule.process.empty() ? "no net posts this fault message (the nets post "
                                                                : "the net of " + rule.process +
                                                                      " does not post this fault message (it posts ") +
                                          what_they_post(applies) + ")");
      }
    }
    for (const ProcessStep& step : rule.insert) {
      if (!has_net(step.process)) {
        diagnostics.error(rule.where, which + " inserts process '" + step.process + "', which has no net here");
      }
    }
  }
}

void check_recovery_file(const std::filesystem::path& rules, std::span<const PetriNet> nets, Diagnostics& diagnostics) {
  std::vector<ProcessNet> processes;
  for (const PetriNet& n : nets) {
    if (n.level == NetLevel::low) processes.push_back({n.id, &n});
  }
  try {
    check_recovery_rules(RecoveryPolicy::load(rules), processes, diagnostics);
  } catch (const ConfigError& e) {
    diagnostics.append(e.diagnostics());
  }
}

}  // namespace tripodal
