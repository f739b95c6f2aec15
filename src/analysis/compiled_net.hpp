// Internal: a configuration net flattened for state-space search. Enabling conditions are folded
// into one lo <= m <= hi check per place (as the engine does), guards are classified once with
// the process parameters (true, false, or "may be true" when they read a fact), and the engine's
// choice rules (urgency of immediate transitions, priorities, one listener per event) are
// precomputed as rank orders.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tripodal/analysis/state_space.hpp"
#include "tripodal/core/petri_net.hpp"
#include "tripodal_core_internal/net_compile.hpp"

namespace tripodal::analysis::detail {

enum class Kind : std::uint8_t { immediate, delayed, event };
inline constexpr std::uint32_t kNoGroup = 0xFFFFFFFFU;
enum class GuardState : std::uint8_t { never, always, maybe };

// The engine's compile step (src/core/net_compile.hpp) gives both.
using Check = tripodal::detail::PlaceBound;
using Change = PlaceChange;

struct CompileOptions {
  Semantics semantics = Semantics::engine;
  /// Karp–Miller runs on a monotone over-approximation: inhibitor arcs and capacities dropped.
  bool monotone = false;
};

class CompiledNet {
 public:
  CompiledNet(const PetriNet& net, const ParameterValues& parameters, CompileOptions options);

  std::size_t places = 0;
  std::size_t transitions = 0;
  Semantics semantics = Semantics::engine;
  std::vector<Kind> kind;
  std::vector<GuardState> guard;
  std::vector<std::uint32_t> check_begin;  // CSR into checks
  std::vector<Check> checks;
  std::vector<std::uint32_t> change_begin;  // CSR into changes (places whose count changes)
  std::vector<Change> changes;
  std::vector<std::uint8_t> is_outcome;     // per place
  // Engine semantics: non-event transitions in conflict order, then per event its listeners.
  std::vector<TransitionIndex> urgent_order;
  std::vector<std::uint32_t> event_begin;
  std::vector<TransitionIndex> listeners;
  std::vector<std::uint8_t> decisive;       // per transition: enabled => nothing ranked below it fires
  // For searches over large nets, where walking every transition per marking costs O(T): a
  // transition needs a token on the place it watches (its first place with lo > 0), so only the
  // watchers of marked places and the unwatched transitions (lo = 0 everywhere) can be enabled.
  // rank is the transition's position in the walk of successors(); group is a listener's event
  // (kNoGroup for the others). Transitions whose guard is false are in neither list.
  std::vector<std::uint32_t> watch_begin;   // CSR per place into watchers
  std::vector<TransitionIndex> watchers;
  std::vector<TransitionIndex> unwatched;
  std::vector<std::uint32_t> rank;
  std::vector<std::uint32_t> group;

  [[nodiscard]] bool enabled(TransitionIndex t, const Tokens* m) const noexcept {
    if (guard[t] == GuardState::never) return false;
    for (std::uint32_t i = check_begin[t], e = check_begin[t + 1]; i < e; ++i) {
      const Check& c = checks[i];
      if (m[c.place] < c.lo || m[c.place] > c.hi) return false;
    }
    return true;
  }

  /// Calls emit(t) for every transition that may fire next in marking m, in a fixed order.
  template <typename Emit>
  void successors(const Tokens* m, Emit&& emit) const {
    if (semantics == Semantics::interleaving) {
      for (TransitionIndex t = 0; t < transitions; ++t) {
        if (enabled(t, m)) emit(t);
      }
      return;
    }
    // The engine fires the first ready transition in conflict order; a transition whose guard
    // reads a fact, or a delayed one (which may not be due yet), might not be ready, so the walk
    // goes on past it. Events are only processed in a settled marking.
    for (const TransitionIndex t : urgent_order) {
      if (!enabled(t, m)) continue;
      emit(t);
      if (decisive[t] != 0) return;
    }
    for (std::size_t e = 0; e + 1 < event_begin.size(); ++e) {
      for (std::uint32_t i = event_begin[e]; i < event_begin[e + 1]; ++i) {
        const TransitionIndex t = listeners[i];
        if (!enabled(t, m)) continue;
        emit(t);
        if (decisive[t] != 0) break;  // the event goes to it, never to a listener ranked below
      }
    }
  }

  /// successors() restricted to `candidates`, which must hold every transition that may be
  /// enabled in m (the watchers of its marked places and the unwatched ones) sorted by rank:
  /// emits the same transitions in the same order, in O(candidates) instead of O(T).
  template <typename Emit>
  void successors_among(const Tokens* m, const std::vector<TransitionIndex>& candidates, Emit&& emit) const {
    if (semantics == Semantics::interleaving) {
      for (const TransitionIndex t : candidates) {
        if (enabled(t, m)) emit(t);
      }
      return;
    }
    std::uint32_t taken = kNoGroup;  // the event a decisive listener took
    for (const TransitionIndex t : candidates) {
      if (group[t] == kNoGroup) {
        if (!enabled(t, m)) continue;
        emit(t);
        if (decisive[t] != 0) return;
        continue;
      }
      if (group[t] == taken || !enabled(t, m)) continue;
      emit(t);
      if (decisive[t] != 0) taken = group[t];
    }
  }
};

/// Each transition's guard with the parameters bound and the facts unknown (three-valued: a
/// conjunct false by the parameters alone makes the guard never true, whatever the facts).
std::vector<GuardState> classify_guards(const PetriNet& net, const std::vector<Value>& parameter_values);

/// Checks parameter values against the declarations (defaults applied, types, unknown names)
/// and that guards read only declared names; throws ConfigError listing every problem.
std::vector<Value> bind_parameters(const PetriNet& net, const ParameterValues& given);

}  // namespace tripodal::analysis::detail
