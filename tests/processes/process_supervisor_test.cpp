// CProcessSupervisor: behavior activation with resolved parameters, events from behaviors and
// modules, delays, outcomes, and run-time failures that become faults without stopping the loop.
#include <catch2/catch.hpp>

#include <functional>
#include <thread>

#include "doubles.hpp"
#include "tripodal/processes/process_registry.hpp"
#include "tripodal/processes/process_supervisor.hpp"

using namespace tripodal;
using namespace tripodal::test;

namespace {

ProcessDefinition def(std::string name, PetriNet net) {
  ProcessDefinition d;
  d.name = std::move(name);
  d.net = std::move(net);
  return d;
}

// Records what the observers see, one line per item.
struct Lines final : SupervisorObserver {
  std::vector<std::string> lines;
  void on_run_started(std::string_view run, const CProcess& p, const ParameterValues&, Time now) override {
    lines.push_back(FakeBehaviors::stamp(now) + " start " + std::string(run) + " " + p.name());
  }
  void on_run_finished(const ProcessResult& r) override {
    lines.push_back(FakeBehaviors::stamp(r.finished) + " end " + r.run + (r.success ? " success" : " fault: " + r.message));
  }
  void on_firing(std::string_view run, const PetriNet&, const Firing& f) override {
    lines.push_back(FakeBehaviors::stamp(f.time) + " " + std::string(run) + " fire " + std::string(f.transition_id));
  }
  void on_fault(std::string_view source, std::string_view reason, Time now) override {
    lines.push_back(FakeBehaviors::stamp(now) + " fault " + std::string(source) + ": " + std::string(reason));
  }
};

struct Rig {
  SimClock clock;
  FakeBehaviors behaviors;
  ProcessRegistry processes;
  CProcessSupervisor supervisor;
  Lines lines;
  std::vector<ProcessResult> results;

  explicit Rig(SupervisorOptions o = {}) : supervisor(behaviors, clock, o) {
    behaviors.add("BhCleaning", 10.0);
    behaviors.add("BhAutoMove", 3.0);
    behaviors.add("BhGlobalLocalization", 2.0);
    processes.add(def("PrCleaning", pr_cleaning(5.0)));
    processes.add(def("PrAutoMove", pr_auto_move(5.0)));
    supervisor.add_observer(lines);
  }

  void start(const std::string& run, const std::string& process, std::vector<BindingParam> params) {
    BoundParameters b = processes.find(process)->bind(params);
    REQUIRE(b.ok);
    std::string error;
    REQUIRE(supervisor.start(run, *processes.find(process), b.values, &error));
    supervisor.step();  // as the planner does: the net starts at once
    for (auto& r : supervisor.take_results()) results.push_back(r);
  }

  // Steps every 0.1 s up to `end_s`, calling `at(t)` before each supervisor step.
  void run(double end_s, const std::function<void(double)>& at = {}) {
    const Duration dt = from_seconds(0.1);
    for (int i = 0; to_seconds(clock.now()) < end_s - 1e-9; ++i) {
      clock.advance(dt);
      behaviors.advance(clock.now(), dt);
      if (at) at(to_seconds(clock.now()));
      supervisor.step();
      for (auto& r : supervisor.take_results()) results.push_back(r);
    }
  }
};

bool near(double t, double x) { return t > x - 0.05 && t < x + 0.05; }

}  // namespace

TEST_CASE("Supervisor activates the bound behavior with resolved parameters and reports success", "[processes]") {
  Rig rig;
  rig.start("X0", "PrCleaning", {{"section", "A", {}}});  // t = 0: the net starts the behavior
  CHECK(rig.behaviors.active("BhCleaning"));
  CHECK(rig.supervisor.active_behaviors() == std::vector<std::string>{"BhCleaning"});
  REQUIRE(rig.behaviors.log.size() == 1);
  CHECK(rig.behaviors.log[0] == "t=0.000 activate BhCleaning(pattern=balloon, section=A)");
  rig.run(12.0);
  REQUIRE(rig.results.size() == 1);
  const ProcessResult& r = rig.results[0];
  CHECK(r.success);
  CHECK(r.run == "X0");
  CHECK(r.process == "PrCleaning");
  CHECK(r.place == "P5");
  CHECK(to_seconds(r.finished) == Approx(10.0));
  CHECK_FALSE(rig.behaviors.active("BhCleaning"));
  CHECK(rig.behaviors.log.back() == "t=10.000 deactivate BhCleaning");
  CHECK(rig.supervisor.idle());
  // The observer saw the firings with the run id.
  CHECK(std::find(rig.lines.lines.begin(), rig.lines.lines.end(), "t=10.000 X0 fire t4") != rig.lines.lines.end());
}

