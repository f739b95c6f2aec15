#include "tripodal/core/net_simulation.hpp"

#include <catch2/catch.hpp>

#include "engine_test_nets.hpp"

using namespace tripodal;

namespace {
const ParameterValues kDifferential{{"wheel_type", Value{std::string("differential")}}};

using Ids = std::vector<std::string>;

Ids fired_ids(const SimulationResult& r) {
  Ids ids;
  for (const auto& e : r.trace) {
    if (e.kind == TraceEntry::Kind::firing) ids.push_back(e.name);
  }
  return ids;
}
}  // namespace

TEST_CASE("simulation: PrCleaning completes normally") {
  const PetriNet net = test::pr_cleaning_net();
  NetSimulation sim(net, kDifferential);
  const SimulationResult r = sim.run(parse_event_script("20 BhCleaning.done\n"));
  CHECK(r.status == StepStatus::ok);
  CHECK(fired_ids(r) == Ids{"t0", "t4"});
  CHECK(r.outcome == Outcome::success);
  CHECK(r.outcome_place == "P5");
  CHECK(r.end_time == time_from_seconds(20));
  const std::string text = r.str(net);
  CHECK_THAT(text, Catch::Contains("     0.000 s  fire t0  Start behavior BhCleaning  -> P1 P3"));
  CHECK_THAT(text, Catch::Contains("    20.000 s  fire t4 [BhCleaning.done]"));
  CHECK_THAT(text, Catch::Contains("end: success at P5; marking P3 P5"));
}

TEST_CASE("simulation: temporary loss, recovery, completion") {
  const PetriNet net = test::pr_cleaning_net(5.0);
  NetSimulation sim(net, kDifferential);
  const SimulationResult r = sim.run(parse_event_script(
      "2 localizer.lost\n"
      "4 BhCleaning.done   # refused while lost\n"
      "6.5 localizer.ok\n"
      "30 BhCleaning.done\n"));
  CHECK(fired_ids(r) == Ids{"t0", "t3", "t2", "t4"});
  REQUIRE(r.trace[2].kind == TraceEntry::Kind::event_dropped);
  CHECK(r.trace[2].name == "BhCleaning.done");
  CHECK(r.trace[2].time == time_from_seconds(4));
  CHECK(r.outcome == Outcome::success);
  CHECK_THAT(r.str(net), Catch::Contains("drop BhCleaning.done"));
}

TEST_CASE("simulation: persistent loss ends in a localization fault at the delay deadline") {
  const PetriNet net = test::pr_cleaning_net(5.0);
  NetSimulation sim(net, {{"wheel_type", Value{std::string("two_wheel")}}});
  const SimulationResult r = sim.run(parse_event_script("2 localizer.lost\n60 localizer.ok\n"));
  CHECK(fired_ids(r) == Ids{"t1", "t3", "t7"});
  CHECK(r.trace.back().time == time_from_seconds(7));  // stepped at the deadline, not at the next event
  CHECK(r.outcome == Outcome::fault);
  CHECK(r.outcome_place == "P8");
  CHECK(r.fault_message == "localization fault");
  CHECK(r.end_time == time_from_seconds(7));  // stopped at the outcome
  CHECK_THAT(r.str(net), Catch::Contains("end: fault at P8: localization fault"));
}

TEST_CASE("simulation: end time, running on after an outcome, and reuse") {
  const PetriNet net = test::pr_cleaning_net(5.0);
  SimulationOptions options;
  options.end_time = time_from_seconds(4);
  NetSimulation sim(net, kDifferential, options);
  const EventScript script = parse_event_script("2 localizer.lost\n");
  const SimulationResult r = sim.run(script);
  CHECK(r.outcome == Outcome::none);
  CHECK(r.end_time == time_from_seconds(4));
  const SimulationResult again = sim.run(script);  // starts over from the initial marking
  CHECK(fired_ids(again) == fired_ids(r));

  SimulationOptions on;
  on.stop_at_outcome = false;
  on.end_time = time_from_seconds(100);
  NetSimulation keep_going(net, kDifferential, on);
  const SimulationResult k = keep_going.run(parse_event_script("1 BhCleaning.done\n50 localizer.lost\n"));
  CHECK(fired_ids(k) == Ids{"t0", "t4", "t3"});
  CHECK(k.end_time == time_from_seconds(100));
}

TEST_CASE("simulation: facts set by the script drive guards") {
  PetriNet net;
  net.id = "charge";
  net.facts.push_back(VariableDecl{"battery_low", ValueType::boolean, Value{false}, "", {}});
  net.facts.push_back(VariableDecl{"room", ValueType::string, std::nullopt, "", {}});
  net.add_place(test::make_place("work", 1));
  net.add_place(test::make_place("dock"));
  Transition t = test::make_transition("go_dock");
  t.guard = Guard::parse("battery_low && room != 'lab'");
  net.add_transition(std::move(t));
  net.add_arc("work", "go_dock");
  net.add_arc("go_dock", "dock");
  NetSimulation sim(net, {});
  const SimulationResult r = sim.run(parse_event_script("1 set room lab\n2 set battery_low true\n3 set room 'hall'\n"));
  CHECK(fired_ids(r) == Ids{"go_dock"});
  CHECK(r.trace.back().time == time_from_seconds(3));
  CHECK_THAT(r.str(net), Catch::Contains("set battery_low = true") && Catch::Contains("set room = \"hall\""));
}

TEST_CASE("simulation: the script is checked against the net with line:col errors") {
  PetriNet net = test::pr_cleaning_net();
  net.facts.push_back(VariableDecl{"battery_low", ValueType::boolean, std::nullopt, "", {}});
  NetSimulation sim(net, kDifferential);
  const EventScript script = parse_event_script(
      "1 localiser.lost\n"
      "2 set batery_low true\n"
      "3 set battery_low maybe\n",
      "bad.script");
  CHECK_THROWS_WITH(sim.run(script), Catch::Contains("bad.script:1:3") && Catch::Contains("'localiser.lost'") &&
                                         Catch::Contains("bad.script:2:7") && Catch::Contains("unknown fact 'batery_low'") &&
                                         Catch::Contains("bad.script:3:19") && Catch::Contains("not a bool"));
  SimulationOptions lax;
  lax.allow_unknown_events = true;
  NetSimulation lenient(net, kDifferential, lax);
  const SimulationResult r = lenient.run(parse_event_script("1 somebody.else\n"));
  REQUIRE(r.trace.size() == 2);
  CHECK(r.trace[1].kind == TraceEntry::Kind::event_dropped);
}

TEST_CASE("simulation: a livelock ends the run with the engine's error") {
  PetriNet net;
  net.id = "spin";
  net.add_place(test::make_place("a", 1));
  net.add_transition(test::make_transition("spin"));
  net.add_arc("a", "spin");
  net.add_arc("spin", "a");
  SimulationOptions options;
  options.engine.max_firings_per_instant = 10;
  NetSimulation sim(net, {}, options);
  const SimulationResult r = sim.run(parse_event_script(""));
  CHECK(r.status == StepStatus::livelock);
  CHECK_THAT(r.error, Catch::Contains("spin"));
  CHECK(r.trace.back().kind == TraceEntry::Kind::error);
  CHECK_THAT(r.str(net), Catch::Contains("error: livelock"));
}
