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

TEST_CASE("ids of every length are found exactly, across table growth") {
  // The id table keeps ids of up to 7 bytes inside its slots and longer ones by hash: ids on both
  // sides of that line, ids that differ only in their last byte or their length, and bytes that
  // are not letters (a NUL too: the building API takes any bytes) must all stay distinct.
  std::vector<std::string> ids;
  for (int i = 0; i < 3000; ++i) ids.push_back("P" + std::to_string(i));  // 2 to 5 bytes
  for (const std::string stem : {"abcdef", "abcdefg", "abcdefgh", "state_machine_"}) {
    for (char c = 'a'; c <= 'z'; ++c) ids.push_back(stem + c);  // 7, 8, 9 and 15 bytes
  }
  ids.push_back("x");
  ids.push_back(std::string("x\0", 2));
  ids.push_back(std::string("x\0\0", 3));
  ids.push_back("\xC3\xA9tat");  // UTF-8

  PetriNet net;  // no reserve: the table grows many times on the way
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (i % 2 == 0) net.add_place({.id = ids[i]});
    else net.add_transition({.id = ids[i]});
  }
  for (std::size_t i = 0; i < ids.size(); ++i) {
    INFO("id " << i << " '" << ids[i] << "'");
    if (i % 2 == 0) {
      REQUIRE(net.find_place(ids[i]) == PlaceIndex(i / 2));
      CHECK_FALSE(net.find_transition(ids[i]));
    } else {
      REQUIRE(net.find_transition(ids[i]) == TransitionIndex(i / 2));
      CHECK_FALSE(net.find_place(ids[i]));
    }
    CHECK_THROWS_WITH(net.add_place({.id = ids[i]}), Catch::Contains("duplicate node id"));
  }
  for (const std::string missing : {"P3000", "abcdef", "abcdef{", "abcdefg{", "abcdefgh{", "state_machine_", "state_machine_{", "y", "P"}) {
    INFO("missing '" << missing << "'");
    CHECK_FALSE(net.find_place(missing));
    CHECK_FALSE(net.find_transition(missing));
    CHECK(net.find_node_where(missing) == nullptr);
  }
  CHECK_FALSE(net.find_place(std::string("x\0\0\0", 4)));
}

TEST_CASE("prefetch_node is a hint that leaves the net as it was") {
  PetriNet net;
  net.prefetch_node("p");  // an empty net: no table yet
  net.add_place({.id = "p"});
  net.prefetch_node("p");
  net.prefetch_node("not there");
  net.prefetch_node("");
  CHECK(net.places().size() == 1);
  CHECK(net.find_place("p") == PlaceIndex(0));
  CHECK_FALSE(net.find_place("not there"));
}

TEST_CASE("new_place and new_transition add a node to be filled in where it lies") {
  PetriNet net;
  net.reserve(2, 1);
  Place& p = net.new_place("P0", SourceLocation{"net.xml", 3, 5});
  p.initial_tokens = 1;
  p.description = "filled in place";
  Transition& t = net.new_transition("T0");
  t.priority = 2;
  net.new_place("P1");
  net.add_arc("P0", "T0");
  net.add_arc("T0", "P1");
  CHECK(net.place(0).name == "P0");  // the name defaults to the id, as with add_place
  CHECK(net.place(0).description == "filled in place");
  CHECK(net.place(0).where.str() == "net.xml:3:5");
  CHECK(net.initial_marking() == Marking{1, 0});
  CHECK(net.transition(0).priority == 2);
  CHECK(net.find_place("P1") == PlaceIndex{1});
  CHECK_THROWS_WITH(net.new_transition("P1"), Catch::Contains("duplicate node id 'P1'"));
  CHECK_THROWS_WITH(net.new_place(""), Catch::Contains("must not be empty"));
  CHECK(net.places().size() == 2);
  CHECK(net.transitions().size() == 1);
}