TEST_CASE("A localization loss shorter than the delay only pauses the process", "[processes]") {
  Rig rig;
  rig.start("X0", "PrCleaning", {{"section", "A", {}}});
  rig.run(20.0, [&](double t) {
    if (near(t, 4.0)) {
      rig.behaviors.paused = true;
      rig.supervisor.post_event("localizer.lost");
    }
    if (near(t, 7.0)) {
      rig.behaviors.paused = false;
      rig.supervisor.post_event("localizer.ok");
    }
  });
  REQUIRE(rig.results.size() == 1);
  CHECK(rig.results[0].success);
  CHECK(to_seconds(rig.results[0].finished) == Approx(13.0));  // 10 s of work + 3 s paused
}

TEST_CASE("A completion that arrives while localization is lost is taken once it recovers", "[processes]") {
  Rig rig;
  rig.start("X0", "PrCleaning", {{"section", "A", {}}});
  // Lost at 9.5 s but the behavior keeps working: it completes at 10 s, when the net cannot
  // take "BhCleaning.done" (t4 reads P3); the supervisor offers it again until it can.
  rig.run(15.0, [&](double t) {
    if (near(t, 9.5)) rig.supervisor.post_event("localizer.lost");
    if (near(t, 12.0)) rig.supervisor.post_event("localizer.ok");
  });
  REQUIRE(rig.results.size() == 1);
  CHECK(rig.results[0].success);
  CHECK(to_seconds(rig.results[0].finished) == Approx(12.0));
}

TEST_CASE("A persistent localization loss ends in the fault place after the delay", "[processes]") {
  Rig rig;
  rig.start("X0", "PrCleaning", {{"section", "A", {}}});
  rig.run(20.0, [&](double t) {
    if (near(t, 4.0)) {
      rig.behaviors.paused = true;
      rig.supervisor.post_event("localizer.lost");
    }
  });
  REQUIRE(rig.results.size() == 1);
  const ProcessResult& r = rig.results[0];
  CHECK_FALSE(r.success);
  CHECK(r.message == "localization fault");
  CHECK(r.place == "P6");
  CHECK(to_seconds(r.finished) == Approx(9.0));
  CHECK_FALSE(rig.behaviors.active("BhCleaning"));
}

TEST_CASE("A behavior failure the net handles goes to its fault place", "[processes]") {
  Rig rig;
  rig.behaviors.specs["BhAutoMove"].fail = true;
  rig.start("X0", "PrAutoMove", {{"goal", "A.entry", {}}});
  rig.run(5.0);
  REQUIRE(rig.results.size() == 1);
  CHECK(rig.results[0].message == "path blocked");
  CHECK(rig.results[0].place == "P7");
  CHECK(std::find(rig.lines.lines.begin(), rig.lines.lines.end(), "t=3.000 fault BhAutoMove: blocked") != rig.lines.lines.end());
}

TEST_CASE("A behavior failure the net does not handle fails the process with its reason", "[processes]") {
  Rig rig;
  PetriNet net = pr_cleaning();
  net.transition(*net.find_transition("t6")).event = "never";  // remove the handler
  rig.processes.add(def("PrBare", net));
  rig.behaviors.specs["BhCleaning"].fail = true;
  rig.behaviors.specs["BhCleaning"].reason = "brush motor stalled";
  rig.start("X0", "PrBare", {{"section", "A", {}}});
  rig.run(12.0);
  REQUIRE(rig.results.size() == 1);
  CHECK(rig.results[0].message == "behavior BhCleaning failed: brush motor stalled");
  CHECK(rig.results[0].place.empty());
  CHECK(to_seconds(rig.results[0].finished) == Approx(10.0));
}

TEST_CASE("Throwing behaviors become faults and the supervisor goes on", "[processes]") {
  SECTION("activation throws") {
    Rig rig;
    rig.behaviors.specs["BhCleaning"].throw_on_activate = true;
    rig.start("X0", "PrCleaning", {{"section", "A", {}}});
    rig.start("X1", "PrAutoMove", {{"goal", "B", {}}});
    REQUIRE_NOTHROW(rig.run(5.0));
    REQUIRE(rig.results.size() == 2);
    CHECK(rig.results[0].run == "X0");
    CHECK(rig.results[0].message == "cleaning behavior failed");  // the net's handler of BhCleaning.failed
    CHECK(to_seconds(rig.results[0].finished) == Approx(0.0));
    CHECK(std::find(rig.lines.lines.begin(), rig.lines.lines.end(),
                    "t=0.000 fault BhCleaning: activation threw: driver not ready") != rig.lines.lines.end());
    CHECK(rig.results[1].run == "X1");  // the other process was not disturbed
    CHECK(rig.results[1].success);
  }
  SECTION("status query throws") {
    Rig rig;
    rig.behaviors.specs["BhAutoMove"].throw_on_report = true;
    rig.start("X0", "PrAutoMove", {{"goal", "B", {}}});
    REQUIRE_NOTHROW(rig.run(1.0));
    REQUIRE(rig.results.size() == 1);
    CHECK(rig.results[0].message == "path blocked");
    CHECK(std::find(rig.lines.lines.begin(), rig.lines.lines.end(),
                    "t=0.100 fault BhAutoMove: status query threw: status register unreadable") != rig.lines.lines.end());
  }
}

