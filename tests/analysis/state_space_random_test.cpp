// Seeded random nets with every arc kind, capacities, priorities, events, delays and fact guards:
// the packed explorer must find exactly the graph a naive search finds (std::map of markings,
// enabling recomputed from the net's arcs as docs/engine.md states it, choice rules written out
// from docs/analysis.md).
#include <catch2/catch.hpp>

#include <algorithm>
#include <deque>
#include <map>
#include <random>
#include <set>

#include "tripodal/analysis/state_space.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

namespace {

bool naive_enabled(const PetriNet& net, TransitionIndex t, const Marking& m) {
  const Transition& tr = net.transition(t);
  std::map<PlaceIndex, long> take;
  std::map<PlaceIndex, long> give;
  for (const ArcRef& a : tr.inputs) take[a.place] += a.weight;
  for (const ArcRef& a : tr.outputs) give[a.place] += a.weight;
  for (const auto& [p, k] : take) {
    if (m[p] < k) return false;
  }
  for (const ArcRef& a : tr.reads) {
    if (m[a.place] < a.weight) return false;
  }
  for (const ArcRef& a : tr.inhibitors) {
    if (m[a.place] >= a.weight) return false;
  }
  for (const auto& [p, k] : give) {
    const auto& cap = net.place(p).capacity;
    const long after = static_cast<long>(m[p]) - (take.count(p) ? take.at(p) : 0) + k;
    if (cap && after > static_cast<long>(*cap)) return false;
  }
  return true;
}

// "Certain": the guard (here only fact guards are generated) cannot be false.
bool certain(const Transition& tr) { return !tr.guard.has_value(); }

std::vector<TransitionIndex> naive_choices(const PetriNet& net, const Marking& m, Semantics sem) {
  std::vector<TransitionIndex> out;
  const std::size_t nt = net.transitions().size();
  if (sem == Semantics::interleaving) {
    for (TransitionIndex t = 0; t < nt; ++t) {
      if (naive_enabled(net, t, m)) out.push_back(t);
    }
    return out;
  }
  auto ranked_before = [&](TransitionIndex a, TransitionIndex b) {
    const int pa = net.transition(a).priority;
    const int pb = net.transition(b).priority;
    return pa != pb ? pa > pb : a < b;
  };
  std::vector<TransitionIndex> non_event;
  std::map<std::string, std::vector<TransitionIndex>> by_event;
  for (TransitionIndex t = 0; t < nt; ++t) {
    const Transition& tr = net.transition(t);
    if (tr.event.empty()) {
      non_event.push_back(t);
    } else {
      by_event[tr.event].push_back(t);
    }
  }
  std::sort(non_event.begin(), non_event.end(), ranked_before);
  // Is some immediate transition with a certain guard enabled? Then only transitions ranked at
  // or above the best such one can fire.
  std::optional<TransitionIndex> urgent;
  for (const TransitionIndex t : non_event) {
    const Transition& tr = net.transition(t);
    if (tr.delay.count() == 0 && certain(tr) && naive_enabled(net, t, m)) {
      urgent = t;
      break;
    }
  }
  for (const TransitionIndex t : non_event) {
    if (urgent && ranked_before(*urgent, t)) continue;
    if (naive_enabled(net, t, m)) out.push_back(t);
  }
  if (urgent) return out;
  for (auto& [name, list] : by_event) {
    std::sort(list.begin(), list.end(), ranked_before);
    for (const TransitionIndex t : list) {
      if (!naive_enabled(net, t, m)) continue;
      out.push_back(t);
      if (net.transition(t).delay.count() == 0 && certain(net.transition(t))) break;
    }
  }
  return out;
}

struct NaiveResult {
  std::size_t states = 0;
  std::size_t edges = 0;
  std::size_t deadlocks = 0;
  std::vector<Tokens> max_tokens;
  std::set<TransitionIndex> fired;
  bool complete = true;
};

NaiveResult naive_explore(const PetriNet& net, Semantics sem, std::size_t limit) {
  NaiveResult r;
  r.max_tokens.assign(net.places().size(), 0);
  std::map<Marking, bool> seen;
  std::deque<Marking> queue{net.initial_marking()};
  seen[queue.front()] = true;
  while (!queue.empty()) {
    const Marking m = queue.front();
    queue.pop_front();
    bool outcome = false;
    for (PlaceIndex p = 0; p < m.size(); ++p) {
      r.max_tokens[p] = std::max(r.max_tokens[p], m[p]);
      outcome = outcome || (m[p] > 0 && net.place(p).outcome != Outcome::none);
    }
    if (outcome) continue;
    const auto choices = naive_choices(net, m, sem);
    if (choices.empty()) ++r.deadlocks;
    for (const TransitionIndex t : choices) {
      Marking next = m;
      for (const ArcRef& a : net.transition(t).inputs) next[a.place] -= a.weight;
      for (const ArcRef& a : net.transition(t).outputs) next[a.place] += a.weight;
      ++r.edges;
      r.fired.insert(t);
      if (seen.emplace(next, true).second) {
        if (seen.size() > limit) {
          r.complete = false;
          return r;
        }
        queue.push_back(next);
      }
    }
  }
  r.states = seen.size();
  return r;
}

PetriNet random_net(std::mt19937& rng) {
  std::uniform_int_distribution<int> size(2, 6);
  std::uniform_int_distribution<int> die(0, 9);
  std::uniform_int_distribution<int> weight(1, 2);
  PetriNet net;
  net.facts.push_back(VariableDecl{.name = "f", .type = ValueType::boolean});
  const int np = size(rng);
  const int nt = size(rng) + 1;
  for (int p = 0; p < np; ++p) {
    Place pl{.id = "p" + std::to_string(p), .initial_tokens = static_cast<Tokens>(die(rng) < 4 ? 1 : 0)};
    if (die(rng) < 6) pl.capacity = static_cast<Tokens>(1 + die(rng) % 3);
    pl.initial_tokens = pl.capacity ? std::min(pl.initial_tokens, *pl.capacity) : pl.initial_tokens;
    if (die(rng) == 0) pl.outcome = Outcome::success;
    net.add_place(pl);
  }
  const char* events[] = {"e1", "e2"};
  for (int t = 0; t < nt; ++t) {
    Transition tr{.id = "t" + std::to_string(t)};
    const int k = die(rng);
    if (k < 3) tr.event = events[die(rng) % 2];
    if (k >= 3 && k < 5) tr.delay = from_seconds(1.0);
    if (die(rng) < 2) tr.guard = Guard::parse("f");
    tr.priority = die(rng) % 3;
    net.add_transition(tr);
    for (int p = 0; p < np; ++p) {
      const std::string pid = "p" + std::to_string(p);
      const int c = die(rng);
      if (c < 2) net.add_arc(pid, tr.id, static_cast<Tokens>(weight(rng)));
      if (c >= 2 && c < 4) net.add_arc(tr.id, pid, static_cast<Tokens>(weight(rng)));
      if (c == 4) net.add_arc(pid, tr.id, 1, ArcKind::read);
      if (c == 5) net.add_arc(pid, tr.id, static_cast<Tokens>(weight(rng)), ArcKind::inhibitor);
    }
  }
  return net;
}

}  // namespace

