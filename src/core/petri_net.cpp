#include "tripodal/core/petri_net.hpp"

#include <stdexcept>

namespace tripodal {

void PetriNet::reserve(std::size_t places, std::size_t transitions) {
  places_.reserve(places);
  transitions_.reserve(transitions);
  ids_.reserve(places + transitions);
}

PlaceIndex PetriNet::add_place(Place p) {
  if (p.id.empty()) throw std::invalid_argument("place id must not be empty");
  if (ids_.count(p.id) != 0) throw std::invalid_argument("duplicate node id '" + p.id + "'");
  if (p.capacity && p.initial_tokens > *p.capacity) {
    throw std::invalid_argument("place '" + p.id + "' starts with more tokens than its capacity");
  }
  if (p.name.empty()) p.name = p.id;
  const auto index = static_cast<PlaceIndex>(places_.size());
  ids_.emplace(p.id, NodeRef{true, index});
  places_.push_back(std::move(p));
  return index;
}

TransitionIndex PetriNet::add_transition(Transition t) {
  if (t.id.empty()) throw std::invalid_argument("transition id must not be empty");
  if (ids_.count(t.id) != 0) throw std::invalid_argument("duplicate node id '" + t.id + "'");
  if (t.delay.count() < 0) throw std::invalid_argument("transition '" + t.id + "' has a negative delay");
  if (t.name.empty()) t.name = t.id;
  const auto index = static_cast<TransitionIndex>(transitions_.size());
  ids_.emplace(t.id, NodeRef{false, index});
  transitions_.push_back(std::move(t));
  return index;
}

void PetriNet::add_arc(std::string_view from_id, std::string_view to_id, Tokens weight, ArcKind kind,
                       SourceLocation arc_where) {
  if (weight == 0) throw std::invalid_argument("arc weight must be positive");
  // One look-up per end: loaders add tens of thousands of arcs.
  const auto from = ids_.find(from_id);
  const auto to = ids_.find(to_id);
  if (from == ids_.end()) throw std::invalid_argument("arc from unknown node '" + std::string(from_id) + "'");
  if (to == ids_.end()) throw std::invalid_argument("arc to unknown node '" + std::string(to_id) + "'");
  if (from->second.is_place && !to->second.is_place) {
    Transition& t = transitions_[to->second.index];
    ArcRef ref{from->second.index, weight, std::move(arc_where)};
    switch (kind) {
      case ArcKind::normal: t.inputs.push_back(std::move(ref)); break;
      case ArcKind::read: t.reads.push_back(std::move(ref)); break;
      case ArcKind::inhibitor: t.inhibitors.push_back(std::move(ref)); break;
    }
    return;
  }
  if (!from->second.is_place && to->second.is_place) {
    if (kind != ArcKind::normal) {
      throw std::invalid_argument("read and inhibitor arcs go from a place to a transition, not from '" +
                                  std::string(from_id) + "' to '" + std::string(to_id) + "'");
    }
    transitions_[from->second.index].outputs.push_back(ArcRef{to->second.index, weight, std::move(arc_where)});
    return;
  }
  throw std::invalid_argument("arc must connect a place and a transition: '" + std::string(from_id) + "' -> '" +
                              std::string(to_id) + "'");
}

std::optional<PlaceIndex> PetriNet::find_place(std::string_view node_id) const noexcept {
  const auto it = ids_.find(node_id);
  if (it == ids_.end() || !it->second.is_place) return std::nullopt;
  return it->second.index;
}

std::optional<TransitionIndex> PetriNet::find_transition(std::string_view node_id) const noexcept {
  const auto it = ids_.find(node_id);
  if (it == ids_.end() || it->second.is_place) return std::nullopt;
  return it->second.index;
}

const VariableDecl* PetriNet::find_parameter(std::string_view n) const noexcept {
  for (const auto& p : parameters) {
    if (p.name == n) return &p;
  }
  return nullptr;
}

const VariableDecl* PetriNet::find_fact(std::string_view n) const noexcept {
  for (const auto& f : facts) {
    if (f.name == n) return &f;
  }
  return nullptr;
}

Marking PetriNet::initial_marking() const {
  Marking m(places_.size(), 0);
  for (std::size_t i = 0; i < places_.size(); ++i) m[i] = places_[i].initial_tokens;
  return m;
}

}  // namespace tripodal