TEST_CASE("A behavior that stops answering fails after the watchdog timeout", "[processes]") {
  SupervisorOptions o;
  o.behavior_watchdog = from_seconds(0.5);
  Rig rig(o);
  rig.behaviors.specs["BhAutoMove"].silent = true;
  rig.start("X0", "PrAutoMove", {{"goal", "B", {}}});
  rig.run(3.0);
  REQUIRE(rig.results.size() == 1);
  CHECK(rig.results[0].message == "path blocked");
  CHECK(to_seconds(rig.results[0].finished) == Approx(0.6));
  CHECK(std::find(rig.lines.lines.begin(), rig.lines.lines.end(),
                  "t=0.600 fault BhAutoMove: stopped answering (no step for 0.600 s)") != rig.lines.lines.end());
}

TEST_CASE("Module watchdog: a silent module posts its event, unhandled module faults fail the processes", "[processes]") {
  SECTION("the localizer's silence is a localization loss the net handles with its delay") {
    Rig rig;
    rig.supervisor.watch_module("localizer", from_seconds(1.0), "localizer.lost");
    rig.start("X0", "PrCleaning", {{"section", "A", {}}});
    rig.run(20.0, [&](double t) {
      if (t < 3.0) rig.supervisor.heartbeat("localizer");
    });
    REQUIRE(rig.results.size() == 1);
    CHECK(rig.results[0].message == "localization fault");
    // Last heartbeat at 2.9 s, silent for 1 s -> lost at 3.9 s, fault 5 s later.
    CHECK(to_seconds(rig.results[0].finished) == Approx(8.9));
  }
  SECTION("a module fault without a handler fails every running process") {
    Rig rig;
    rig.supervisor.watch_module("laser", from_seconds(0.5));
    rig.start("X0", "PrCleaning", {{"section", "A", {}}});
    rig.run(3.0, [&](double t) {
      if (t < 1.0) rig.supervisor.heartbeat("laser");
    });
    REQUIRE(rig.results.size() == 1);
    CHECK(rig.results[0].message == "module laser failed: stopped answering (no heartbeat for 0.500 s)");
    CHECK(to_seconds(rig.results[0].finished) == Approx(1.4));
  }
  SECTION("a reported module fault the net handles is an ordinary event") {
    Rig rig;
    PetriNet net = pr_cleaning();
    net.transition(*net.find_transition("t3")).event = "localizer.fault";
    rig.processes.add(def("PrHandles", net));
    rig.start("X0", "PrHandles", {{"section", "A", {}}});
    rig.run(2.0, [&](double t) {
      if (near(t, 1.0)) rig.supervisor.report_module_fault("localizer", "scan matcher threw");
    });
    CHECK(rig.results.empty());  // the net took it: abnormal localization, waiting for the delay
    rig.run(7.0);
    REQUIRE(rig.results.size() == 1);
    CHECK(rig.results[0].message == "localization fault");
  }
}

TEST_CASE("stop() deactivates the behaviors and reports a fault", "[processes]") {
  Rig rig;
  rig.start("X0", "PrCleaning", {{"section", "A", {}}});
  rig.run(1.0);
  CHECK(rig.behaviors.active("BhCleaning"));
  CHECK(rig.supervisor.stop("X0", "task cancelled"));
  CHECK_FALSE(rig.supervisor.stop("X0"));
  CHECK_FALSE(rig.behaviors.active("BhCleaning"));
  auto results = rig.supervisor.take_results();
  REQUIRE(results.size() == 1);
  CHECK(results[0].message == "stopped: task cancelled");
  std::string error;
  const CProcess& p = *rig.processes.find("PrCleaning");
  CHECK(rig.supervisor.start("X0", p, p.bind({{"section", "A", {}}}).values, &error));
  CHECK_FALSE(rig.supervisor.start("X0", p, p.bind({{"section", "A", {}}}).values, &error));
  CHECK(error == "a process is already running as 'X0'");
  CHECK_FALSE(rig.supervisor.start("X9", p, ParameterValues{}, &error));
  CHECK_THAT(error, Catch::Contains("PrCleaning: ") && Catch::Contains("section"));
}

