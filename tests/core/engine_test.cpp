#include "tripodal/core/engine.hpp"

#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include <catch2/catch.hpp>

#include "engine_test_nets.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/net_history.hpp"

using namespace tripodal;
using tripodal::test::make_place;
using tripodal::test::make_transition;

namespace {

Time at(double seconds) { return time_from_seconds(seconds); }

PlaceIndex place_of(const PetriNet& net, std::string_view id) { return *net.find_place(id); }

/// Steps once and returns the ids of the transitions fired in that step.
std::vector<std::string> fired(Engine& engine, HistoryRecorder& history, Time now,
                               std::initializer_list<std::string_view> events = {}) {
  const std::size_t before = history.size();
  engine.step(now, events);
  std::vector<std::string> ids;
  for (std::size_t i = before; i < history.size(); ++i) ids.push_back(history.firings()[i].transition_id);
  return ids;
}

using Ids = std::vector<std::string>;

}  // namespace

TEST_CASE("API example: run a two-step net with an event") {
  // The example of docs/engine.md.
  PetriNet net;
  net.add_place(Place{.id = "idle", .initial_tokens = 1});
  net.add_place(Place{.id = "working"});
  net.add_place(Place{.id = "done", .outcome = Outcome::success});
  net.add_transition(Transition{.id = "start"});  // immediate
  net.add_transition(Transition{.id = "finish", .event = "work.done"});
  net.add_arc("idle", "start");
  net.add_arc("start", "working");
  net.add_arc("working", "finish");
  net.add_arc("finish", "done");

  Engine engine(net);
  HistoryRecorder history;
  engine.add_observer(history);
  engine.step(time_from_seconds(0.0));  // fires start
  CHECK(engine.outcome().outcome == Outcome::none);
  const StepResult& r = engine.step(time_from_seconds(1.0), {"work.done"});  // fires finish
  CHECK(r.ok());
  CHECK(r.firings == 1);
  CHECK(engine.outcome().outcome == Outcome::success);
  CHECK(engine.outcome().place_id == "done");
  CHECK(history.transition_ids() == Ids{"start", "finish"});
}

TEST_CASE("input arcs need their weight and consume it, output arcs produce") {
  PetriNet net;
  net.add_place(make_place("a", 1));
  net.add_place(make_place("b"));
  net.add_transition(make_transition("t"));
  net.add_arc("a", "t", 2);
  net.add_arc("t", "b", 3);
  Engine engine(net);
  CHECK_FALSE(engine.is_enabled(0));
  CHECK(engine.step(at(0)).firings == 0);

  PetriNet net2 = net;
  net2.place(0).initial_tokens = 5;
  Engine e2(net2);
  HistoryRecorder h;
  e2.add_observer(h);
  CHECK(e2.step(at(0)).firings == 2);  // 5 -> 3 -> 1, then not enabled
  CHECK(e2.tokens(0) == 1);
  CHECK(e2.tokens(1) == 6);
  REQUIRE(h.size() == 2);
  const auto& changes = h.firings()[0].changes;
  REQUIRE(changes.size() == 2);
  CHECK(changes[0].place == 0);
  CHECK(changes[0].consumed == 2);
  CHECK(changes[0].produced == 0);
  CHECK(changes[1].place == 1);
  CHECK(changes[1].produced == 3);
  CHECK(h.firings()[0].marking_after == Marking{3, 3});
}

TEST_CASE("read arcs test without consuming") {
  PetriNet net;
  net.add_place(make_place("ready", 2));
  net.add_place(make_place("src", 3));
  net.add_place(make_place("dst"));
  net.add_transition(make_transition("t"));
  net.add_arc("ready", "t", 2, ArcKind::read);
  net.add_arc("src", "t");
  net.add_arc("t", "dst");
  Engine engine(net);
  CHECK(engine.step(at(0)).firings == 3);
  CHECK(engine.tokens(0) == 2);
  CHECK(engine.tokens(2) == 3);

  net.place(0).initial_tokens = 1;  // below the read weight
  Engine blocked(net);
  CHECK(blocked.step(at(0)).firings == 0);
}

TEST_CASE("inhibitor arcs enable only below their weight") {
  PetriNet net;
  net.add_place(make_place("stop", 0));
  net.add_place(make_place("src", 5));
  net.add_place(make_place("dst"));
  net.add_transition(make_transition("t"));
  net.add_arc("stop", "t", 2, ArcKind::inhibitor);
  net.add_arc("src", "t");
  net.add_arc("t", "stop");  // each firing adds to the inhibiting place
  Engine engine(net);
  CHECK(engine.step(at(0)).firings == 2);  // stop: 0 -> 1 -> 2, then inhibited
  CHECK(engine.tokens(0) == 2);
  CHECK(engine.tokens(1) == 3);
}

