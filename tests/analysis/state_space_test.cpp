// Reachability exploration: known state spaces (Kanban, rings, philosophers), the engine's
// choice rules versus interleaving, limits, and the packed store's widening.
#include <catch2/catch.hpp>

#include "analysis_test_nets.hpp"
#include "tripodal/analysis/state_space.hpp"
#include "tripodal/core/diagnostic.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

namespace {

ExploreOptions interleaving() {
  ExploreOptions o;
  o.semantics = Semantics::interleaving;
  return o;
}

PetriNet conflict_net() {
  // p -> a -> q and p -> b -> r, a and b in conflict.
  PetriNet net;
  net.id = "conflict";
  net.add_place(Place{.id = "p", .initial_tokens = 1});
  net.add_place(Place{.id = "q"});
  net.add_place(Place{.id = "r"});
  net.add_transition(Transition{.id = "a"});
  net.add_transition(Transition{.id = "b"});
  net.add_arc("p", "a");
  net.add_arc("a", "q");
  net.add_arc("p", "b");
  net.add_arc("b", "r");
  return net;
}

}  // namespace

TEST_CASE("Kanban with one and two kanbans per stage has the known state spaces", "[analysis][explore]") {
  const StateSpace k1 = explore(test::kanban_net(1), interleaving());
  CHECK(k1.complete());
  CHECK(k1.states() == 160);
  const StateSpace k2 = explore(test::kanban_net(2), interleaving());
  CHECK(k2.complete());
  CHECK(k2.states() == 4600);
  CHECK(k2.edges() == 28120);
  CHECK(k2.deadlocks().empty());
  for (const Tokens m : k2.max_tokens()) CHECK(m == 2);
  // 16 places of 4 bits (no bounds given): 8 bytes per marking.
  CHECK(k2.bytes_per_marking() == 8);
  CHECK(k2.restarts() == 0);
}

TEST_CASE("Known bounds pack markings tighter", "[analysis][explore]") {
  ExploreOptions o = interleaving();
  o.place_bounds.assign(16, Tokens{2});
  const StateSpace k2 = explore(test::kanban_net(2), o);
  CHECK(k2.states() == 4600);
  CHECK(k2.bytes_per_marking() == 4);  // 16 x 2 bits
  CHECK(k2.bytes_per_state() < 40.0);
}

TEST_CASE("Token ring state count is a binomial coefficient", "[analysis][explore]") {
  const StateSpace s = explore(test::ring_of_tokens(10, 5), interleaving());
  CHECK(s.states() == 2002);  // C(14, 5)
  CHECK(s.edges() > s.states());
  CHECK(s.deadlocks().empty());
}

TEST_CASE("Philosophers deadlock when everyone holds a left fork, found with a shortest path", "[analysis][explore]") {
  const PetriNet net = test::philosophers_net(3);
  const StateSpace s = explore(net, interleaving());
  REQUIRE(s.complete());
  REQUIRE(s.deadlocks().size() == 1);
  const Marking m = s.marking(s.deadlocks()[0]);
  for (std::size_t i = 0; i < 3; ++i) CHECK(m[*net.find_place("left" + std::to_string(i))] == 1);
  const auto path = s.path_to(s.deadlocks()[0]);
  CHECK(path.size() == 3);
  for (const TransitionIndex t : path) CHECK(net.transition(t).id.rfind("takeLeft", 0) == 0);
}

TEST_CASE("An inhibitor arc on its own output place makes the initial marking dead", "[analysis][explore]") {
  // deadlock-test018: P0 (1 token), T0 with an inhibitor arc from P0 and an arc to P0.
  PetriNet net;
  net.add_place(Place{.id = "P0", .initial_tokens = 1});
  net.add_transition(Transition{.id = "T0"});
  net.add_arc("T0", "P0");
  net.add_arc("P0", "T0", 1, ArcKind::inhibitor);
  const StateSpace s = explore(net, interleaving());
  CHECK(s.states() == 1);
  CHECK(s.edges() == 0);
  REQUIRE(s.deadlocks() == std::vector<StateId>{0});
  CHECK(s.path_to(0).empty());
  CHECK(s.fired()[0] == 0);
}

TEST_CASE("Engine semantics: the higher priority wins a conflict of immediate transitions", "[analysis][explore][engine]") {
  PetriNet net = conflict_net();
  net.transition(1).priority = 1;  // b
  const StateSpace engine = explore(net, {});
  CHECK(engine.states() == 2);
  CHECK(engine.fired() == std::vector<std::uint8_t>{0, 1});
  const StateSpace all = explore(net, interleaving());
  CHECK(all.states() == 3);
  CHECK(all.fired() == std::vector<std::uint8_t>{1, 1});
  net.transition(1).priority = 0;  // equal priorities: declaration order
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{1, 0});
}

