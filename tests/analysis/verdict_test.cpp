// Verification that does not over-promise (issue 40): guards with the parameters known and the
// facts unknown, behaviors started twice, nets that grow without end, process nets without an
// outcome, parameter sets, and the assumption a verdict rests on. Through the analyzer API on the
// corpus of wrong nets (tests/data/nets/wrong/, also run through tripodal-net by CTest).
#include <catch2/catch.hpp>
#include <filesystem>

#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/core/net_loader.hpp"

using namespace tripodal;
using namespace tripodal::analysis;
using Catch::Contains;

namespace {

const std::filesystem::path kWrong = std::filesystem::path(TRIPODAL_TEST_DATA_DIR) / "nets" / "wrong";

PetriNet wrong(const char* name) {
  return load_net_or_throw(kWrong / name);
}

std::string check_text(const PetriNet& net, const BehaviourCheckOptions& o,
                       BehaviourCheckResult* result = nullptr) {
  Diagnostics d;
  const BehaviourCheckResult r = check_behaviour_detailed(net, d, o);
  if (result != nullptr) *result = r;
  return d.str();
}

std::string load_errors(const char* name) {
  Diagnostics d;
  const auto net = load_net(kWrong / name, d);
  CHECK_FALSE(net.has_value());
  return d.str();
}

}  // namespace

TEST_CASE("a guard false by its parameter part makes its transition dead, whatever the facts",
          "[analysis][verdict]") {
  const PetriNet net = wrong("false_parameter_guard_hang.xml");
  const AnalysisReport r = analyze(net);
  // Before: the guard read a fact, so it was "may be true" and the net passed.
  CHECK(r.deadlock_count == 1);
  CHECK(r.outcome == Verdict::fail);
  CHECK_FALSE(r.ok());
  REQUIRE(r.guard_false.size() == 1);
  CHECK(net.transition(r.guard_false[0]).id == "undock");
  CHECK(r.assumed_facts.empty());  // nothing rests on the fact: the guard is decided
  BehaviourCheckResult result;
  const std::string text = check_text(net, {}, &result);
  CHECK_FALSE(result.checked);
  CHECK_THAT(
      text,
      Contains(
          "error: deadlock: nothing can fire in marking charged, reached by start -> plugged [BhDock.done]"));
  CHECK_THAT(text, Contains("warning: transition 'undock' never fires (guard 'auto_charge && battery_percent "
                            ">= full_percent')"));

  // With auto_charge true the verdict is OK, but it rests on the fact: the result says which.
  const ParameterValues live{{"auto_charge", Value{true}}};
  const AnalysisReport ok = analyze(net, {.parameters = live});
  CHECK(ok.ok());
  CHECK(ok.assumed_facts == std::vector<std::string>{"battery_percent"});
  CHECK_THAT(format_text(ok, net),
             Contains("verdict: OK under the assumption that fact battery_percent can take any value"));
  const std::string checked = check_text(net, {.parameter_sets = {live}}, &result);
  CHECK(result.checked);
  CHECK(result.assumed_facts == std::vector<std::string>{"battery_percent"});
  CHECK(assumption_text(result.assumed_facts) ==
        "the assumption that fact battery_percent can take any value");
}

TEST_CASE("each parameter set is checked, and the errors name it", "[analysis][verdict]") {
  const PetriNet net = wrong("false_parameter_guard_hang.xml");
  BehaviourCheckOptions o;
  o.parameter_sets = {{{"auto_charge", Value{false}}, {"full_percent", Value{90.0}}},
                      {{"auto_charge", Value{true}}, {"full_percent", Value{100.0}}}};
  BehaviourCheckResult result;
  const std::string text = check_text(net, o, &result);
  CHECK(result.parameter_sets == 2);
  CHECK_FALSE(result.checked);
  CHECK_THAT(
      text,
      Contains("with auto_charge=false, full_percent=90: deadlock: nothing can fire in marking charged"));
  CHECK_THAT(text, !Contains("with auto_charge=true"));
  // undock fires for the second set: no warning.
  CHECK_THAT(text, !Contains("never fires"));
}

TEST_CASE("a behavior place that can hold two tokens is an error with its firing sequence",
          "[analysis][verdict]") {
  const PetriNet net = wrong("behavior_started_twice.xml");
  const AnalysisReport r = analyze(net);
  CHECK(r.complete());
  CHECK(r.safe == Verdict::fail);
  REQUIRE(r.double_started.size() == 1);
  CHECK(net.place(r.double_started[0].place).id == "moving");
  REQUIRE(r.double_started[0].witness.path.size() == 2);
  CHECK_FALSE(r.ok());  // before: "1-safe: NO" and "verdict: OK"
  CHECK_THAT(format_text(r, net), Contains("behaviors started twice: 1"));
  const std::string text = check_text(net, {});
  CHECK_THAT(
      text,
      Contains("behavior_started_twice.xml:10:3: error: behavior 'BhMove' is started twice: place 'moving' "
               "holds 2 tokens in marking moving*2, reached by start -> cleared [obstacle.cleared]"));
}

