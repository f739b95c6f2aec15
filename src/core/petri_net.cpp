#include "tripodal/core/petri_net.hpp"

#include <bit>
#include <cstring>
#include <stdexcept>

namespace tripodal {

namespace {

// FNV-1a, for ids longer than a slot holds.
std::uint32_t id_hash(std::string_view s) noexcept {
  std::uint32_t h = 2166136261U;
  for (const char c : s) {
    h ^= static_cast<unsigned char>(c);
    h *= 16777619U;
  }
  return h;
}

constexpr std::size_t kShortId = 7;  // bytes a slot holds, with the length in the eighth
constexpr std::uint64_t kLongId = 0xFFULL << 56;

}  // namespace

void PetriNet::reserve(std::size_t places, std::size_t transitions) {
  places_.reserve(places);
  transitions_.reserve(transitions);
  place_ids_.reserve(places);
  transition_ids_.reserve(transitions);
  place_keys_.reserve(places);
  transition_keys_.reserve(transitions);
  grow_index(places + transitions);
}

void PetriNet::grow_index(std::size_t nodes) {
  // Load factor at most 3/4: a 20,000-node net fits a 256 KiB table.
  if (nodes * 4 <= id_slots_.size() * 3) return;  // the common case: room enough
  std::size_t capacity = 16;
  while (capacity * 3 < nodes * 4) capacity *= 2;
  if (capacity <= id_slots_.size()) return;
  std::vector<IdSlot> old = std::move(id_slots_);
  id_slots_.assign(capacity, IdSlot{});
  const std::size_t mask = capacity - 1;
  for (const IdSlot& slot : old) {
    if (slot.node == 0) continue;
    std::size_t i = slot.hash & mask;
    while (id_slots_[i].node != 0) i = (i + 1) & mask;
    id_slots_[i] = slot;
  }
}

PetriNet::IdKey PetriNet::id_key(std::string_view node_id) noexcept {
  if (node_id.size() > kShortId) {
    const std::uint32_t h = id_hash(node_id);
    return IdKey{kLongId | h, h};
  }
  // The bytes in little-endian order whatever the machine. From 4 bytes on, two 4-byte loads
  // that may overlap (an overlapping byte lands on the same place from both).
  const auto* b = reinterpret_cast<const unsigned char*>(node_id.data());
  const std::size_t n = node_id.size();
  const auto load4 = [](const unsigned char* p) {
    std::uint32_t w = 0;
    std::memcpy(&w, p, 4);
    if constexpr (std::endian::native == std::endian::big) w = __builtin_bswap32(w);
    return std::uint64_t{w};
  };
  std::uint64_t key = static_cast<std::uint64_t>(n) << 56;
  if (n >= 4) {
    key |= load4(b) | load4(b + n - 4) << (8 * (n - 4));
  } else {
    for (std::size_t k = 0; k < n; ++k) key |= std::uint64_t{b[k]} << (8 * k);
  }
  // A 64-bit finaliser (multiply, xor-shift): every byte of the key, the length included,
  // reaches the low bits that pick the slot.
  std::uint64_t h = key * 0x9E3779B97F4A7C15ULL;
  h ^= h >> 32;
  h *= 0xFF51AFD7ED558CCDULL;
  h ^= h >> 29;
  return IdKey{key, static_cast<std::uint32_t>(h)};
}

std::size_t PetriNet::probe(std::string_view node_id, IdKey key, bool& found) const noexcept {
  const std::size_t mask = id_slots_.size() - 1;
  for (std::size_t i = key.hash & mask;; i = (i + 1) & mask) {
    const IdSlot& slot = id_slots_[i];
    if (slot.node == 0) {
      found = false;
      return i;
    }
    if (slot.hash != key.hash) continue;
    const std::uint32_t code = slot.node - 1;
    const bool is_place = (code & 1U) != 0;
    if ((is_place ? place_keys_[code >> 1] : transition_keys_[code >> 1]) != key.key) continue;
    if ((key.key & kLongId) != kLongId) {  // a short id: the key is the id
      found = true;
      return i;
    }
    const IdSpan span = is_place ? place_ids_[code >> 1] : transition_ids_[code >> 1];
    if (span.size == node_id.size() && std::string_view(id_chars_).substr(span.offset, span.size) == node_id) {
      found = true;
      return i;
    }
  }
}

std::optional<PetriNet::NodeRef> PetriNet::find_node(std::string_view node_id) const noexcept {
  if (id_slots_.empty()) return std::nullopt;
  bool found = false;
  const std::size_t i = probe(node_id, id_key(node_id), found);
  if (!found) return std::nullopt;
  const std::uint32_t code = id_slots_[i].node - 1;
  return NodeRef{(code & 1U) != 0, code >> 1};
}

void PetriNet::prefetch_node(std::string_view node_id) const noexcept {
  if (id_slots_.empty()) return;
  __builtin_prefetch(&id_slots_[id_key(node_id).hash & (id_slots_.size() - 1)]);
}

std::size_t PetriNet::claim_slot(std::string_view node_id, IdKey& key) {
  grow_index(places_.size() + transitions_.size() + 1);
  key = id_key(node_id);
  bool found = false;
  const std::size_t slot = probe(node_id, key, found);
  if (found) throw std::invalid_argument("duplicate node id '" + std::string(node_id) + "'");
  return slot;
}

void PetriNet::fill_slot(std::size_t slot, IdKey key, std::string_view node_id, NodeRef ref) {
  id_slots_[slot] = IdSlot{key.hash, ((ref.index << 1) | (ref.is_place ? 1U : 0U)) + 1};
  (ref.is_place ? place_keys_ : transition_keys_).push_back(key.key);
  (ref.is_place ? place_ids_ : transition_ids_)
      .push_back(IdSpan{static_cast<std::uint32_t>(id_chars_.size()), static_cast<std::uint32_t>(node_id.size())});
  id_chars_.append(node_id);
}

const SourceLocation* PetriNet::find_node_where(std::string_view node_id) const noexcept {
  const auto ref = find_node(node_id);
  if (!ref) return nullptr;
  return ref->is_place ? &places_[ref->index].where : &transitions_[ref->index].where;
}

PlaceIndex PetriNet::add_place(Place p) {
  if (p.id.empty()) throw std::invalid_argument("place id must not be empty");
  IdKey key;
  const std::size_t slot = claim_slot(p.id, key);  // throws on a duplicate
  if (p.capacity && p.initial_tokens > *p.capacity) {
    throw std::invalid_argument("place '" + p.id + "' starts with more tokens than its capacity");
  }
  if (p.name.empty()) p.name = p.id;
  const auto index = static_cast<PlaceIndex>(places_.size());
  places_.push_back(std::move(p));
  fill_slot(slot, key, places_.back().id, NodeRef{true, index});
  return index;
}

template <typename Node>
Node& PetriNet::emplace_node(std::vector<Node>& nodes, bool is_place, std::string_view node_id, SourceLocation node_where) {
  if (node_id.empty()) throw std::invalid_argument(std::string(is_place ? "place" : "transition") + " id must not be empty");
  IdKey key;
  const std::size_t slot = claim_slot(node_id, key);  // throws on a duplicate
  const auto index = static_cast<std::uint32_t>(nodes.size());
  Node& node = nodes.emplace_back();
  node.id = node_id;
  node.name = node.id;
  node.where = node_where;
  fill_slot(slot, key, node.id, NodeRef{is_place, index});
  return node;
}

Place& PetriNet::new_place(std::string_view node_id, SourceLocation node_where) {
  return emplace_node(places_, true, node_id, node_where);
}

Transition& PetriNet::new_transition(std::string_view node_id, SourceLocation node_where) {
  return emplace_node(transitions_, false, node_id, node_where);
}

TransitionIndex PetriNet::add_transition(Transition t) {
  if (t.id.empty()) throw std::invalid_argument("transition id must not be empty");
  IdKey key;
  const std::size_t slot = claim_slot(t.id, key);  // throws on a duplicate
  if (t.delay.count() < 0) throw std::invalid_argument("transition '" + t.id + "' has a negative delay");
  if (t.name.empty()) t.name = t.id;
  const auto index = static_cast<TransitionIndex>(transitions_.size());
  transitions_.push_back(std::move(t));
  fill_slot(slot, key, transitions_.back().id, NodeRef{false, index});
  return index;
}

void PetriNet::add_arc(std::string_view from_id, std::string_view to_id, Tokens weight, ArcKind kind,
                       SourceLocation arc_where) {
  if (weight == 0) throw std::invalid_argument("arc weight must be positive");
  // One look-up per end: loaders add tens of thousands of arcs.
  const auto from = find_node(from_id);
  const auto to = find_node(to_id);
  if (!from) throw std::invalid_argument("arc from unknown node '" + std::string(from_id) + "'");
  if (!to) throw std::invalid_argument("arc to unknown node '" + std::string(to_id) + "'");
  if (from->is_place && !to->is_place) {
    Transition& t = transitions_[to->index];
    ArcRef ref{from->index, weight, arc_where};
    switch (kind) {
      case ArcKind::normal: t.inputs.push_back(ref); break;
      case ArcKind::read: t.reads.push_back(ref); break;
      case ArcKind::inhibitor: t.inhibitors.push_back(ref); break;
    }
    return;
  }
  if (!from->is_place && to->is_place) {
    if (kind != ArcKind::normal) {
      throw std::invalid_argument("read and inhibitor arcs go from a place to a transition, not from '" +
                                  std::string(from_id) + "' to '" + std::string(to_id) + "'");
    }
    transitions_[from->index].outputs.push_back(ArcRef{to->index, weight, arc_where});
    return;
  }
  throw std::invalid_argument("arc must connect a place and a transition: '" + std::string(from_id) + "' -> '" +
                              std::string(to_id) + "'");
}

std::optional<PlaceIndex> PetriNet::find_place(std::string_view node_id) const noexcept {
  const auto ref = find_node(node_id);
  if (!ref || !ref->is_place) return std::nullopt;
  return ref->index;
}

std::optional<TransitionIndex> PetriNet::find_transition(std::string_view node_id) const noexcept {
  const auto ref = find_node(node_id);
  if (!ref || ref->is_place) return std::nullopt;
  return ref->index;
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