TEST_CASE("Engine semantics: an immediate transition is urgent, an event waits for a settled marking", "[analysis][explore][engine]") {
  PetriNet net = conflict_net();
  net.transition(0).event = "go";  // a waits for an event, b is immediate
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{0, 1});
  net.transition(1).event = "stop";  // both wait for events: either may come first
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{1, 1});
  net.transition(1).event = "go";  // one event, two listeners: the first in conflict order takes it
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{1, 0});
  net.transition(0).delay = from_seconds(1.0);  // ... unless its delay may not have elapsed
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{1, 1});
}

TEST_CASE("Engine semantics: a guard over a fact may be true or false, over a parameter it is decided", "[analysis][explore][engine]") {
  PetriNet net = conflict_net();
  net.facts.push_back(VariableDecl{.name = "battery_low", .type = ValueType::boolean});
  net.parameters.push_back(VariableDecl{.name = "mode", .type = ValueType::string, .default_value = Value{std::string("slow")}});
  net.transition(0).guard = Guard::parse("battery_low");
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{1, 1});
  net.transition(0).guard = Guard::parse("mode == 'fast'");
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{0, 1});
  ExploreOptions fast;
  fast.parameters["mode"] = Value{std::string("fast")};
  CHECK(explore(net, fast).fired() == std::vector<std::uint8_t>{1, 0});
  fast.parameters["mode"] = Value{1.0};
  REQUIRE_THROWS_WITH(explore(net, fast), Catch::Contains("parameter 'mode'") && Catch::Contains("must be a string"));
  net.transition(0).guard = Guard::parse("speed > 2");
  REQUIRE_THROWS_WITH(explore(net, {}), Catch::Contains("reads 'speed', which is neither a parameter nor a fact"));
}

TEST_CASE("Engine semantics: a delayed transition may fire before a lower-ranked immediate one, never after a higher one",
          "[analysis][explore][engine]") {
  PetriNet net = conflict_net();
  net.transition(0).delay = from_seconds(2.0);  // a delayed, ranked first
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{1, 1});
  net.transition(1).priority = 1;  // b immediate and ranked above a
  CHECK(explore(net, {}).fired() == std::vector<std::uint8_t>{0, 1});
}

TEST_CASE("Outcome markings are terminal and not deadlocks", "[analysis][explore]") {
  PetriNet net = conflict_net();
  net.place(1).outcome = Outcome::success;
  net.add_transition(Transition{.id = "after"});
  net.add_arc("q", "after");
  net.add_arc("after", "p");
  const StateSpace s = explore(net, interleaving());
  CHECK(s.states() == 3);
  CHECK(s.outcome_states().size() == 1);
  CHECK(s.deadlocks().size() == 1);  // r
  CHECK(s.fired()[2] == 0);
  ExploreOptions go_on = interleaving();
  go_on.stop_at_outcome = false;
  CHECK(explore(net, go_on).fired()[2] == 1);
}

TEST_CASE("max_states stops the search cleanly with a partial graph", "[analysis][explore][limits]") {
  ExploreOptions o = interleaving();
  o.max_states = 1000;
  const StateSpace s = explore(test::kanban_net(3), o);
  CHECK(s.stop_reason() == StopReason::max_states);
  CHECK(s.states() == 1000);
  CHECK(s.expanded() < 1000);
  CHECK_FALSE(s.complete());
}

TEST_CASE("The memory cap stops the search before the store outgrows it", "[analysis][explore][limits]") {
  ExploreOptions o = interleaving();
  o.max_memory_bytes = 256 * 1024;
  const StateSpace s = explore(test::kanban_net(3), o);
  CHECK(s.stop_reason() == StopReason::max_memory);
  CHECK(s.memory_bytes() <= o.max_memory_bytes);
  CHECK(s.states() > 1000);
}

TEST_CASE("A field that overflows is widened and the search restarted", "[analysis][explore]") {
  // A source transition blocked by an inhibitor at 100 tokens: 101 states, no bound given.
  PetriNet net;
  net.add_place(Place{.id = "p"});
  net.add_transition(Transition{.id = "produce"});
  net.add_arc("produce", "p");
  net.add_arc("p", "produce", 100, ArcKind::inhibitor);
  const StateSpace s = explore(net, interleaving());
  CHECK(s.complete());
  CHECK(s.states() == 101);
  CHECK(s.max_tokens()[0] == 100);
  CHECK(s.restarts() == 1);
  CHECK(s.bits_per_place()[0] == 8);
  CHECK(s.find(Marking{57}).has_value());
  CHECK_FALSE(s.find(Marking{101}).has_value());
}

TEST_CASE("An unbounded net hits the state limit, never memory exhaustion", "[analysis][explore][limits]") {
  PetriNet net;
  net.add_place(Place{.id = "p", .initial_tokens = 1});
  net.add_place(Place{.id = "q"});
  net.add_transition(Transition{.id = "t"});
  net.add_arc("p", "t");
  net.add_arc("t", "p");
  net.add_arc("t", "q");
  ExploreOptions o = interleaving();
  o.max_states = 50'000;
  const StateSpace s = explore(net, o);
  CHECK(s.stop_reason() == StopReason::max_states);
  CHECK(s.max_tokens()[1] >= 49'998);
}
