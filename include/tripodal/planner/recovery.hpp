// Recovery rules of the deliberate layer: how the planner reorganizes the remaining plan when a
// process fails with a fault message ("localization fault" -> insert PrGlobalLocalization, then
// retry the failed module), with a retry limit after which the task fails with a report; and the
// check that every rule can match a fault some process net posts.
#pragma once

#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/petri_net.hpp"
#include "tripodal/planner/plan.hpp"
#include "tripodal/processes/recovery_rule.hpp"

namespace tripodal {

struct RecoveryDecision {
  RecoveryAction action = RecoveryAction::abort;
  std::vector<ProcessStep> insert;
  const RecoveryRule* rule = nullptr;  ///< the rule that decided; null when none applies
  std::string reason;                  ///< for the task report
};

class RecoveryPolicy {
 public:
  RecoveryPolicy() = default;
  explicit RecoveryPolicy(std::vector<RecoveryRule> rules) : rules_(std::move(rules)) {}

  /// Loads rules from YAML (`recovery:` list; docs/planner.md), then those of the files its
  /// `include:` list names (relative to it; a rule of the file itself wins); throws ConfigError
  /// with every error located (a missing or self-including file at its entry).
  static RecoveryPolicy load(const std::filesystem::path& file,
                             const std::function<bool(std::string_view)>& is_known_process = {});
  static RecoveryPolicy load_from_string(std::string_view yaml, std::string_view name,
                                         const std::function<bool(std::string_view)>& is_known_process = {});

  [[nodiscard]] const std::vector<RecoveryRule>& rules() const noexcept { return rules_; }

  /// Decides what to do about `failed` ending with `message`, when the first matching rule has
  /// already fired `times_fired` times in this task. The first rule that matches the message
  /// (and process, when given) decides; a process-specific rule listed first wins.
  [[nodiscard]] RecoveryDecision decide(const ProcessStep& failed, std::string_view message, int times_fired) const;

  /// Index of the rule that handles this fault, or -1.
  [[nodiscard]] int find_rule(const ProcessStep& failed, std::string_view message) const;

  /// The plan that remains after stage `failed_stage` of `plan` failed and `decision` was taken:
  /// the inserted processes followed by the failed stage (retry) or by the stages after it (skip);
  /// empty for abort.
  [[nodiscard]] static Plan remaining_plan(const Plan& plan, std::size_t failed_stage, const RecoveryDecision& decision);

 private:
  std::vector<RecoveryRule> rules_;
};

/// A process's low-level net, as the recovery check sees it.
struct ProcessNet {
  std::string process;  ///< the name rules use, e.g. "PrAutoMove"
  const PetriNet* net = nullptr;
};

/// The fault messages a process net can post: those of its fault places that some firing
/// sequence might mark (structurally_markable), each once, in place order.
[[nodiscard]] std::vector<std::string> postable_fault_messages(const PetriNet& net);

/// Whether the process supervisor itself makes this fault message, whatever the nets: "behavior
/// X failed: ..." (a failure the net does not consume), "module m failed: ...", "stopped: ...".
[[nodiscard]] bool is_supervisor_fault_message(std::string_view message) noexcept;

/// Checks recovery rules against the processes' nets and appends an error, located at the rule,
/// for every rule that can never do what it says: its fault message is posted by none of the
/// nets (by its process's net when the rule names a process; supervisor messages are not checked),
/// or the process it names or inserts has no net among `nets`. Each message says what the nets
/// can post.
void check_recovery_rules(const RecoveryPolicy& policy, std::span<const ProcessNet> nets, Diagnostics& diagnostics);

/// check_recovery_rules for a rules file and loose nets (`tripodal-net check --recovery`): each
/// low-level net is the net of the process its id names. A file that does not load gives its
/// errors instead.
void check_recovery_file(const std::filesystem::path& rules, std::span<const PetriNet> nets, Diagnostics& diagnostics);

}  // namespace tripodal
