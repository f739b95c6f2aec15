// The behavioural verdict on a configuration net before it runs: reachability graph, deadlocks
// with shortest paths, bounds and safeness (with Karp–Miller for unboundedness), dead
// transitions, never-marked places, the outcome check and invariants, as one report with a
// human-readable and a JSON form. Behind `tripodal-net analyze` and `tripodal-net check`.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "tripodal/analysis/coverability.hpp"
#include "tripodal/analysis/invariants.hpp"
#include "tripodal/analysis/state_space.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/core/petri_net.hpp"

namespace tripodal::analysis {

/// Default of AnalysisOptions::max_structural_size (`--max-structural-size`).
inline constexpr std::size_t kMaxStructuralSize = 1'000;

struct AnalysisOptions {
  Semantics semantics = Semantics::engine;
  ParameterValues parameters;           ///< process parameters (defaults applied for the rest)
  std::size_t max_states = 5'000'000;   ///< stop the exploration here (partial report)
  std::size_t max_memory_bytes = std::size_t{2} << 30;
  bool stop_at_outcome = true;          ///< outcome markings are terminal, as for the supervisor
  std::size_t max_examples = 10;        ///< deadlocks / stuck markings listed with their paths
  std::size_t max_invariant_rows = 20'000;
  std::size_t max_coverability_nodes = 200'000;
  /// Places + transitions above which invariants and the Karp–Miller search are skipped (a note in
  /// the report): both are superlinear in the net's size (Farkas' rows hold a place and a
  /// transition column each; Karp–Miller compares every node with its ancestors), while the
  /// exploration alone is linear in the states times the marked places.
  std::size_t max_structural_size = kMaxStructuralSize;
  bool invariants = true;               ///< compute place and transition invariants
  const Clock* clock = nullptr;         ///< times the exploration; nullptr: a SteadyClock
};

enum class Verdict { pass, fail, unknown, not_applicable };

[[nodiscard]] std::string_view to_string(Verdict v) noexcept;

/// A reachable marking and a shortest firing sequence from the initial marking to it.
struct Witness {
  StateId state = 0;
  Marking marking;
  std::vector<TransitionIndex> path;
};

enum class BoundKind {
  exact,      ///< the largest count over the complete reachability graph
  unbounded,  ///< proved by Karp–Miller
  at_least,   ///< exploration incomplete: the largest count seen so far
};

struct PlaceBound {
  Tokens max_seen = 0;
  BoundKind kind = BoundKind::exact;
  std::optional<Tokens> structural;  ///< from place invariants or the capacity
  bool may_be_unbounded = false;     ///< Karp–Miller over-approximation put an omega here
};

struct AnalysisReport {
  std::string net_id;
  std::size_t places = 0;
  std::size_t transitions = 0;
  Semantics semantics = Semantics::engine;
  ParameterValues parameters;  ///< as given (defaults are not listed)

  // reachability graph
  std::size_t states = 0;
  std::size_t edges = 0;
  std::size_t expanded = 0;
  StopReason stop = StopReason::complete;
  std::size_t max_states = 0;
  std::size_t max_memory_bytes = 0;
  double exploration_s = 0.0;
  std::size_t memory_bytes = 0;
  double bytes_per_state = 0.0;
  std::size_t bytes_per_marking = 0;

  // deadlocks (expanded states where nothing can fire and no outcome place is marked)
  std::size_t deadlock_count = 0;
  std::vector<Witness> deadlocks;  ///< the first max_examples, shortest paths first

  // bounds
  std::vector<PlaceBound> bounds;
  Verdict bounded = Verdict::unknown;  ///< pass: every place bounded
  Verdict safe = Verdict::unknown;     ///< pass: every place holds at most one token
  bool coverability_ran = false;
  CoverabilityResult coverability;

  std::vector<TransitionIndex> dead_transitions;  ///< never fired (seen so far if incomplete)
  std::vector<PlaceIndex> never_marked;

  // outcome check
  Verdict outcome = Verdict::not_applicable;  ///< not_applicable: the net has no outcome place
  std::size_t outcome_states = 0;
  std::size_t stuck_count = 0;     ///< reachable markings from which no outcome can be reached
  std::vector<Witness> stuck;      ///< the first max_examples

  // structure
  std::size_t max_structural_size = 0;
  bool structure_skipped = false;  ///< the net exceeds max_structural_size: no invariants, no Karp–Miller
  bool invariants_computed = false;
  InvariantBasis p_invariants;
  InvariantBasis t_invariants;

  /// Complete, no deadlock, bounded, and the outcome check passed or does not apply.
  [[nodiscard]] bool ok() const noexcept;
  [[nodiscard]] bool complete() const noexcept { return stop == StopReason::complete; }
};

/// Runs every analysis. Throws ConfigError for bad parameters or guards reading undeclared names.
[[nodiscard]] AnalysisReport analyze(const PetriNet& net, const AnalysisOptions& options = {});

/// Why an exploration stopped short, naming the limit and the option that raises it
/// ("more than 200000 reachable states: the exploration stopped at the limit of 200000 states;
/// raise it with --max-states N").
[[nodiscard]] std::string incomplete_reason(const AnalysisReport& report);

/// The report for a person: sections in a fixed order, paths as transition ids with events.
[[nodiscard]] std::string format_text(const AnalysisReport& report, const PetriNet& net);
/// The report as one JSON object (schema in docs/analysis.md).
[[nodiscard]] std::string format_json(const AnalysisReport& report, const PetriNet& net);

/// Parses "K=V" with V typed by the net's declaration of parameter K; throws ConfigError
/// ("unknown parameter", "expected a number for ...").
[[nodiscard]] ParameterValues parse_parameter_assignments(const PetriNet& net, const std::vector<std::string>& kv);

}  // namespace tripodal::analysis

namespace tripodal::analysis {

/// The state limit of the behavioural part of `tripodal-net check`: larger nets are reported as
/// not checked (a note naming the limit and --max-states), never as failing; `tripodal-net
/// analyze` has a larger default.
inline constexpr std::size_t kCheckStateLimit = 200'000;
/// Parameters without defaults are checked with every combination of the values their guards
/// name, up to this many combinations (more: a note, not checked).
inline constexpr std::size_t kCheckParameterCombinations = 16;

struct BehaviourCheckOptions {
  Semantics semantics = Semantics::engine;
  std::size_t max_states = kCheckStateLimit;            ///< `tripodal-net check --max-states`
  std::size_t max_memory_bytes = std::size_t{2} << 30;  ///< `tripodal-net check --max-memory-mb`
};

/// What `tripodal-net check` runs on a net that loaded: reachable deadlocks and markings from
/// which no outcome can be reached become errors located at the net (with the firing sequence),
/// a net too large gets a note. A parameter without a default is given, in turn, each value its
/// guards compare it with (both values for a boolean; a number also one below and one above each
/// literal); the diagnostics then start "with NAME=VALUE: ". Returns true when every check ran to
/// completion and found nothing.
bool check_behaviour(const PetriNet& net, Diagnostics& diagnostics, const BehaviourCheckOptions& options = {});

/// The default semantics for a file: interleaving for PNML (written for plain P/T tools), engine
/// for tripodal's native XML. Decided by extension, then by a <pnml root element in `head`.
[[nodiscard]] Semantics default_semantics_for(std::string_view file_name, std::string_view head);

}  // namespace tripodal::analysis
