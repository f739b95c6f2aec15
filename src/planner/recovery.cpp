#include "tripodal/planner/recovery.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <optional>
#include <system_error>

#include "tripodal/core/net_loader.hpp"
#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal {

namespace {

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

using KnownProcess = std::function<bool(std::string_view)>;

RecoveryPolicy parse(const std::string& text, const std::string& file, const KnownProcess& is_known_process,
                     std::vector<std::filesystem::path>& chain);

// `include: [FILE, ...]`: the rules of other files (relative to this one), after this file's own,
// so that a robot's file shares a family's rules (charging) and adds its own (its devices' link).
// The first rule that matches decides: this file's rules win over the included ones.
void read_includes(const YAML::Node& list, const std::string& file, yaml::Reader& r, const KnownProcess& is_known_process,
                   std::vector<std::filesystem::path>& chain, std::vector<RecoveryRule>& rules) {
  if (!r.expect_list(list, "'include'")) return;
  for (const auto& item : list) {
    const std::optional<std::string> name = r.text(item, "an included recovery rules file", true);
    if (!name) continue;
    std::filesystem::path path = *name;
    if (path.is_relative()) path = std::filesystem::path(file).parent_path() / path;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
      r.error(item, "include: no recovery rules file '" + path.string() + "'");
      continue;
    }
    const std::filesystem::path canonical = std::filesystem::weakly_canonical(path, ec);
    if (std::find(chain.begin(), chain.end(), canonical) != chain.end()) {
      std::string cycle;
      for (const auto& f : chain) cycle += f.filename().string() + " -> ";
      r.error(item, "include: '" + path.string() + "' includes itself (" + cycle + canonical.filename().string() + ")");
      continue;
    }
    try {
      const RecoveryPolicy included = parse(yaml::read_file(path), path.string(), is_known_process, chain);
      rules.insert(rules.end(), included.rules().begin(), included.rules().end());
    } catch (const ConfigError& e) {
      r.diagnostics().append(e.diagnostics());
    }
  }
}

RecoveryPolicy walk(const std::string& text, const std::string& file, const KnownProcess& is_known_process,
                    std::vector<std::filesystem::path>& chain) {
  const YAML::Node root = yaml::parse(text, file);
  Diagnostics d;
  yaml::Reader r(file, d);
  std::vector<RecoveryRule> rules;
  if (!r.expect_keys(root, {"recovery", "include"}, "the recovery rules file")) throw ConfigError(d);
  // A file of includes only (a robot that adds nothing of its own) needs no `recovery:`.
  const YAML::Node list = root["include"] && !root["recovery"]
                              ? YAML::Node(YAML::NodeType::Sequence)
                              : r.require(root, "recovery", "the recovery rules file", "a list of rules");
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
      if (auto a = r.choice(v, "'then'", {"retry", "skip", "abort", "end"})) {
        rule.then = *a == "retry"  ? RecoveryAction::retry
                    : *a == "skip" ? RecoveryAction::skip
                    : *a == "end"  ? RecoveryAction::end
                                   : RecoveryAction::abort;
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
        const auto process = r.key(step_kv.first, "an inserted step (the process name)");
        if (!process) continue;
        ProcessStep step{*process, {}};
        if (is_known_process && !is_known_process(step.process)) r.error(step_kv.first, "unknown process '" + step.process + "'");
        if (step_kv.second.IsMap()) {
          for (const auto& p : step_kv.second) {
            const auto name = r.key(p.first, "the parameters of '" + step.process + "'");
            if (!name) continue;
            if (auto value = r.text(p.second, "parameter '" + *name + "'")) step.params.push_back({*name, *value, r.at(p.second)});
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
  if (const YAML::Node includes = root["include"]) read_includes(includes, file, r, is_known_process, chain, rules);
  if (d.has_errors()) throw ConfigError(d);
  return RecoveryPolicy(std::move(rules));
}

RecoveryPolicy parse(const std::string& text, const std::string& file, const KnownProcess& is_known_process,
                     std::vector<std::filesystem::path>& chain) {
  std::error_code ec;
  chain.push_back(std::filesystem::weakly_canonical(file, ec));
  try {
    RecoveryPolicy out = yaml::guarded(file, [&] { return walk(text, file, is_known_process, chain); });
    chain.pop_back();
    return out;
  } catch (...) {
    chain.pop_back();
    throw;
  }
}

RecoveryPolicy parse(const std::string& text, const std::string& file, const KnownProcess& is_known_process) {
  std::vector<std::filesystem::path> chain;
  return parse(text, file, is_known_process, chain);
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
             (rule.then == RecoveryAction::retry  ? "retry"
              : rule.then == RecoveryAction::skip ? "skip"
              : rule.then == RecoveryAction::end  ? "end the task"
                                                  : "abort") +
             " (" + std::to_string(times_fired + 1) + "/" + std::to_string(rule.max_retries) + ")";
  return d;
}

Plan RecoveryPolicy::remaining_plan(const Plan& plan, std::size_t failed_stage, const RecoveryDecision& decision) {
  Plan out;
  out.task = plan.task;
  out.command = plan.command;
  if (decision.action == RecoveryAction::abort || failed_stage >= plan.stages.size()) return out;
  for (const auto& step : decision.insert) out.stages.push_back(PlanStage{{step}});
  const std::size_t from = decision.action == RecoveryAction::retry ? failed_stage
                           : decision.action == RecoveryAction::end ? plan.stages.size()
                                                                    : failed_stage + 1;
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