TEST_CASE("capacity: a firing that would exceed an output place's capacity is not enabled") {
  PetriNet net;
  Place buf = make_place("buf", 0);
  buf.capacity = 2;
  net.add_place(std::move(buf));
  net.add_place(make_place("src", 10));
  net.add_transition(make_transition("fill"));
  net.add_arc("src", "fill");
  net.add_arc("fill", "buf");
  Engine engine(net);
  CHECK(engine.step(at(0)).firings == 2);
  CHECK(engine.tokens(0) == 2);

  SECTION("consumption from the same place counts") {
    PetriNet loop;
    Place p = make_place("p", 2);
    p.capacity = 2;
    loop.add_place(std::move(p));
    loop.add_place(make_place("q", 0));
    Transition t = make_transition("swap", "go");
    loop.add_transition(std::move(t));
    loop.add_arc("p", "swap", 1);
    loop.add_arc("swap", "p", 1);  // full place, but takes one before putting one back
    loop.add_arc("swap", "q");
    Engine e(loop);
    CHECK(e.is_enabled(0));
    CHECK(e.step(at(0), {"go"}).firings == 1);
    CHECK(e.tokens(0) == 2);
    CHECK(e.tokens(1) == 1);
  }
  SECTION("a gain above the capacity never fires") {
    PetriNet big;
    Place p = make_place("p", 0);
    p.capacity = 1;
    big.add_place(std::move(p));
    big.add_transition(make_transition("t"));
    big.add_arc("t", "p", 2);
    Engine e(big);
    CHECK_FALSE(e.is_enabled(0));
    CHECK(e.step(at(0)).firings == 0);
  }
}

TEST_CASE("conflict: higher priority first, then declaration order") {
  PetriNet net;
  net.add_place(make_place("p", 1));
  net.add_place(make_place("a"));
  net.add_place(make_place("b"));
  net.add_place(make_place("c"));
  net.add_transition(make_transition("ta"));
  net.add_transition(make_transition("tb"));
  net.add_transition(make_transition("tc"));
  for (const char* t : {"ta", "tb", "tc"}) net.add_arc("p", t);
  net.add_arc("ta", "a");
  net.add_arc("tb", "b");
  net.add_arc("tc", "c");

  SECTION("equal priorities: the first declared wins") {
    Engine e(net);
    e.step(at(0));
    CHECK(e.marking()[1] == 1);
  }
  SECTION("the highest priority wins") {
    net.transition(2).priority = 5;
    net.transition(1).priority = 3;
    Engine e(net);
    e.step(at(0));
    CHECK(e.marking()[3] == 1);
  }
  SECTION("negative priorities lose to the default") {
    net.transition(0).priority = -1;
    Engine e(net);
    e.step(at(0));
    CHECK(e.marking()[2] == 1);
  }
}

TEST_CASE("an event is consumed once, by the highest-priority enabled transition waiting for it") {
  PetriNet net;
  net.add_place(make_place("p", 3));
  net.add_place(make_place("low"));
  net.add_place(make_place("high"));
  net.add_place(make_place("blocked", 0));
  net.add_transition(make_transition("t_low", "go", 0));
  net.add_transition(make_transition("t_high", "go", 2));
  net.add_transition(make_transition("t_blocked", "go", 9));
  net.add_arc("p", "t_low");
  net.add_arc("t_low", "low");
  net.add_arc("p", "t_high");
  net.add_arc("t_high", "high");
  net.add_arc("blocked", "t_blocked");  // highest priority but not enabled
  net.add_arc("t_blocked", "low");

  Engine e(net);
  HistoryRecorder h;
  e.add_observer(h);
  CHECK(fired(e, h, at(0)).empty());  // event transitions wait
  CHECK(fired(e, h, at(1), {"go"}) == Ids{"t_high"});
  CHECK(fired(e, h, at(2), {"go", "go"}) == Ids{"t_high", "t_high"});
  const StepResult& r = e.step(at(3), {"go"});  // p is empty now
  CHECK(r.firings == 0);
  CHECK(r.unconsumed_events == std::vector<std::string>{"go"});
}

