// Internal: the compile step the engine (src/core/engine.cpp) and the analyser
// (src/analysis/compiled_net.cpp) share, so that both read a net the same way: each transition's
// arcs folded, per place, into one bound the marking must satisfy and the tokens a firing takes
// and gives, and the conflict order in which enabled transitions are chosen.
#pragma once

#include <limits>
#include <vector>

#include "tripodal/core/engine.hpp"
#include "tripodal/core/petri_net.hpp"

namespace tripodal::detail {

/// A transition's enabling condition on one place: lo <= marking <= hi. Input and read arcs
/// raise lo, inhibitor arcs and the place's capacity (after the firing's net gain) lower hi; a
/// gain beyond the capacity gives lo > hi, a transition that can never fire.
struct PlaceBound {
  PlaceIndex place = 0;
  Tokens lo = 0;
  Tokens hi = std::numeric_limits<Tokens>::max();
};

struct FoldOptions {
  /// false drops capacities and inhibitor arcs: the monotone over-approximation that coverability
  /// (Karp-Miller) needs.
  bool capacities_and_inhibitors = true;
};

/// Appends the transition's bounds and its changes (every place an input or output arc touches,
/// also when it takes as many tokens as it gives), each in place order.
void fold_transition(const PetriNet& net, const Transition& transition, FoldOptions options,
                     std::vector<PlaceBound>& bounds, std::vector<PlaceChange>& changes);

/// Every transition, in conflict order: priority descending, then declaration order.
[[nodiscard]] std::vector<TransitionIndex> conflict_order(const PetriNet& net);

}  // namespace tripodal::detail
