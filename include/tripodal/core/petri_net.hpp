// The configuration-net model: a place/transition net with weighted, read and inhibitor arcs,
// transitions triggered by events, guards, delays and priorities, and places that bind
// behaviors, mark outcomes or refer to process modules. Loaders (native XML, PNML) produce it,
// the engine executes it, the analyser explores it, the planner generates high-level ones.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/guard.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/core/value.hpp"

namespace tripodal {

using PlaceIndex = std::uint32_t;
using TransitionIndex = std::uint32_t;
using Tokens = std::uint32_t;

/// Tokens per place, indexed by PlaceIndex.
using Marking = std::vector<Tokens>;

/// High-level nets plan a task from process modules; low-level nets run a process from behaviors.
enum class NetLevel { low, high };

/// What marking a place means to the process supervisor / planner.
enum class Outcome { none, success, fault };

enum class ArcKind {
  normal,     ///< consumes (place->transition) or produces (transition->place) `weight` tokens
  read,       ///< test arc: needs `weight` tokens in the place, consumes none
  inhibitor,  ///< enabled only while the place holds fewer than `weight` tokens
};

/// A declared process parameter (fixed while a process runs) or fact (changes at run time, set
/// by modules). Guards may read both; the analyser treats facts as free choices.
struct VariableDecl {
  std::string name;
  ValueType type = ValueType::string;
  std::optional<Value> default_value;
  std::string description;
  SourceLocation where;
};

/// name=value passed to a behavior or process. `value` is text; "$name" refers to a parameter of
/// the enclosing process, resolved by the process supervisor when the place becomes marked.
struct BindingParam {
  std::string name;
  std::string value;
  SourceLocation where;
};

struct BehaviorBinding {
  std::string behavior;
  std::vector<BindingParam> params;
};

struct ProcessRef {
  std::string process;
  std::vector<BindingParam> params;
};

struct Place {
  std::string id;           ///< unique within the net, e.g. "P1"
  std::string name;         ///< short label for drawings; defaults to id
  std::string description;  ///< as in the paper's tables
  Tokens initial_tokens = 0;
  std::optional<Tokens> capacity;  ///< a firing that would exceed it is not enabled
  std::optional<BehaviorBinding> behavior;  ///< active while the place is marked
  std::optional<ProcessRef> process;        ///< high-level nets: runs while the place is marked
  Outcome outcome = Outcome::none;
  std::string fault_message;  ///< for Outcome::fault, e.g. "localization fault"
  SourceLocation where;
};

struct ArcRef {
  PlaceIndex place = 0;
  Tokens weight = 1;
  SourceLocation where;
};

struct Transition {
  std::string id;
  std::string name;
  std::string description;
  std::string event;          ///< empty: no trigger; else fires only when this event is posted
  std::optional<Guard> guard; ///< must hold for the transition to be enabled
  Duration delay{0};          ///< must have stayed enabled this long before it may fire
  int priority = 0;           ///< higher fires first among conflicting transitions
  std::vector<ArcRef> inputs;      ///< normal arcs place -> transition (consume)
  std::vector<ArcRef> outputs;     ///< normal arcs transition -> place (produce)
  std::vector<ArcRef> reads;       ///< read arcs (test, no consumption)
  std::vector<ArcRef> inhibitors;  ///< inhibitor arcs
  SourceLocation where;
};

/// A configuration net. Built by loaders or programmatically through the add_* methods, which
/// keep indices consistent and throw std::invalid_argument on misuse (duplicate id, unknown id,
/// zero weight).
class PetriNet {
 public:
  std::string id;
  std::string name;
  std::string description;
  NetLevel level = NetLevel::low;
  std::vector<VariableDecl> parameters;
  std::vector<VariableDecl> facts;
  SourceLocation where;  ///< the file (and element) it was loaded from

  /// Room for this many places and transitions (loaders know the counts up front).
  void reserve(std::size_t places, std::size_t transitions);
  PlaceIndex add_place(Place p);
  TransitionIndex add_transition(Transition t);
  /// Adds a node with this id and defaults elsewhere, and returns it to be filled in where it
  /// lies (the loaders read each node's details straight into the net). Throws like add_*; the
  /// reference is valid until the next node of its kind is added beyond the reserved room.
  Place& new_place(std::string_view node_id, SourceLocation node_where = {});
  Transition& new_transition(std::string_view node_id, SourceLocation node_where = {});
  /// Adds an arc between a place and a transition given by id, in either direction for normal
  /// arcs; read and inhibitor arcs go from a place to a transition.
  void add_arc(std::string_view from_id, std::string_view to_id, Tokens weight = 1,
               ArcKind kind = ArcKind::normal, SourceLocation arc_where = {});