TEST_CASE("events are not latched: an event nobody waits for is dropped and reported") {
  PetriNet net;
  net.add_place(make_place("idle", 0));
  net.add_place(make_place("lost"));
  net.add_place(make_place("start", 1));
  net.add_transition(make_transition("on_lost", "localizer.lost"));
  net.add_transition(make_transition("begin", "go"));
  net.add_arc("idle", "on_lost");
  net.add_arc("on_lost", "lost");
  net.add_arc("start", "begin");
  net.add_arc("begin", "idle");

  Engine e(net);
  const StepResult& r = e.step(at(0), {"localizer.lost", "no.such.event"});
  CHECK(r.firings == 0);
  CHECK(r.unconsumed_events == std::vector<std::string>{"localizer.lost", "no.such.event"});
  e.step(at(1), {"go"});
  CHECK(e.tokens(place_of(net, "idle")) == 1);
  // The stale "lost" of time 0 does not fire now that on_lost is enabled.
  CHECK(e.step(at(2)).firings == 0);
  CHECK(e.tokens(place_of(net, "lost")) == 0);
  CHECK(e.step(at(3), {"localizer.lost"}).firings == 1);
  CHECK(e.tokens(place_of(net, "lost")) == 1);
}

TEST_CASE("events are processed in posting order, the net settling after each") {
  PetriNet net;
  net.add_place(make_place("a", 1));
  net.add_place(make_place("b"));
  net.add_place(make_place("c"));
  net.add_place(make_place("d"));
  net.add_transition(make_transition("ab", "x"));
  net.add_transition(make_transition("bc"));  // immediate
  net.add_transition(make_transition("cd", "y"));
  net.add_arc("a", "ab");
  net.add_arc("ab", "b");
  net.add_arc("b", "bc");
  net.add_arc("bc", "c");
  net.add_arc("c", "cd");
  net.add_arc("cd", "d");
  Engine e(net);
  HistoryRecorder h;
  e.add_observer(h);
  SECTION("y after x: the immediate transition in between has made c marked") {
    CHECK(fired(e, h, at(0), {"x", "y"}) == Ids{"ab", "bc", "cd"});
  }
  SECTION("y before x: y finds nothing and is dropped") {
    const StepResult& r = e.step(at(0), {"y", "x"});
    CHECK(r.unconsumed_events == std::vector<std::string>{"y"});
    CHECK(h.transition_ids() == Ids{"ab", "bc"});
    CHECK(e.tokens(place_of(net, "c")) == 1);
  }
}

TEST_CASE("a delayed transition fires once continuously enabled for its delay") {
  PetriNet net;
  net.add_place(make_place("waiting", 1));
  net.add_place(make_place("timed_out"));
  net.add_place(make_place("block", 0));
  Transition t = make_transition("timeout");
  t.delay = from_seconds(2.0);
  net.add_transition(std::move(t));
  net.add_transition(make_transition("set_block", "block"));
  net.add_transition(make_transition("clear_block", "unblock"));
  net.add_arc("waiting", "timeout");
  net.add_arc("timeout", "timed_out");
  net.add_arc("block", "timeout", 1, ArcKind::inhibitor);
  net.add_place(make_place("src", 5));
  net.add_arc("src", "set_block");
  net.add_arc("set_block", "block");
  net.add_arc("block", "clear_block");

  Engine e(net);
  HistoryRecorder h;
  e.add_observer(h);
  REQUIRE(e.next_deadline() == at(2.0));

  SECTION("fires at its deadline") {
    CHECK(fired(e, h, at(1.999)).empty());
    CHECK(fired(e, h, at(2.0)) == Ids{"timeout"});
    CHECK_FALSE(e.next_deadline().has_value());
  }
  SECTION("a coarse step fires it at its deadline, not at the step's time") {
    CHECK(fired(e, h, at(10.0)) == Ids{"timeout"});
    CHECK(h.firings().back().time == at(2.0));
    CHECK(e.now() == at(10.0));
  }
  SECTION("becoming disabled resets the timer") {
    CHECK(fired(e, h, at(1.5), {"block"}) == Ids{"set_block"});
    CHECK_FALSE(e.next_deadline().has_value());
    CHECK(fired(e, h, at(3.0), {"unblock"}) == Ids{"clear_block"});
    REQUIRE(e.next_deadline() == at(5.0));
    CHECK(fired(e, h, at(4.9)).empty());
    CHECK(fired(e, h, at(5.0)) == Ids{"timeout"});
  }
}

