// Structural analysis of a configuration net: the incidence matrix and bases of semi-positive
// place and transition invariants (Farkas / Fourier–Motzkin elimination with minimal-support
// pruning). Used by the analyser for reports and for structural place bounds.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "tripodal/core/petri_net.hpp"

namespace tripodal::analysis {

/// C[p][t] = tokens t puts into p minus tokens it takes from p. Read arcs take and give back
/// nothing and inhibitor arcs move no tokens, so neither appears here.
using IncidenceMatrix = std::vector<std::vector<std::int64_t>>;

[[nodiscard]] IncidenceMatrix incidence_matrix(const PetriNet& net);

/// A semi-positive vector with minimal support, as (index, weight) pairs with weight > 0,
/// ascending index, weights coprime.
struct Invariant {
  std::vector<std::pair<std::uint32_t, std::int64_t>> weights;
  /// Place invariants: the weighted token sum, the same in every reachable marking.
  std::int64_t token_sum = 0;
};

struct InvariantBasis {
  std::vector<Invariant> invariants;
  /// False when the elimination was cut short (too many intermediate rows or a coefficient
  /// overflow): the invariants listed are still invariants, but some may be missing.
  bool complete = true;
  /// Per node (place or transition): in the support of some invariant.
  std::vector<std::uint8_t> covered;
};

struct InvariantOptions {
  std::size_t max_rows = 20'000;  ///< intermediate rows of the elimination before giving up
};

/// Minimal-support semi-positive solutions y >= 0 of y^T C = 0 (all of them: every semi-positive
/// place invariant is a non-negative rational combination of these).
[[nodiscard]] InvariantBasis place_invariants(const PetriNet& net, const InvariantOptions& options = {});
/// Minimal-support semi-positive solutions x >= 0 of C x = 0.
[[nodiscard]] InvariantBasis transition_invariants(const PetriNet& net, const InvariantOptions& options = {});

/// The same elimination on any integer matrix (rows are the unknowns): minimal-support y >= 0
/// with y^T A = 0. Exposed for tests.
[[nodiscard]] InvariantBasis semi_positive_kernel(const std::vector<std::vector<std::int64_t>>& a,
                                                  const InvariantOptions& options = {});

/// Upper bound of every place implied by the place invariants (nullopt: not covered).
[[nodiscard]] std::vector<std::optional<Tokens>> structural_bounds(const PetriNet& net, const InvariantBasis& p_invariants);

}  // namespace tripodal::analysis
