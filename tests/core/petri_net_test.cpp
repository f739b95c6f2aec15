#include "tripodal/core/petri_net.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

TEST_CASE("nets built in code keep arcs on their transitions") {
  PetriNet net;
  net.add_place({.id = "P0", .initial_tokens = 2});
  net.add_place({.id = "P1", .capacity = 1});
  net.add_place({.id = "P2"});
  net.add_transition({.id = "t0"});
  net.add_arc("P0", "t0", 2);
  net.add_arc("t0", "P1");
  net.add_arc("P2", "t0", 1, ArcKind::inhibitor);
  net.add_arc("P1", "t0", 1, ArcKind::read);

  const Transition& t = net.transition(0);
  REQUIRE(t.inputs.size() == 1);
  CHECK(t.inputs[0].weight == 2);
  CHECK(t.outputs.at(0).place == 1);
  CHECK(t.inhibitors.at(0).place == 2);
  CHECK(t.reads.at(0).place == 1);
  CHECK(net.initial_marking() == Marking{2, 0, 0});
  CHECK(net.place(0).name == "P0");
  CHECK(net.find_place("P2") == PlaceIndex{2});
  CHECK_FALSE(net.find_place("t0"));
  CHECK(net.find_transition("t0") == TransitionIndex{0});
}

TEST_CASE("misuse of the building API is refused with the offending id") {
  PetriNet net;
  net.add_place({.id = "P0"});
  net.add_transition({.id = "t0"});
  CHECK_THROWS_WITH(net.add_place({.id = "t0"}), Catch::Contains("duplicate node id 't0'"));
  CHECK_THROWS_WITH(net.add_arc("P0", "P0"), Catch::Contains("must connect a place and a transition"));
  CHECK_THROWS_WITH(net.add_arc("P0", "tx"), Catch::Contains("unknown node 'tx'"));
  CHECK_THROWS_WITH(net.add_arc("P0", "t0", 0), Catch::Contains("positive"));
  CHECK_THROWS_WITH(net.add_arc("t0", "P0", 1, ArcKind::inhibitor), Catch::Contains("from a place"));
  CHECK_THROWS_WITH(net.add_place({.id = "P5", .initial_tokens = 3, .capacity = 2}), Catch::Contains("capacity"));
}