TEST_CASE("due delayed transitions fire in deadline order, each with what it enables") {
  PetriNet net;
  net.add_place(make_place("a", 1));
  net.add_place(make_place("b", 1));
  net.add_place(make_place("a2"));
  net.add_place(make_place("b2"));
  net.add_place(make_place("a3"));
  Transition slow = make_transition("slow");
  slow.delay = from_seconds(3.0);
  slow.priority = 10;  // priority does not reorder different deadlines
  net.add_transition(std::move(slow));
  Transition fast = make_transition("fast");
  fast.delay = from_seconds(1.0);
  net.add_transition(std::move(fast));
  Transition follow = make_transition("follow");
  follow.delay = from_seconds(1.0);
  net.add_transition(std::move(follow));
  net.add_arc("a", "slow");
  net.add_arc("slow", "a2");
  net.add_arc("b", "fast");
  net.add_arc("fast", "b2");
  net.add_arc("b2", "follow");  // enabled at 1.0 by fast, due at 2.0
  net.add_arc("follow", "a3");
  Engine e(net);
  HistoryRecorder h;
  e.add_observer(h);
  CHECK(fired(e, h, at(5.0)) == Ids{"fast", "follow", "slow"});
  CHECK(h.firings()[0].time == at(1.0));
  CHECK(h.firings()[1].time == at(2.0));
  CHECK(h.firings()[2].time == at(3.0));
}

// step(now) without events fires a timer due alone on a path of its own (Engine::Impl::fire_until);
// what it enables must still settle at its deadline, before later timers, and ties go through the
// ready set in rank order.
TEST_CASE("step(now): a timer due alone fires at its deadline, then what it enables, then later timers") {
  PetriNet net;
  net.add_place(make_place("a", 1));
  net.add_place(make_place("b"));
  net.add_place(make_place("c"));
  net.add_place(make_place("d"));
  net.add_place(make_place("x", 1));
  net.add_place(make_place("y"));
  Transition first = make_transition("first");
  first.delay = from_seconds(1.0);
  net.add_transition(std::move(first));
  net.add_transition(make_transition("then"));  // immediate, enabled by first
  Transition second = make_transition("second");
  second.delay = from_seconds(1.0);
  net.add_transition(std::move(second));
  Transition tie = make_transition("tie");  // due at 2.0 with second; declared later: fires after it
  tie.delay = from_seconds(2.0);
  net.add_transition(std::move(tie));
  net.add_arc("a", "first");
  net.add_arc("first", "b");
  net.add_arc("b", "then");
  net.add_arc("then", "c");
  net.add_arc("c", "second");
  net.add_arc("second", "d");
  net.add_arc("x", "tie");
  net.add_arc("tie", "y");

  SECTION("observed") {
    Engine e(net);
    HistoryRecorder h;
    e.add_observer(h);
    CHECK(e.step(at(0.5)).firings == 0);
    const StepResult& r = e.step(at(1.5));
    CHECK(r.ok());
    CHECK(r.firings == 2);
    REQUIRE(h.transition_ids() == Ids{"first", "then"});
    CHECK(h.firings()[0].time == at(1.0));
    CHECK(h.firings()[1].time == at(1.0));
    CHECK(e.now() == at(1.5));
    CHECK(e.step(at(10.0)).firings == 2);
    REQUIRE(h.transition_ids() == Ids{"first", "then", "second", "tie"});
    CHECK(h.firings()[2].time == at(2.0));
    CHECK(h.firings()[3].time == at(2.0));
    CHECK(e.now() == at(10.0));
  }
  SECTION("unobserved: one coarse step") {
    Engine e(net);
    const StepResult& r = e.step(at(10.0));
    CHECK(r.ok());
    CHECK(r.firings == 4);
    CHECK(e.tokens(place_of(net, "d")) == 1);
    CHECK(e.tokens(place_of(net, "y")) == 1);
    CHECK_FALSE(e.next_deadline().has_value());
  }
}

TEST_CASE("step(now): a timer due alone that starts an immediate cycle ends in a livelock") {
  PetriNet net;
  net.add_place(make_place("start", 1));
  net.add_place(make_place("spin"));
  Transition go = make_transition("go");
  go.delay = from_seconds(1.0);
  net.add_transition(std::move(go));
  net.add_transition(make_transition("loop"));
  net.add_arc("start", "go");
  net.add_arc("go", "spin");
  net.add_arc("spin", "loop");
  net.add_arc("loop", "spin");
  EngineOptions options;
  options.max_firings_per_instant = 10;
  Engine e(net, {}, options);
  const StepResult& r = e.step(at(2.0));
  CHECK(r.status == StepStatus::livelock);
  CHECK(r.firings == 10);
  CHECK(r.loop == std::vector<TransitionIndex>{*net.find_transition("loop")});
}

TEST_CASE("an event transition with a delay takes its event only after the delay") {
  PetriNet net;
  net.add_place(make_place("p", 1));
  net.add_place(make_place("q"));
  Transition t = make_transition("confirm", "ok");
  t.delay = from_seconds(1.0);
  net.add_transition(std::move(t));
  net.add_arc("p", "confirm");
  net.add_arc("confirm", "q");
  Engine e(net);
  CHECK_FALSE(e.next_deadline().has_value());  // event transitions do not time
  CHECK(e.step(at(0.5), {"ok"}).unconsumed_events.size() == 1);
  CHECK(e.step(at(1.0), {"ok"}).firings == 1);
}

