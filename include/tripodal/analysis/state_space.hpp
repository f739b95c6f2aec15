// Reachability graph of a configuration net, explored breadth-first over a compact state store
// (markings bit-packed into a contiguous arena, an open-addressing hash set of their indices).
// The analysis layer of tripodal-net analyze/check builds on it; it has no robot dependencies.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "tripodal/core/engine.hpp"
#include "tripodal/core/petri_net.hpp"

namespace tripodal::analysis {

/// How the environment and the engine's choice rules are modelled (docs/analysis.md).
enum class Semantics {
  /// The engine's rules: an enabled immediate transition is urgent and the highest in conflict
  /// order fires first; events and elapsed delays are free choices; guards reading facts may be
  /// true or false. Default for native nets.
  engine,
  /// Plain place/transition semantics: any enabled transition may fire (priorities, urgency and
  /// events ignored). Default for PNML nets written for other tools.
  interleaving,
};

[[nodiscard]] std::string_view to_string(Semantics s) noexcept;

enum class StopReason {
  complete,        ///< every reachable state was expanded
  max_states,      ///< ExploreOptions::max_states reached
  max_memory,      ///< the store would have grown past ExploreOptions::max_memory_bytes
  token_overflow,  ///< a place would exceed 2^32-1 tokens
};

[[nodiscard]] std::string_view to_string(StopReason r) noexcept;

using StateId = std::uint32_t;

/// How stored markings are laid out (docs/analysis.md, "Reachability graph").
enum class MarkingStore {
  automatic,  ///< dense for small nets; sparse when a dense marking would be larger than 64 bytes
              ///< and a sparse one much smaller
  dense,      ///< every place a bit field: cheapest for small nets, O(places) work per state
  sparse,     ///< only the marked places: O(marked places + their transitions) per state
};

struct ExploreOptions {
  Semantics semantics = Semantics::engine;
  ParameterValues parameters;   ///< process parameters guards are evaluated with
  bool stop_at_outcome = true;  ///< outcome markings are terminal (the supervisor ends the net)
  bool keep_edges = false;      ///< store successor lists (the outcome check needs them)
  std::size_t max_states = 5'000'000;
  std::size_t max_memory_bytes = std::size_t{2} << 30;
  /// Known upper bounds per place (from invariants, capacities or coverability) used to size the
  /// packed fields; empty or nullopt: start narrow and widen (re-exploring) when exceeded.
  std::vector<std::optional<Tokens>> place_bounds;
  MarkingStore store = MarkingStore::automatic;
};

/// The explored graph. States are numbered in breadth-first order from 0 (the initial marking),
/// so the parent chain of a state is a shortest firing sequence to it.
class StateSpace {
 public:
  StateSpace();
  ~StateSpace();
  StateSpace(StateSpace&&) noexcept;
  StateSpace& operator=(StateSpace&&) noexcept;

  [[nodiscard]] std::size_t states() const noexcept;    ///< stored (discovered) states
  [[nodiscard]] std::size_t expanded() const noexcept;  ///< states whose successors were generated
  [[nodiscard]] std::size_t edges() const noexcept;     ///< firings from expanded states
  [[nodiscard]] StopReason stop_reason() const noexcept;
  [[nodiscard]] bool complete() const noexcept { return stop_reason() == StopReason::complete; }
  [[nodiscard]] Marking marking(StateId s) const;
  /// Transitions fired from the initial marking to s, shortest first found.
  [[nodiscard]] std::vector<TransitionIndex> path_to(StateId s) const;
  /// Successors of an expanded state (only with ExploreOptions::keep_edges).
  [[nodiscard]] std::span<const StateId> successors(StateId s) const;
  [[nodiscard]] bool has_edges() const noexcept;
  [[nodiscard]] std::optional<StateId> find(const Marking& m) const;

  /// Largest count per place over the stored states.
  [[nodiscard]] const std::vector<Tokens>& max_tokens() const noexcept;
  /// Per transition: fired on at least one edge.
  [[nodiscard]] const std::vector<std::uint8_t>& fired() const noexcept;
  /// Expanded states where nothing can fire and no outcome place is marked, in BFS order.
  [[nodiscard]] const std::vector<StateId>& deadlocks() const noexcept;
  /// Stored states where an outcome place is marked.
  [[nodiscard]] const std::vector<StateId>& outcome_states() const noexcept;

  /// The packed marking in the arena; with the sparse store, the average over the stored states.
  [[nodiscard]] std::size_t bytes_per_marking() const noexcept;
  [[nodiscard]] bool sparse() const noexcept;  ///< the sparse store was used
  [[nodiscard]] std::size_t memory_bytes() const noexcept;       ///< arena, hash set, parents, edges
  [[nodiscard]] double bytes_per_state() const noexcept;
  [[nodiscard]] const std::vector<std::uint8_t>& bits_per_place() const noexcept;
  [[nodiscard]] std::size_t restarts() const noexcept;  ///< re-explorations after widening a field

  struct Impl;

 private:
  friend StateSpace explore(const PetriNet& net, const ExploreOptions& options);
  std::unique_ptr<Impl> impl_;
};

/// Explores the reachability graph breadth-first. Stops cleanly at the limits (stop_reason()).
/// Throws ConfigError for bad parameters or guards reading undeclared names.
[[nodiscard]] StateSpace explore(const PetriNet& net, const ExploreOptions& options = {});

}  // namespace tripodal::analysis
