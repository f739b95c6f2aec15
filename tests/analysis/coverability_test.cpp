// Karp–Miller: unboundedness proved on small nets, exact bounds on bounded ones, and agreement
// with the bounded exploration on seeded random nets.
#include <catch2/catch.hpp>

#include <random>

#include "analysis_test_nets.hpp"
#include "tripodal/analysis/coverability.hpp"
#include "tripodal/analysis/state_space.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

TEST_CASE("Karp-Miller proves a producer loop unbounded and names the pump", "[analysis][coverability]") {
  PetriNet net;
  net.add_place(Place{.id = "p", .initial_tokens = 1});
  net.add_place(Place{.id = "q"});
  net.add_place(Place{.id = "idle", .initial_tokens = 1});
  net.add_transition(Transition{.id = "t"});
  net.add_arc("p", "t");
  net.add_arc("t", "p");
  net.add_arc("t", "q");
  const CoverabilityResult r = karp_miller(net);
  CHECK(r.complete);
  CHECK(r.exact);
  CHECK_FALSE(r.bounded());
  CHECK(r.bounds[0] == Tokens{1});
  CHECK_FALSE(r.bounds[1].has_value());
  CHECK(r.bounds[2] == Tokens{1});
  CHECK(r.prefix.empty());
  CHECK(r.pump == std::vector<TransitionIndex>{0});
  CHECK(r.pumped == std::vector<PlaceIndex>{1});
}

TEST_CASE("Karp-Miller on a bounded net gives the exact bounds", "[analysis][coverability]") {
  const CoverabilityResult r = karp_miller(test::kanban_net(2));
  CHECK(r.complete);
  CHECK(r.bounded());
  CHECK(r.nodes == 4600);
  for (const auto& b : r.bounds) CHECK(b == Tokens{2});
}

TEST_CASE("Inhibitor arcs and capacities make Karp-Miller an over-approximation", "[analysis][coverability]") {
  PetriNet net;
  net.add_place(Place{.id = "p"});
  net.add_transition(Transition{.id = "produce"});
  net.add_arc("produce", "p");
  net.add_arc("p", "produce", 3, ArcKind::inhibitor);
  const CoverabilityResult r = karp_miller(net);
  CHECK(r.complete);
  CHECK_FALSE(r.exact);
  CHECK_FALSE(r.bounds[0].has_value());  // may be unbounded; the exploration finds 3
  ExploreOptions o;
  o.semantics = Semantics::interleaving;
  CHECK(explore(net, o).max_tokens()[0] == 3);
}

TEST_CASE("Karp-Miller stops at its node limit without concluding", "[analysis][coverability][limits]") {
  const CoverabilityResult r = karp_miller(test::kanban_net(3), {.max_nodes = 100});
  CHECK_FALSE(r.complete);
  CHECK(r.nodes == 100);
}

TEST_CASE("Random monotone nets: Karp-Miller agrees with the bounded exploration", "[analysis][coverability][random]") {
  std::mt19937 rng(4242);
  int bounded_nets = 0;
  int unbounded_nets = 0;
  for (int round = 0; round < 400; ++round) {
    std::uniform_int_distribution<int> places_d(2, 5);
    std::uniform_int_distribution<int> weight(1, 2);
    std::uniform_int_distribution<int> coin(0, 3);
    PetriNet net;
    const int np = places_d(rng);
    const int nt = places_d(rng);
    for (int p = 0; p < np; ++p) {
      net.add_place(Place{.id = "p" + std::to_string(p), .initial_tokens = static_cast<Tokens>(coin(rng) == 0 ? 1 : 0)});
    }
    net.place(0).initial_tokens = 1;
    for (int t = 0; t < nt; ++t) {
      const std::string id = "t" + std::to_string(t);
      net.add_transition(Transition{.id = id});
      for (int p = 0; p < np; ++p) {
        const std::string pid = "p" + std::to_string(p);
        const int c = coin(rng);
        if (c == 0) net.add_arc(pid, id, static_cast<Tokens>(weight(rng)));
        if (c == 1) net.add_arc(id, pid, static_cast<Tokens>(weight(rng)));
        if (c == 2 && coin(rng) == 0) net.add_arc(pid, id, 1, ArcKind::read);
      }
    }
    const CoverabilityResult km = karp_miller(net, {.max_nodes = 20'000});
    if (!km.complete) continue;
    ExploreOptions o;
    o.semantics = Semantics::interleaving;
    o.max_states = 20'000;
    const StateSpace s = explore(net, o);
    INFO("round " << round);
    if (km.bounded()) {
      ++bounded_nets;
      REQUIRE(s.complete());
      // In a bounded monotone net no acceleration happens: the graphs coincide.
      REQUIRE(s.states() == km.nodes);
      for (std::size_t p = 0; p < net.places().size(); ++p) REQUIRE(s.max_tokens()[p] == *km.bounds[p]);
    } else {
      ++unbounded_nets;
      REQUIRE_FALSE(s.complete());
      // Repeating the pump from the end of the prefix really grows the pumped places.
      Marking m = net.initial_marking();
      auto fire = [&](TransitionIndex t) {
        const Transition& tr = net.transition(t);
        for (const ArcRef& a : tr.inputs) {
          REQUIRE(m[a.place] >= a.weight);
          m[a.place] -= a.weight;
        }
        for (const ArcRef& a : tr.outputs) m[a.place] += a.weight;
      };
      for (const TransitionIndex t : km.prefix) fire(t);
      const Marking before = m;
      for (int k = 0; k < 3; ++k) {
        for (const TransitionIndex t : km.pump) fire(t);
      }
      for (const PlaceIndex p : km.pumped) REQUIRE(m[p] > before[p]);
    }
  }
  CHECK(bounded_nets > 20);
  CHECK(unbounded_nets > 20);
}