namespace {
PetriNet guarded_net() {
  PetriNet net;
  net.id = "guarded";
  net.parameters.push_back(VariableDecl{"mode", ValueType::string, Value{std::string("auto")}, "", {}});
  net.parameters.push_back(VariableDecl{"speed_m_s", ValueType::number, std::nullopt, "", {}});
  net.facts.push_back(VariableDecl{"battery_low", ValueType::boolean, Value{false}, "", {}});
  net.facts.push_back(VariableDecl{"door", ValueType::string, std::nullopt, "", {}});
  net.add_place(make_place("p", 1));
  net.add_place(make_place("charging"));
  net.add_place(make_place("fast"));
  net.add_place(make_place("through"));
  Transition charge = make_transition("charge");
  charge.guard = Guard::parse("battery_low && mode == 'auto'");
  net.add_transition(std::move(charge));
  Transition go_fast = make_transition("go_fast", "go");
  go_fast.guard = Guard::parse("speed_m_s > 0.5");
  net.add_transition(std::move(go_fast));
  Transition pass = make_transition("pass");
  pass.guard = Guard::parse("door == 'open'");
  net.add_transition(std::move(pass));
  net.add_arc("p", "charge");
  net.add_arc("charge", "charging");
  net.add_arc("p", "go_fast");
  net.add_arc("go_fast", "fast");
  net.add_arc("p", "pass");
  net.add_arc("pass", "through");
  return net;
}
}  // namespace

TEST_CASE("guards read parameters (defaults applied) and facts, a fact change re-examines") {
  const PetriNet net = guarded_net();
  Engine e(net, {{"speed_m_s", Value{1.0}}});
  CHECK(std::get<std::string>(e.parameter("mode")) == "auto");
  CHECK(e.is_enabled(1));        // speed 1.0 > 0.5, waits for "go"
  CHECK_FALSE(e.is_enabled(0));  // battery_low defaults to false
  CHECK_FALSE(e.is_enabled(2));  // door unknown: guard false
  CHECK(e.step(at(0)).firings == 0);

  SECTION("setting a fact enables, the next step fires") {
    e.set_fact("battery_low", Value{true});
    CHECK(e.is_enabled(0));
    CHECK(e.step(at(1)).firings == 1);
    CHECK(e.tokens(place_of(net, "charging")) == 1);
  }
  SECTION("set, cleared and unknown facts") {
    const FactId door = *e.fact_id("door");
    CHECK(e.fact(door) == nullptr);
    e.set_fact(door, Value{std::string("closed")});
    CHECK_FALSE(e.is_enabled(2));
    e.set_fact(door, Value{std::string("open")});
    CHECK(e.is_enabled(2));
    e.clear_fact(door);
    CHECK_FALSE(e.is_enabled(2));
    CHECK(e.step(at(1)).firings == 0);
  }
  SECTION("a parameter selects the branch") {
    Engine slow(net, {{"speed_m_s", Value{0.2}}, {"mode", Value{std::string("manual")}}});
    slow.set_fact("battery_low", Value{true});
    CHECK_FALSE(slow.is_enabled(0));
    CHECK_FALSE(slow.is_enabled(1));
  }
  SECTION("bad facts are errors naming them") {
    CHECK_THROWS_WITH(e.set_fact("battery", Value{true}), Catch::Contains("unknown fact 'battery'"));
    CHECK_THROWS_WITH(e.set_fact("battery_low", Value{1.0}),
                      Catch::Contains("fact 'battery_low' is a bool") && Catch::Contains("number 1"));
  }
}

TEST_CASE("parameters: missing, mistyped, unknown, and guards over undeclared names are errors") {
  const PetriNet net = guarded_net();
  CHECK_THROWS_AS(Engine(net), ConfigError);
  CHECK_THROWS_WITH(Engine(net), Catch::Contains("missing required parameter 'speed_m_s' (number)"));
  CHECK_THROWS_WITH(Engine(net, {{"speed_m_s", Value{std::string("fast")}}}),
                    Catch::Contains("parameter 'speed_m_s'") && Catch::Contains("must be a number"));
  CHECK_THROWS_WITH(Engine(net, {{"speed_m_s", Value{1.0}}, {"colour", Value{true}}}),
                    Catch::Contains("unknown parameter 'colour'") && Catch::Contains("mode, speed_m_s"));

  PetriNet bad = net;
  bad.transition(0).guard = Guard::parse("batery_low");
  bad.transition(0).where = SourceLocation{"guarded.xml", 12, 5};
  CHECK_THROWS_WITH(Engine(bad, {{"speed_m_s", Value{1.0}}}),
                    Catch::Contains("guarded.xml:12:5") && Catch::Contains("reads 'batery_low'"));
  PetriNet mistyped = net;
  mistyped.transition(1).guard = Guard::parse("mode > 3");
  CHECK_THROWS_WITH(Engine(mistyped, {{"speed_m_s", Value{1.0}}}),
                    Catch::Contains("uses parameter 'mode' (string) as a number"));
  // Every problem is reported at once.
  try {
    Engine e(mistyped, {{"colour", Value{true}}});
    FAIL("expected ConfigError");
  } catch (const ConfigError& error) {
    CHECK(error.diagnostics().error_count() == 3);
  }
}

