// Graphviz drawings of configuration nets in the style of the paper's figures (Fig. 2, Fig. 3):
// places as circles holding their tokens, transitions as black bars, ids beside the nodes and the
// descriptions in a table, as in the paper's tables. Backs `tripodal-net dot`.
#pragma once

#include <span>
#include <string>

#include "tripodal/core/petri_net.hpp"

namespace tripodal {

struct DotOptions {
  /// Add a legend table of the descriptions (bindings and fault messages too), like the tables
  /// that accompany the paper's figures; the drawing itself carries ids and annotations.
  bool descriptions = true;
};

/// The net as a DOT digraph. `marking` (one entry per place) replaces the initial marking when
/// given. Read arcs are drawn dashed without a head, inhibitor arcs end in a small circle; an
/// arc weight above one labels its arc; event, guard and delay annotate their transition.
[[nodiscard]] std::string net_to_dot(const PetriNet& net, std::span<const Tokens> marking = {},
                                     const DotOptions& options = {});

}  // namespace tripodal
