// Verification of large nets whose state space is linear (issue 32, finding 8): a chain of
// 10,000 places is checked and analysed completely, the state limit of `tripodal-net check` is
// honoured exactly and named in the note, and a net of a million places stays within the limits
// instead of exhausting memory. Results and memory are asserted here; time only in
// bench/analysis (BM_CheckChain).
#include <catch2/catch.hpp>

#include "analysis_test_nets.hpp"
#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/net_simulation.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

TEST_CASE("A chain of 10,000 places is explored completely in a few MiB", "[analysis][large]") {
  const PetriNet chain = test::chain_net(10'000);
  ExploreOptions o;
  o.keep_edges = true;
  // A dense marking of 10,000 places takes 5,000 bytes: 10,000 of them would need 50 MB, 6x this cap.
  o.max_memory_bytes = std::size_t{8} << 20;
  const StateSpace s = explore(chain, o);
  CHECK(s.sparse());
  REQUIRE(s.complete());
  CHECK(s.states() == 10'000);
  CHECK(s.edges() == 9'999);
  CHECK(s.deadlocks().empty());
  REQUIRE(s.outcome_states().size() == 1);
  CHECK(s.marking(s.outcome_states()[0])[9'999] == 1);
  CHECK(s.path_to(s.outcome_states()[0]).size() == 9'999);
  CHECK(s.memory_bytes() <= o.max_memory_bytes);
  CHECK(s.bytes_per_marking() == 8);  // one marked place
}

TEST_CASE("check and analyze give the 10,000-place chain its verdict", "[analysis][large]") {
  const PetriNet chain = test::chain_net(10'000);
  Diagnostics d;
  CHECK(check_behaviour(chain, d));
  CHECK(d.empty());

  const AnalysisReport r = analyze(chain);
  REQUIRE(r.complete());
  CHECK(r.states == 10'000);
  CHECK(r.edges == 9'999);
  CHECK(r.deadlock_count == 0);
  CHECK(r.outcome == Verdict::pass);
  CHECK(r.bounded == Verdict::pass);
  CHECK(r.safe == Verdict::pass);
  CHECK(r.dead_transitions.empty());
  CHECK(r.ok());
  // Invariants and Karp–Miller grow faster than the net: skipped past the limit, and said so.
  CHECK(r.structure_skipped);
  CHECK_FALSE(r.invariants_computed);
  CHECK_FALSE(r.coverability_ran);
  const std::string text = format_text(r, chain);
  CHECK_THAT(text, Catch::Contains("invariants and coverability: not computed: 10000 places + 9999 transitions exceed "
                                   "the limit of 1000 (both grow faster than the net; raise it with "
                                   "--max-structural-size N)"));
  CHECK_THAT(text, Catch::EndsWith("verdict: OK\n"));
  CHECK_THAT(format_json(r, chain), Catch::Contains(R"("structure":{"max_size":1000,"skipped":true})"));
}

TEST_CASE("Below the structural limit a chain still gets its invariant", "[analysis][large]") {
  const PetriNet chain = test::chain_net(300);
  const AnalysisReport r = analyze(chain);
  CHECK_FALSE(r.structure_skipped);
  REQUIRE(r.invariants_computed);
  REQUIRE(r.p_invariants.invariants.size() == 1);
  CHECK(r.p_invariants.invariants[0].weights.size() == 300);
  CHECK(r.p_invariants.invariants[0].token_sum == 1);
  CHECK(r.ok());
}

TEST_CASE("check's state limit: at the limit it passes, one state over it is not checked", "[analysis][large]") {
  const PetriNet chain = test::chain_net(1'000);
  Diagnostics at;
  CHECK(check_behaviour(chain, at, {.max_states = 1'000}));
  CHECK(at.empty());

  Diagnostics over;
  CHECK_FALSE(check_behaviour(chain, over, {.max_states = 999}));
  CHECK_FALSE(over.has_errors());
  CHECK_THAT(over.str(), Catch::Contains("note: behaviour not checked: more than 999 reachable states: the exploration "
                                         "stopped at the limit of 999 states; raise it with --max-states N"));

  // analyze says INCOMPLETE, never OK, when the limit cut the search.
  AnalysisOptions o;
  o.max_states = 999;
  const AnalysisReport r = analyze(chain, o);
  CHECK_FALSE(r.ok());
  CHECK(r.states == 999);
  CHECK(r.outcome == Verdict::unknown);
  CHECK_THAT(format_text(r, chain), Catch::Contains("verdict: INCOMPLETE: not every reachable marking was explored "
                                                    "(more than 999 reachable states"));
}

TEST_CASE("check's memory limit is named with the option that raises it", "[analysis][large]") {
  const PetriNet chain = test::chain_net(20'000);
  Diagnostics d;
  CHECK_FALSE(check_behaviour(chain, d, {.max_states = 1'000'000, .max_memory_bytes = std::size_t{1} << 20}));
  CHECK_FALSE(d.has_errors());
  CHECK_THAT(d.str(), Catch::Contains("behaviour not checked: the state store would exceed the memory limit of 1 MiB "
                                      "after ") &&
                          Catch::Contains(" states; raise it with --max-memory-mb N"));
}

TEST_CASE("A net of a million places stays within the state limit and memory", "[analysis][large]") {
  const PetriNet chain = test::chain_net(1'000'000);
  // check: the default limit of 200,000 states stops it, with a note naming the limit.
  Diagnostics d;
  CHECK_FALSE(check_behaviour(chain, d));
  CHECK_FALSE(d.has_errors());
  CHECK_THAT(d.str(), Catch::Contains("more than 200000 reachable states: the exploration stopped at the limit of "
                                      "200000 states; raise it with --max-states N"));
  ExploreOptions o;
  o.keep_edges = true;
  o.max_states = kCheckStateLimit;
  const StateSpace limited = explore(chain, o);
  CHECK(limited.stop_reason() == StopReason::max_states);
  CHECK(limited.states() == kCheckStateLimit);
  // Sparse markings: tens of bytes per state, not the 500 KB a dense marking of this net takes.
  CHECK(limited.memory_bytes() < std::size_t{64} << 20);

  // analyze's larger default limit covers it: every state, within memory.
  const AnalysisReport r = analyze(chain);
  REQUIRE(r.complete());
  CHECK(r.states == 1'000'000);
  CHECK(r.ok());
  CHECK(r.memory_bytes < std::size_t{256} << 20);
}

TEST_CASE("Simulating a large net keeps only the marked places per firing", "[analysis][large]") {
  // A dense marking per trace entry would take 100,000 x 400 KB here.
  const PetriNet chain = test::chain_net(100'000);
  SimulationOptions o;
  o.engine.max_firings_per_instant = 200'000;
  NetSimulation simulation(chain, {}, o);
  const SimulationResult r = simulation.run({});
  REQUIRE(r.error.empty());
  CHECK(r.outcome == Outcome::success);
  CHECK(r.outcome_place == "p99999");
  REQUIRE(r.trace.size() == 99'999);
  CHECK(r.trace.back().marked_after == std::vector<std::pair<PlaceIndex, Tokens>>{{99'999, 1}});
  CHECK(r.trace[41].marked_after == std::vector<std::pair<PlaceIndex, Tokens>>{{42, 1}});
}