TEST_CASE("immediate transitions cycling are stopped with a livelock naming the loop") {
  PetriNet net;
  net.id = "cycle";
  net.add_place(make_place("start", 1));
  net.add_place(make_place("a"));
  net.add_place(make_place("b"));
  net.add_place(make_place("c"));
  net.add_transition(make_transition("enter"));
  net.add_transition(make_transition("ab"));
  net.add_transition(make_transition("bc"));
  net.add_transition(make_transition("ca"));
  net.add_arc("start", "enter");
  net.add_arc("enter", "a");
  net.add_arc("a", "ab");
  net.add_arc("ab", "b");
  net.add_arc("b", "bc");
  net.add_arc("bc", "c");
  net.add_arc("c", "ca");
  net.add_arc("ca", "a");

  EngineOptions options;
  options.max_firings_per_instant = 100;
  Engine e(net, {}, options);
  HistoryRecorder h;
  e.add_observer(h);
  const StepResult& r = e.step(at(0), {"never"});
  CHECK(r.status == StepStatus::livelock);
  CHECK(r.firings == 100);
  CHECK(h.size() == 100);
  CHECK(r.loop.size() == 3);
  CHECK_THAT(r.error, Catch::Contains("livelock in net 'cycle'") && Catch::Contains("ab") &&
                          Catch::Contains("bc") && Catch::Contains("ca") && !Catch::Contains("enter"));
  CHECK(r.unconsumed_events == std::vector<std::string>{"never"});  // not reached
  // The engine stays consistent: one token in the cycle.
  CHECK(e.tokens(1) + e.tokens(2) + e.tokens(3) == 1);
  CHECK(to_string(r.status) == "livelock");

  SECTION("the default budget also stops it") {
    Engine d(net);
    CHECK(d.options().max_firings_per_instant == 100'000);
    const StepResult& rd = d.step(at(0));
    CHECK(rd.status == StepStatus::livelock);
    CHECK(rd.firings == 100'000);
  }
}

TEST_CASE("a step's result starts empty whatever the previous step filled in (livelock, dropped events, time error)") {
  PetriNet net;
  net.add_place(make_place("start", 1));
  net.add_place(make_place("a"));
  net.add_place(make_place("b"));
  net.add_transition(make_transition("enter"));
  net.add_transition(make_transition("ab"));
  net.add_transition(make_transition("ba"));
  net.add_arc("start", "enter");
  net.add_arc("enter", "a");
  net.add_arc("a", "ab");
  net.add_arc("ab", "b");
  net.add_arc("b", "ba");
  net.add_arc("ba", "a");
  EngineOptions options;
  options.max_firings_per_instant = 10;
  Engine e(net, {}, options);
  const StepResult& r = e.step(at(0), {"never"});
  REQUIRE(r.status == StepStatus::livelock);
  REQUIRE_FALSE(r.loop.empty());
  REQUIRE_FALSE(r.error.empty());
  REQUIRE(r.unconsumed_events.size() == 1);
  // The next step livelocks again (the cycle is still enabled): what it reports is its own.
  const StepResult& again = e.step(at(1));
  CHECK(again.unconsumed_events.empty());
  CHECK(again.loop.size() == 2);

  // A net that goes quiet: its idle steps report nothing of the step before.
  Engine quiet(test::ring_net(3, from_seconds(1.0)));
  CHECK(quiet.step(at(5), {"no.such.event"}).unconsumed_events.size() == 1);
  REQUIRE(quiet.step(at(4)).status == StepStatus::time_regressed);
  const StepResult& idle = quiet.step(at(5));
  CHECK(idle.ok());
  CHECK(idle.firings == 0);
  CHECK(idle.error.empty());
  CHECK(idle.unconsumed_events.empty());
  CHECK(idle.loop.empty());
  CHECK(idle.activated.empty());
  CHECK(idle.deactivated.empty());
}

TEST_CASE("a budget of zero is rejected") {
  EngineOptions options;
  options.max_firings_per_instant = 0;
  CHECK_THROWS_WITH(Engine(test::ring_net(3), {}, options), Catch::Contains("max_firings_per_instant"));
}

TEST_CASE("a step to an earlier time is refused without changes") {
  Engine e(test::ring_net(3, from_seconds(1.0)));
  e.step(at(5));
  const StepResult& r = e.step(at(4));
  CHECK(r.status == StepStatus::time_regressed);
  CHECK_THAT(r.error, Catch::Contains("earlier"));
  CHECK(e.now() == at(5));
}

TEST_CASE("behavior bindings: active places and activated/deactivated per step") {
  PetriNet net;
  net.add_place(make_place("idle", 1));
  Place clean = make_place("clean");
  clean.behavior = BehaviorBinding{"BhCleaning", {}};
  net.add_place(std::move(clean));
  Place dock = make_place("dock");
  dock.behavior = BehaviorBinding{"BhDocking", {}};
  net.add_place(std::move(dock));
  net.add_transition(make_transition("start", "go"));
  net.add_transition(make_transition("switch", "switch"));
  net.add_transition(make_transition("back", "back"));
  net.add_arc("idle", "start");
  net.add_arc("start", "clean");
  net.add_arc("clean", "switch");
  net.add_arc("switch", "dock");
  net.add_arc("dock", "back");
  net.add_arc("back", "clean");

  Engine e(net);
  CHECK(e.active_bindings().empty());
  const StepResult& r1 = e.step(at(0), {"go"});
  CHECK(r1.activated == std::vector<PlaceIndex>{1});
  CHECK(r1.deactivated.empty());
  CHECK(e.active_bindings() == std::vector<PlaceIndex>{1});
  const StepResult& r2 = e.step(at(1), {"switch"});
  CHECK(r2.activated == std::vector<PlaceIndex>{2});
  CHECK(r2.deactivated == std::vector<PlaceIndex>{1});
  // Deactivated and re-activated within one step: no change to report.
  const StepResult& r3 = e.step(at(2), {"back", "switch"});
  CHECK(r3.firings == 2);
  CHECK(r3.activated.empty());
  CHECK(r3.deactivated.empty());

  SECTION("initially marked bindings are reported by the first step") {
    PetriNet marked = net;
    marked.place(1).initial_tokens = 1;
    Engine m(marked);
    CHECK(m.step(at(0)).activated == std::vector<PlaceIndex>{1});
    CHECK(m.step(at(1)).activated.empty());
  }
}

TEST_CASE("outcome: fault wins over success, lowest place first") {
  PetriNet net;
  for (const char* id : {"ok1", "ok2", "bad1", "bad2"}) net.add_place(make_place(id));
  net.place(0).outcome = Outcome::success;
  net.place(1).outcome = Outcome::success;
  net.place(2).outcome = Outcome::fault;
  net.place(2).fault_message = "first fault";
  net.place(3).outcome = Outcome::fault;
  net.place(3).fault_message = "second fault";
  net.add_transition(make_transition("s2", "s2"));
  net.add_transition(make_transition("f2", "f2"));
  net.add_transition(make_transition("f1", "f1"));
  net.add_arc("s2", "ok2");
  net.add_arc("f2", "bad2");
  net.add_arc("f1", "bad1");
  Engine e(net);
  CHECK(e.outcome().outcome == Outcome::none);
  e.step(at(0), {"s2"});
  CHECK(e.outcome().outcome == Outcome::success);
  CHECK(e.outcome().place_id == "ok2");
  CHECK(e.outcome().message.empty());
  e.step(at(1), {"f2"});
  CHECK(e.outcome().outcome == Outcome::fault);
  CHECK(e.outcome().message == "second fault");
  e.step(at(2), {"f1"});
  CHECK(e.outcome().place == 2);
  CHECK(e.outcome().message == "first fault");
}

TEST_CASE("observers see every firing until removed, reset restarts the net") {
  Engine e(test::ring_net(4, from_seconds(1.0)));
  HistoryRecorder a;
  HistoryRecorder b;
  e.add_observer(a);
  e.add_observer(b);
  e.step(at(1));
  CHECK(a.transition_ids() == Ids{"T0", "T1", "T2", "T3"});
  CHECK(b.sequence() == std::vector<TransitionIndex>{0, 1, 2, 3});
  e.remove_observer(b);
  e.step(at(2));
  CHECK(a.size() == 8);
  CHECK(b.size() == 4);
  CHECK(a.firings()[4].time == at(2));
  e.reset(at(10));
  CHECK(e.now() == at(10));
  CHECK(e.next_deadline() == at(11));
  CHECK(e.tokens(0) == 1);
}

TEST_CASE("firings and dropped events are logged at debug level on 'tripodal.engine'") {
  Engine e(test::ring_net(2, Duration{0}, "tick"));
  auto logger = spdlog::get("tripodal.engine");
  REQUIRE(logger != nullptr);
  auto sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(16);
  logger->sinks().push_back(sink);
  const auto old_level = logger->level();
  logger->set_level(spdlog::level::debug);
  e.step(at(0.5), {"tick", "tock"});
  logger->set_level(old_level);
  logger->sinks().pop_back();
  const auto lines = sink->last_formatted();
  std::string all;
  for (const auto& l : lines) all += l;
  CHECK_THAT(all, Catch::Contains("fire T0 at 0.500000 s on event tick"));
  CHECK_THAT(all, Catch::Contains("fire T1"));
  CHECK_THAT(all, Catch::Contains("event tock at 0.500000 s dropped"));
}

// --- the paper's PrCleaning net (Fig. 3 / Table 2) -------------------------------------------

TEST_CASE("PrCleaning: the wheel_type parameter selects BhCleaning or BhCleaningTwoWheel") {
  const PetriNet net = test::pr_cleaning_net();
  Engine diff(net, {{"wheel_type", Value{std::string("differential")}}});
  const StepResult& r = diff.step(at(0));
  REQUIRE(r.activated.size() == 1);
  CHECK(net.place(r.activated[0]).behavior->behavior == "BhCleaning");

  Engine two(net, {{"wheel_type", Value{std::string("two_wheel")}}});
  const StepResult& r2 = two.step(at(0));
  REQUIRE(r2.activated.size() == 1);
  CHECK(net.place(r2.activated[0]).behavior->behavior == "BhCleaningTwoWheel");

  CHECK_THROWS_WITH(Engine(net), Catch::Contains("missing required parameter 'wheel_type'"));
}

TEST_CASE("PrCleaning: normal completion") {
  const PetriNet net = test::pr_cleaning_net();
  Engine e(net, {{"wheel_type", Value{std::string("differential")}}});
  HistoryRecorder h;
  e.add_observer(h);
  CHECK(fired(e, h, at(0)) == Ids{"t0"});
  CHECK(fired(e, h, at(30), {"BhCleaning.done"}) == Ids{"t4"});
  const OutcomeState o = e.outcome();
  CHECK(o.outcome == Outcome::success);
  CHECK(o.place_id == "P5");
  CHECK(e.step(at(31)).ok());
}

TEST_CASE("PrCleaning: temporary localization loss, recovery, then completion") {
  const PetriNet net = test::pr_cleaning_net(5.0);
  Engine e(net, {{"wheel_type", Value{std::string("two_wheel")}}});
  HistoryRecorder h;
  e.add_observer(h);
  CHECK(fired(e, h, at(0)) == Ids{"t1"});
  CHECK(fired(e, h, at(10), {"localizer.lost"}) == Ids{"t3"});
  CHECK(e.next_deadline() == at(15));  // t7 times the loss
  // Completion is not accepted while lost.
  CHECK(e.step(at(12), {"BhCleaningTwoWheel.done"}).unconsumed_events.size() == 1);
  CHECK(fired(e, h, at(14.5), {"localizer.ok"}) == Ids{"t2"});
  CHECK_FALSE(e.next_deadline().has_value());
  CHECK(fired(e, h, at(100)).empty());
  CHECK(fired(e, h, at(101), {"BhCleaningTwoWheel.done"}) == Ids{"t6"});
  CHECK(e.outcome().outcome == Outcome::success);
  CHECK(e.outcome().place_id == "P7");
}

TEST_CASE("PrCleaning: persistent localization loss ends in 'localization fault'") {
  const PetriNet net = test::pr_cleaning_net(5.0);
  Engine e(net, {{"wheel_type", Value{std::string("differential")}}});
  HistoryRecorder h;
  e.add_observer(h);
  e.step(at(0));
  e.step(at(10), {"localizer.lost"});
  CHECK(fired(e, h, at(14.999)).empty());
  const StepResult& r = e.step(at(15));
  CHECK(r.deactivated == std::vector<PlaceIndex>{place_of(net, "P1")});
  CHECK(h.transition_ids() == Ids{"t0", "t3", "t5"});
  const OutcomeState o = e.outcome();
  CHECK(o.outcome == Outcome::fault);
  CHECK(o.place_id == "P6");
  CHECK(o.message == "localization fault");
  CHECK(e.active_bindings().empty());
}