TEST_CASE("a place that grows without end is an error with the cycle that fills it", "[analysis][verdict]") {
  const PetriNet net = wrong("unbounded_process.xml");
  const AnalysisReport r = analyze(net, {.max_states = 2'000});
  CHECK_FALSE(r.complete());
  REQUIRE(r.growth.has_value());
  CHECK(r.growth->confirmed());
  CHECK(net.place(r.growth->place).id == "log");
  REQUIRE(r.growth->pump.size() == 1);
  CHECK(net.transition(r.growth->pump[0]).id == "tick");
  CHECK(r.bounded == Verdict::fail);
  CHECK(r.bounds[r.growth->place].kind == BoundKind::unbounded);
  CHECK_THAT(format_text(r, net), Contains("UNBOUNDED (pumping cycle)") && Contains("  log: unbounded"));
  BehaviourCheckOptions o;
  o.max_states = 2'000;
  BehaviourCheckResult result;
  const std::string text = check_text(net, o, &result);
  CHECK_FALSE(result.checked);
  CHECK_THAT(
      text,
      Contains("error: unbounded: place 'log' grows without end: after start, the cycle tick [timer.tick] "
               "can fire again and again"));
  CHECK_THAT(text, !Contains("behaviour not checked"));
}

TEST_CASE("a process net without an outcome place is an error, a PNML net is not a process net",
          "[analysis][verdict]") {
  const PetriNet net = wrong("no_outcome_place.xml");
  CHECK_THAT(check_text(net, {}), Contains("error: net 'PrLoop' has no outcome place"));
  BehaviourCheckResult result;
  const std::string text = check_text(net, {.process_net = false}, &result);
  CHECK_THAT(text, !Contains("no outcome place"));
  CHECK(result.checked);
}

TEST_CASE("an outcome no marking can reach, a dead branch, a read arc never satisfied",
          "[analysis][verdict]") {
  CHECK_THAT(
      check_text(wrong("outcome_unreachable.xml"), {}),
      Contains("error: no outcome place can be reached from marking idle, reached by the initial marking"));
  BehaviourCheckResult result;
  const std::string dead = check_text(wrong("dead_transition.xml"), {}, &result);
  CHECK(result.checked);  // a warning, not an error
  CHECK_THAT(dead, Contains("warning: transition 'shortcut' never fires"));
  CHECK_THAT(check_text(wrong("read_arc_never_marked.xml"), {}),
             Contains("error: deadlock: nothing can fire in marking work, reached by start"));
}

TEST_CASE("unknown names in a net get a suggestion", "[analysis][verdict][loader]") {
  CHECK_THAT(
      load_errors("dangling_arc_typo.xml"),
      Contains(
          "dangling_arc_typo.xml:19:16: error: arc from unknown node 'aproach'; did you mean 'approach'?"));
  const std::string events = load_errors("unknown_event_typo.xml");
  CHECK_THAT(
      events,
      Contains("error: unknown event 'BhAproach.done': no place of net 'PrDock' binds 'BhAproach'; did "
               "you mean 'BhApproach.done'?"));
  CHECK_THAT(events,
             Contains("error: unknown event 'BhApproach.fail': 'BhApproach' posts BhApproach.done and "
                      "BhApproach.failed; did you mean 'BhApproach.failed'?"));
  const std::string params = load_errors("unknown_parameter_typo.xml");
  CHECK_THAT(params, Contains("unknown parameter 'retries_alowed' in guard of transition 'again'"));
  CHECK_THAT(params, Contains("did you mean 'retries_allowed'?"));
  CHECK_THAT(params, Contains("did you mean '$speed_m_s'?"));
  CHECK_THAT(load_errors("inhibitor_arc_reversed.xml"),
             Contains("error: a inhibitor arc goes from a place to a transition, not from transition 'start' "
                      "to place 'busy'"));

  // Behaviors and processes: the names the loader is given.
  LoadOptions o;
  o.is_known_behavior = [](std::string_view n) { return n == "BhApproach"; };
  o.behavior_names = {"BhApproach"};
  Diagnostics d;
  const auto net = load_net_from_string(
      R"(<net id="n" level="low" version="1"><place id="p" tokens="1"><behavior name="BhAproach"/></place></net>)",
      "typo.xml", d, o);
  CHECK_FALSE(net.has_value());
  CHECK_THAT(d.str(), Contains("unknown behavior 'BhAproach'; did you mean 'BhApproach'?"));
  // Module events are not the net's to know: no error for a lower-case source.
  Diagnostics quiet;
  CHECK(load_net_from_string(
            R"(<net id="n" level="low" version="1"><place id="p" tokens="1"><behavior name="BhDock"/></place>
      <transition id="t" event="dock.arrived"/><arc source="p" target="t"/></net>)",
            "module.xml", quiet, {})
            .has_value());
}