TEST_CASE("A livelocked process net becomes a fault, not a hang", "[processes]") {
  Rig rig;
  PetriNet net;
  net.id = "spin";
  net.add_place(place("A", 1));
  net.add_place(place("B"));
  Place done = place("D");
  done.outcome = Outcome::success;
  net.add_place(std::move(done));
  net.add_transition(transition("ab"));
  net.add_transition(transition("ba"));
  arcs(net, {{"A", "ab"}, {"ab", "B"}, {"B", "ba"}, {"ba", "A"}});
  rig.processes.add(def("PrSpin", net));
  SupervisorOptions o;
  o.engine.max_firings_per_instant = 50;
  CProcessSupervisor sup(rig.behaviors, rig.clock, o);
  REQUIRE(sup.start("X0", *rig.processes.find("PrSpin"), {}));
  sup.step();
  auto results = sup.take_results();
  REQUIRE(results.size() == 1);
  CHECK_THAT(results[0].message, Catch::Contains("livelock") && Catch::Contains("ab -> ba"));
}

TEST_CASE("Facts reach the running nets that declare them", "[processes]") {
  Rig rig;
  PetriNet net = pr_auto_move();
  net.facts.push_back(decl("battery_low", ValueType::boolean, Value{false}));
  Transition t = transition("t9");
  t.guard = Guard::parse("battery_low == true");
  net.add_transition(std::move(t));
  net.add_arc("P1", "t9");
  net.add_arc("t9", "P7");
  rig.processes.add(def("PrWatched", net));
  rig.start("X0", "PrWatched", {{"goal", "dock", {}}});
  rig.run(1.0, [&](double now_s) {
    if (near(now_s, 0.5)) rig.supervisor.set_fact("battery_low", Value{true});
  });
  REQUIRE(rig.results.size() == 1);
  CHECK(rig.results[0].place == "P7");
  CHECK(to_seconds(rig.results[0].finished) == Approx(0.5));
}

TEST_CASE("A process started after a fact was set begins with the fact's latest value, not its net's default",
          "[processes][facts]") {
  // The robot docked (charging) before the dock-and-charge process started: a module sets a fact
  // when it changes, so the net must not wait for a change that already happened.
  Rig rig;
  PetriNet net = pr_auto_move();
  net.facts.push_back(decl("battery_low", ValueType::boolean, Value{false}));
  Transition t = transition("t9");
  t.guard = Guard::parse("battery_low == true");
  net.add_transition(std::move(t));
  net.add_arc("P1", "t9");
  net.add_arc("t9", "P7");
  rig.processes.add(def("PrWatched", net));
  rig.supervisor.set_fact("battery_low", Value{false});
  rig.supervisor.set_fact("battery_low", Value{true});  // the latest counts
  rig.supervisor.set_fact("unrelated", Value{1.0});     // declared by no net: kept, harmless
  rig.supervisor.step();                                // no process runs yet
  rig.start("X0", "PrWatched", {{"goal", "dock", {}}});
  rig.run(0.2);
  REQUIRE(rig.results.size() == 1);
  CHECK(rig.results[0].place == "P7");
  CHECK(to_seconds(rig.results[0].finished) == Approx(0.0));
}

TEST_CASE("Modules post events, facts, heartbeats and faults from their own threads while the supervisor steps",
          "[processes][threads]") {
  // The supervisor's inbox is the one part of it other threads touch (scripts/tsan.sh runs this
  // under ThreadSanitizer); the counts are bounded, not timed.
  Rig rig;
  rig.supervisor.watch_module("localizer", from_seconds(100.0));
  rig.start("X0", "PrCleaning", {{"section", "A", {}}});
  bool done = false;
  std::vector<std::thread> modules;
  modules.emplace_back([&] {
    for (int i = 0; i < 200; ++i) rig.supervisor.post_event(i % 2 == 0 ? "localizer.lost" : "localizer.ok");
  });
  modules.emplace_back([&] {
    for (int i = 0; i < 200; ++i) rig.supervisor.heartbeat("localizer");
  });
  modules.emplace_back([&] {
    for (int i = 0; i < 200; ++i) rig.supervisor.set_fact("retries_allowed", Value(i % 2 == 0));
    rig.supervisor.report_module_fault("camera", "unplugged");
  });
  int steps = 0;
  for (; steps < 1000 && !done; ++steps) {
    rig.supervisor.step();
    for (auto& r : rig.supervisor.take_results()) rig.results.push_back(r);
    done = rig.results.size() == 1;
  }
  for (std::thread& t : modules) t.join();
  rig.supervisor.step();
  for (auto& r : rig.supervisor.take_results()) rig.results.push_back(r);
  // The camera fault reaches the run whatever the interleaving: nothing in PrCleaning consumes it.
  REQUIRE(rig.results.size() == 1);
  CHECK_FALSE(rig.results[0].success);
  CHECK_THAT(rig.results[0].message, Catch::Contains("module camera failed: unplugged"));
}
