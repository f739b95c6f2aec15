// The analysis of nets loaded from files: the PNML models of tests/data/pnml (written by others,
// with published state-space figures) and every shipped configuration net under configs/petri.
#include <catch2/catch.hpp>

#include <filesystem>

#include "analysis_test_nets.hpp"
#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/core/net_loader.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

namespace {
const std::filesystem::path kData = TRIPODAL_TEST_DATA_DIR;
}

TEST_CASE("Kanban2-test001.pnml: 4,600 states, 28,120 edges, no deadlock", "[analysis][files]") {
  const PetriNet net = load_net_or_throw(kData / "pnml" / "Kanban2-test001.pnml");
  REQUIRE(net.places().size() == 16);
  REQUIRE(net.transitions().size() == 16);
  const AnalysisReport r = analyze(net, {.semantics = Semantics::interleaving});
  CHECK(r.complete());
  CHECK(r.states == 4600);
  CHECK(r.edges == 28120);
  CHECK(r.deadlock_count == 0);
  CHECK(r.bounded == Verdict::pass);
  CHECK(r.dead_transitions.empty());
  CHECK(r.p_invariants.invariants.size() == 6);
  // The generated Kanban of the benchmarks is the same net.
  const AnalysisReport generated = analyze(test::kanban_net(2), {.semantics = Semantics::interleaving});
  CHECK(generated.states == r.states);
  CHECK(generated.edges == r.edges);
}

TEST_CASE("deadlock-test018.pnml: the initial marking is dead", "[analysis][files]") {
  const PetriNet net = load_net_or_throw(kData / "pnml" / "deadlock-test018.pnml");
  const AnalysisReport r = analyze(net, {.semantics = Semantics::interleaving});
  CHECK(r.states == 1);
  CHECK(r.edges == 0);
  REQUIRE(r.deadlock_count == 1);
  CHECK(r.deadlocks[0].path.empty());
  CHECK(r.deadlocks[0].state == 0);
  CHECK(r.dead_transitions.size() == 1);
  CHECK_THAT(format_text(r, net), Catch::Contains("path (0 firings): (initial marking)"));
}
