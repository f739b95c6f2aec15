#include "net_compile.hpp"

#include <algorithm>
#include <map>

namespace tripodal::detail {

void fold_transition(const PetriNet& net, const Transition& transition, FoldOptions options,
                     std::vector<PlaceBound>& bounds, std::vector<PlaceChange>& changes) {
  // Ordered maps: a transition has a handful of arcs, and both lists come out in place order.
  std::map<PlaceIndex, PlaceChange> delta;
  std::map<PlaceIndex, PlaceBound> bound;
  auto bound_of = [&](PlaceIndex p) -> PlaceBound& {
    auto [it, inserted] = bound.try_emplace(p);
    if (inserted) it->second.place = p;
    return it->second;
  };
  for (const ArcRef& a : transition.inputs) {
    PlaceChange& d = delta[a.place];
    d.place = a.place;
    d.consumed += a.weight;
  }
  for (const ArcRef& a : transition.outputs) {
    PlaceChange& d = delta[a.place];
    d.place = a.place;
    d.produced += a.weight;
  }
  for (const auto& [p, d] : delta) {
    if (d.consumed > 0) bound_of(p).lo = std::max(bound_of(p).lo, d.consumed);
    const auto& cap = net.places()[p].capacity;
    if (cap && options.capacities_and_inhibitors && d.produced > d.consumed) {
      const Tokens gain = d.produced - d.consumed;
      PlaceBound& b = bound_of(p);
      if (gain > *cap) {
        b.lo = 1;  // can never fire: the gain alone exceeds the capacity
        b.hi = 0;
      } else {
        b.hi = std::min(b.hi, *cap - gain);
      }
    }
  }
  for (const ArcRef& a : transition.reads) bound_of(a.place).lo = std::max(bound_of(a.place).lo, a.weight);
  if (options.capacities_and_inhibitors) {
    for (const ArcRef& a : transition.inhibitors) bound_of(a.place).hi = std::min(bound_of(a.place).hi, a.weight - 1);
  }
  for (const auto& [p, b] : bound) bounds.push_back(b);
  for (const auto& [p, d] : delta) changes.push_back(d);
}

std::vector<TransitionIndex> conflict_order(const PetriNet& net) {
  const auto& transitions = net.transitions();
  std::vector<TransitionIndex> order(transitions.size());
  for (TransitionIndex t = 0; t < order.size(); ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(), [&](TransitionIndex a, TransitionIndex b) {
    return transitions[a].priority > transitions[b].priority;
  });
  return order;
}

}  // namespace tripodal::detail
