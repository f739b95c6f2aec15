// Karp–Miller search. Nodes are omega markings (vector<Tokens> with kOmega), kept in a hash map
// so identical markings are merged; acceleration compares a new marking with the ancestors on
// its search-tree path, which in a monotone net is sound (the path from the ancestor can be
// repeated forever) and keeps the graph finite. Not a hot path: the explorer is the fast one.
#include "tripodal/analysis/coverability.hpp"

#include <algorithm>
#include <deque>
#include <string_view>
#include <unordered_map>

#include "compiled_net.hpp"

namespace tripodal::analysis {

namespace {

struct MarkingHash {
  std::size_t operator()(const Marking& m) const noexcept {
    return std::hash<std::string_view>{}(
        std::string_view(reinterpret_cast<const char*>(m.data()), m.size() * sizeof(Tokens)));
  }
};

constexpr std::uint32_t kRoot = 0xFFFFFFFFU;

// Bit p % 64 for every marked place p: a marking covers another only if its signature contains
// the other's, so most ancestors are passed over without comparing the markings place by place.
std::uint64_t signature(const Marking& m) noexcept {
  std::uint64_t s = 0;
  for (std::size_t p = 0; p < m.size(); ++p) {
    if (m[p] != 0) s |= std::uint64_t{1} << (p % 64);
  }
  return s;
}

}  // namespace

bool CoverabilityResult::bounded() const noexcept {
  return complete && std::all_of(bounds.begin(), bounds.end(), [](const auto& b) { return b.has_value(); });
}

CoverabilityResult karp_miller(const PetriNet& net, const CoverabilityOptions& options) {
  const detail::CompiledNet compiled(net, options.parameters,
                                     {.semantics = Semantics::interleaving, .monotone = true});
  CoverabilityResult result;
  result.exact = true;
  for (const Place& p : net.places()) result.exact = result.exact && !p.capacity;
  for (const Transition& t : net.transitions()) result.exact = result.exact && t.inhibitors.empty();

  std::vector<Marking> nodes;
  std::vector<std::uint32_t> parent;
  std::vector<TransitionIndex> via;
  std::vector<std::uint64_t> sig;
  std::unordered_map<Marking, std::uint32_t, MarkingHash> index;
  nodes.push_back(net.initial_marking());
  parent.push_back(kRoot);
  via.push_back(0);
  sig.push_back(signature(nodes[0]));
  index.emplace(nodes[0], 0);
  bool found_pump = false;

  auto path_between = [&](std::uint32_t from, std::uint32_t to) {
    std::vector<TransitionIndex> path;
    for (std::uint32_t at = to; at != from && parent[at] != kRoot; at = parent[at]) path.push_back(via[at]);
    std::reverse(path.begin(), path.end());
    return path;
  };

  result.complete = true;
  for (std::uint32_t n = 0; n < nodes.size(); ++n) {
    for (TransitionIndex t = 0; t < compiled.transitions; ++t) {
      if (!compiled.enabled(t, nodes[n].data())) continue;
      Marking next = nodes[n];
      for (std::uint32_t i = compiled.change_begin[t]; i < compiled.change_begin[t + 1]; ++i) {
        const detail::Change& c = compiled.changes[i];
        Tokens& v = next[c.place];
        if (v == kOmega) continue;
        const std::uint64_t after = std::uint64_t{v} - c.consumed + c.produced;
        v = after >= kOmega ? kOmega : static_cast<Tokens>(after);
      }
      const std::uint64_t next_sig = signature(next);  // acceleration only turns marked places into omega
      for (std::uint32_t a = n; a != kRoot; a = parent[a]) {
        if ((sig[a] & ~next_sig) != 0) continue;
        const Marking& old = nodes[a];
        bool covers = true;
        bool strictly = false;
        for (std::size_t p = 0; p < next.size() && covers; ++p) {
          covers = next[p] >= old[p];
          strictly = strictly || next[p] > old[p];
        }
        if (!covers || !strictly) continue;
        std::vector<PlaceIndex> grown;
        for (std::size_t p = 0; p < next.size(); ++p) {
          if (next[p] > old[p] && next[p] != kOmega) {
            next[p] = kOmega;
            grown.push_back(static_cast<PlaceIndex>(p));
          }
        }
        if (!found_pump && !grown.empty()) {
          found_pump = true;
          result.prefix = path_between(kRoot, a);
          result.pump = path_between(a, n);
          result.pump.push_back(t);
          result.pumped = grown;
        }
      }
      if (index.count(next) != 0) continue;
      if (nodes.size() >= options.max_nodes) {
        result.complete = false;
        break;
      }
      index.emplace(next, static_cast<std::uint32_t>(nodes.size()));
      nodes.push_back(std::move(next));
      parent.push_back(n);
      via.push_back(t);
      sig.push_back(next_sig);
    }
    if (!result.complete) break;
  }
  result.nodes = nodes.size();
  result.bounds.assign(net.places().size(), Tokens{0});
  for (const Marking& m : nodes) {
    for (std::size_t p = 0; p < m.size(); ++p) {
      if (!result.bounds[p]) continue;
      if (m[p] == kOmega) {
        result.bounds[p].reset();
      } else {
        result.bounds[p] = std::max(*result.bounds[p], m[p]);
      }
    }
  }
  return result;
}

}  // namespace tripodal::analysis
