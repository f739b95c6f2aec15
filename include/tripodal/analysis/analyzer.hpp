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

/// A place the net may fill without end: firing `prefix` from the initial marking, then `pump`,
/// gives a marking that covers the one after `prefix` with more tokens in `place`. `rounds`
/// further repetitions of `pump` were replayed under the analysis semantics, each growing the
/// place again (0: the repetition could not be confirmed, the growth is only suspected).
struct GrowthWitness {
  PlaceIndex place = 0;
  std::vector<TransitionIndex> prefix;
  std::vector<TransitionIndex> pump;
  Tokens before = 0;  ///< tokens in `place` after `prefix`
  Tokens after = 0;   ///< ... after `prefix`, `pump` and the replayed rounds
  std::size_t rounds = 0;
  [[nodiscard]] bool confirmed() const noexcept { return rounds > 0; }
};

/// A place binding a behavior (or a process) that reaches two tokens: the behavior is started
/// twice, which the supervisor cannot do. `witness` is the first such marking in BFS order.
struct DoubleStart {
  PlaceIndex place = 0;
  Witness witness;
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

  /// Places binding a behavior or process seen with two tokens (an error: started twice).
  std::vector<DoubleStart> double_started;
  /// Set when the exploration was cut short and a pumping cycle was found on its deepest path.
  std::optional<GrowthWitness> growth;
  /// Facts read by guards the parameters leave undecided: every verdict holds under the
  /// assumption that these facts can take any value at any time (sorted, each once).
  std::vector<std::string> assumed_facts;
  /// Per transition: its guard is false for these parameters whatever the facts.
  std::vector<TransitionIndex> guard_false;

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

  /// Complete, no deadlock, bounded, no behavior started twice, and the outcome check passed or
  /// does not apply.
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
  /// The parameter sets the net is used with (`--param`, `--params FILE`, a robot profile's
  /// process entries): each is checked; parameters a set leaves out take their defaults, or,
  /// without one, every value their guards name. Empty: the defaults only.
  std::vector<ParameterValues> parameter_sets;
  /// Native low-level nets are process nets: the supervisor ends them at an outcome place, so a
  /// net without one is an error. Applies to low-level nets under engine semantics; false for
  /// nets written for other tools (PNML).
  bool process_net = true;
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

struct BehaviourCheckResult {
  bool checked = false;  ///< every check ran to completion and found nothing (what check_behaviour returns)
  /// Facts the verdict treats as free (union over the parameter sets): "OK under the assumption
  /// that facts X, Y can take any value".
  std::vector<std::string> assumed_facts;
  std::size_t parameter_sets = 0;  ///< parameter combinations checked
};

/// check_behaviour with what the verdict rests on. Besides the errors above: a place binding a
/// behavior or process that can hold two tokens (started twice), a place that grows without end
/// (a pumping cycle, confirmed by replaying it), and a process net without an outcome place are
/// errors; a transition that fires for none of the default parameter sets (parameter_sets empty)
/// is a warning.
BehaviourCheckResult check_behaviour_detailed(const PetriNet& net, Diagnostics& diagnostics,
                                              const BehaviourCheckOptions& options = {});

/// "the assumption that facts battery_low, docked can take any value" (empty: nothing assumed).
[[nodiscard]] std::string assumption_text(const std::vector<std::string>& facts);

/// The default semantics for a file: interleaving for PNML (written for plain P/T tools), engine
/// for tripodal's native XML. Decided by extension, then by a <pnml root element in `head`.
[[nodiscard]] Semantics default_semantics_for(std::string_view file_name, std::string_view head);

}  // namespace tripodal::analysis
