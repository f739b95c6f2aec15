// Karp–Miller coverability: decides which places are unbounded without enumerating an infinite
// state space. Part of the analysis layer (tripodal-net analyze), next to state_space.hpp.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "tripodal/core/engine.hpp"
#include "tripodal/core/petri_net.hpp"

namespace tripodal::analysis {

/// "Any number of tokens" in an omega marking.
inline constexpr Tokens kOmega = 0xFFFFFFFFU;

struct CoverabilityOptions {
  ParameterValues parameters;       ///< guards over parameters are evaluated; over facts: may be true
  std::size_t max_nodes = 200'000;  ///< stop (complete = false) beyond this many graph nodes
};

struct CoverabilityResult {
  /// Every node was expanded; otherwise nothing is concluded.
  bool complete = false;
  /// The search ran on the net itself, not on an over-approximation: the net has no inhibitor
  /// arcs and no capacities. Only then does an omega prove a place unbounded (under
  /// interleaving semantics). Otherwise an omega means "may be unbounded".
  bool exact = false;
  std::size_t nodes = 0;
  /// Per place: the largest count in the coverability graph, nullopt for omega. When complete,
  /// a finite value is an upper bound of the place in every reachable marking.
  std::vector<std::optional<Tokens>> bounds;
  /// The first acceleration found: firing `prefix` from the initial marking, then `pump` gives a
  /// marking that strictly covers the one before `pump`, growing `pumped` places.
  std::vector<TransitionIndex> prefix;
  std::vector<TransitionIndex> pump;
  std::vector<PlaceIndex> pumped;

  [[nodiscard]] bool bounded() const noexcept;  ///< complete and no omega
};

/// Karp–Miller coverability graph (identical omega markings merged, acceleration against the
/// ancestors in the search tree), under interleaving semantics on the monotone
/// over-approximation of the net (inhibitor arcs and capacities dropped).
[[nodiscard]] CoverabilityResult karp_miller(const PetriNet& net, const CoverabilityOptions& options = {});

}  // namespace tripodal::analysis