TEST_CASE("Random nets: the packed explorer finds the graph of a naive search", "[analysis][explore][random]") {
  std::mt19937 rng(1122);
  int compared = 0;
  for (int round = 0; round < 600; ++round) {
    const PetriNet net = random_net(rng);
    for (const Semantics sem : {Semantics::interleaving, Semantics::engine}) {
      const NaiveResult naive = naive_explore(net, sem, 3000);
      if (!naive.complete) continue;
      for (const MarkingStore store : {MarkingStore::dense, MarkingStore::sparse}) {
        ExploreOptions o;
        o.semantics = sem;
        o.store = store;
        const StateSpace s = explore(net, o);
        INFO("round " << round << " semantics " << to_string(sem) << " sparse " << s.sparse());
        REQUIRE(s.sparse() == (store == MarkingStore::sparse));
        REQUIRE(s.complete());
        REQUIRE(s.states() == naive.states);
        REQUIRE(s.edges() == naive.edges);
        REQUIRE(s.deadlocks().size() == naive.deadlocks);
        REQUIRE(s.max_tokens() == naive.max_tokens);
        for (TransitionIndex t = 0; t < net.transitions().size(); ++t) {
          REQUIRE((s.fired()[t] != 0) == (naive.fired.count(t) != 0));
        }
        // Every deadlock's path replays to its marking.
        for (const StateId d : s.deadlocks()) {
          Marking m = net.initial_marking();
          for (const TransitionIndex t : s.path_to(d)) {
            REQUIRE(naive_enabled(net, t, m));
            for (const ArcRef& a : net.transition(t).inputs) m[a.place] -= a.weight;
            for (const ArcRef& a : net.transition(t).outputs) m[a.place] += a.weight;
          }
          REQUIRE(m == s.marking(d));
        }
        ++compared;
      }
    }
  }
  CHECK(compared > 1600);
}

TEST_CASE("Random nets: the sparse store numbers the states as the dense one", "[analysis][explore][random]") {
  // Same BFS order, same parents, same markings, same edges: paths in reports do not depend on
  // the store the size of the net picked.
  std::mt19937 rng(2233);
  int compared = 0;
  for (int round = 0; round < 300; ++round) {
    const PetriNet net = random_net(rng);
    for (const Semantics sem : {Semantics::interleaving, Semantics::engine}) {
      ExploreOptions o;
      o.semantics = sem;
      o.keep_edges = true;
      o.max_states = 3000;
      o.store = MarkingStore::dense;
      const StateSpace dense = explore(net, o);
      o.store = MarkingStore::sparse;
      const StateSpace sparse = explore(net, o);
      INFO("round " << round << " semantics " << to_string(sem));
      REQUIRE(sparse.stop_reason() == dense.stop_reason());
      REQUIRE(sparse.states() == dense.states());
      REQUIRE(sparse.expanded() == dense.expanded());
      REQUIRE(sparse.outcome_states() == dense.outcome_states());
      REQUIRE(sparse.deadlocks() == dense.deadlocks());
      for (StateId id = 0; id < dense.states(); ++id) {
        REQUIRE(sparse.marking(id) == dense.marking(id));
        REQUIRE(sparse.path_to(id) == dense.path_to(id));
        REQUIRE(sparse.find(dense.marking(id)) == std::optional<StateId>(id));
        const auto a = dense.successors(id);
        const auto b = sparse.successors(id);
        REQUIRE(std::vector<StateId>(a.begin(), a.end()) == std::vector<StateId>(b.begin(), b.end()));
      }
      ++compared;
    }
  }
  CHECK(compared == 600);
}