  [[nodiscard]] const std::vector<Place>& places() const noexcept { return places_; }
  [[nodiscard]] const std::vector<Transition>& transitions() const noexcept { return transitions_; }
  /// Mutable access for loaders and generators; changing a node's id is not supported.
  [[nodiscard]] Place& place(PlaceIndex i) { return places_.at(i); }
  [[nodiscard]] const Place& place(PlaceIndex i) const { return places_.at(i); }
  [[nodiscard]] Transition& transition(TransitionIndex i) { return transitions_.at(i); }
  [[nodiscard]] const Transition& transition(TransitionIndex i) const { return transitions_.at(i); }
  [[nodiscard]] std::optional<PlaceIndex> find_place(std::string_view node_id) const noexcept;
  [[nodiscard]] std::optional<TransitionIndex> find_transition(std::string_view node_id) const noexcept;
  /// Where the place or transition with this id was defined; nullptr when no node has it.
  [[nodiscard]] const SourceLocation* find_node_where(std::string_view node_id) const noexcept;
  /// A hint, no effect on the net: `node_id` is about to be added or looked up (its slot in the
  /// id index is fetched into the cache). Loaders call it a few nodes ahead: in a net of 10^5
  /// nodes the index no longer fits the caches and each look-up would wait for memory.
  void prefetch_node(std::string_view node_id) const noexcept;
  [[nodiscard]] const VariableDecl* find_parameter(std::string_view name) const noexcept;
  [[nodiscard]] const VariableDecl* find_fact(std::string_view name) const noexcept;

  [[nodiscard]] Marking initial_marking() const;

 private:
  struct NodeRef {
    bool is_place;
    std::uint32_t index;
  };
  // Ids are found through an open-addressing table of (hash, node) pairs, linear probing, load
  // factor at most 3/4: 8 bytes a slot, so a 20,000-node net's table is 256 KiB, and a look-up
  // that meets its hash confirms the match against the node's key, which holds the id itself
  // when it has at most 7 bytes (as ids such as "P12" or "T_dock" do); a longer id is compared
  // against a copy of every id kept back to back. A node-based hash map would chase two or three
  // pointers per look-up (the loaders resolve every arc by id).
  struct IdKey {
    std::uint64_t key = 0;   ///< short: the bytes, length in the top byte; long: 0xFF, then the hash
    std::uint32_t hash = 0;  ///< where probing starts
  };
  struct IdSlot {
    std::uint32_t hash = 0;
    std::uint32_t node = 0;  ///< 0: empty; else (index << 1 | is_place) + 1
  };
  [[nodiscard]] static IdKey id_key(std::string_view node_id) noexcept;
  [[nodiscard]] std::optional<NodeRef> find_node(std::string_view node_id) const noexcept;
  [[nodiscard]] std::size_t probe(std::string_view node_id, IdKey key, bool& found) const noexcept;
  // The free slot for a new id (throws on a duplicate), then filled once the node is stored.
  std::size_t claim_slot(std::string_view node_id, IdKey& key);
  void fill_slot(std::size_t slot, IdKey key, std::string_view node_id, NodeRef ref);
  void grow_index(std::size_t nodes);
  template <typename Node>
  Node& emplace_node(std::vector<Node>& nodes, bool is_place, std::string_view node_id, SourceLocation node_where);

  std::vector<Place> places_;
  std::vector<Transition> transitions_;
  std::vector<IdSlot> id_slots_;
  struct IdSpan {
    std::uint32_t offset = 0;
    std::uint32_t size = 0;
  };
  std::string id_chars_;
  std::vector<IdSpan> place_ids_;       // per place, into id_chars_
  std::vector<IdSpan> transition_ids_;  // per transition
  std::vector<std::uint64_t> place_keys_;       // per place, IdKey::key
  std::vector<std::uint64_t> transition_keys_;  // per transition
};

}  // namespace tripodal
