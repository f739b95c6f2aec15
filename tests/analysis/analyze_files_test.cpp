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

TEST_CASE("The worked example of docs/analysis.md: a deadlock after a failed alignment, and its fix", "[analysis][files]") {
  const PetriNet broken = load_net_or_throw(kData / "analysis" / "docking_deadlock.xml");
  const AnalysisReport r = analyze(broken);
  REQUIRE(r.deadlock_count == 1);
  CHECK(r.deadlocks[0].marking[*broken.find_place("retry")] == 1);
  CHECK(r.outcome == Verdict::fail);
  CHECK(r.dead_transitions == std::vector<TransitionIndex>{*broken.find_transition("again")});
  const std::string text = format_text(r, broken);
  CHECK_THAT(text, Catch::Contains("path (3 firings): start -> close [BhApproach.done] -> misaligned [BhAlign.failed]"));
  CHECK_THAT(text, Catch::Contains("events needed: BhApproach.done, BhAlign.failed"));
  // Allowing retries removes the deadlock; so does the fixed net with its give_up transition.
  AnalysisOptions retries;
  retries.parameters = parse_parameter_assignments(broken, {"retries_allowed=true"});
  CHECK(analyze(broken, retries).ok());
  const PetriNet fixed = load_net_or_throw(kData / "analysis" / "docking_fixed.xml");
  CHECK(analyze(fixed).ok());
  Diagnostics d;
  CHECK_FALSE(check_behaviour(broken, d));
  CHECK_THAT(d.str(), Catch::Contains("docking_deadlock.xml") && Catch::Contains("error: deadlock: nothing can fire in marking retry, reached by start -> close [BhApproach.done] -> misaligned [BhAlign.failed]"));
  CHECK_THAT(d.str(), Catch::Contains("error: no outcome place can be reached from marking retry"));
  Diagnostics ok;
  CHECK(check_behaviour(fixed, ok));
  CHECK_FALSE(ok.has_errors());
}

TEST_CASE("check_behaviour notes nets it cannot decide instead of failing them", "[analysis][files]") {
  const PetriNet kanban = load_net_or_throw(kData / "pnml" / "Kanban2-test001.pnml");
  Diagnostics d;
  CHECK_FALSE(check_behaviour(kanban, d, {.semantics = Semantics::interleaving, .max_states = 1000}));
  CHECK_FALSE(d.has_errors());
  CHECK_THAT(d.str(), Catch::Contains("note: behaviour not checked: more than 1000 reachable states"));
  CHECK(default_semantics_for("a/b/Kanban.PNML", "") == Semantics::interleaving);
  CHECK(default_semantics_for("net.xml", "<?xml version=\"1.0\"?>\n<pnml xmlns=") == Semantics::interleaving);
  CHECK(default_semantics_for("net.xml", "<net id=\"x\">") == Semantics::engine);
}

TEST_CASE("check_behaviour tries each value the guards name for a parameter without default", "[analysis][files]") {
  // Without a default, retries_allowed is checked false and true: the fixed net passes both.
  PetriNet fixed = load_net_or_throw(kData / "analysis" / "docking_fixed.xml");
  fixed.parameters[0].default_value.reset();
  Diagnostics f;
  CHECK(check_behaviour(fixed, f));
  CHECK(f.empty());
  // The broken net deadlocks only with retries_allowed=false, and the error says so.
  PetriNet broken = load_net_or_throw(kData / "analysis" / "docking_deadlock.xml");
  broken.parameters[0].default_value.reset();
  Diagnostics b;
  CHECK_FALSE(check_behaviour(broken, b));
  CHECK(b.error_count() == 2);
  CHECK_THAT(b.str(), Catch::Contains("error: with retries_allowed=false: deadlock: nothing can fire in marking retry"));
  CHECK_THAT(b.str(), !Catch::Contains("retries_allowed=true"));
  // PrCleaning: wheel_type has no default; both wheel types the guards name are verified.
  const PetriNet cleaning = load_net_or_throw(kData / ".." / ".." / "configs" / "petri" / "PrCleaning.xml");
  const auto& t0 = *cleaning.transition(*cleaning.find_transition("t0")).guard;
  CHECK(t0.compared_literals(0) == std::vector<Value>{Value{std::string("omni")}});
  Diagnostics c;
  CHECK(check_behaviour(cleaning, c));
  CHECK(c.empty());
  // The net is written for these two wheel types only: with another one the token stays in P0
  // (localization can still change, so no deadlock, but no outcome is ever reached).
  AnalysisOptions other;
  other.parameters = parse_parameter_assignments(cleaning, {"wheel_type=tracked"});
  const AnalysisReport r = analyze(cleaning, other);
  CHECK(r.deadlock_count == 0);
  CHECK(r.outcome == Verdict::fail);
}
