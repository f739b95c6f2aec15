// CPlanner, the planner executive: commands, plan nets, process life cycle, recovery at quiet
// points, retry limits, refusals and determinism, with test doubles for behaviors and the
// section splitter and the paper's process nets built in code.
#include <catch2/catch.hpp>

#include <functional>

#include "../processes/doubles.hpp"
#include "tripodal/core/net_loader.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/planner/planner.hpp"

using namespace tripodal;
using namespace tripodal::test;

namespace {

ProcessDefinition def(std::string name, PetriNet net) {
  ProcessDefinition d;
  d.name = std::move(name);
  d.net = std::move(net);
  return d;
}

const char* kRecovery = R"(recovery:
  - fault: localization fault
    insert:
      - PrGlobalLocalization: {}
    then: retry
    max_retries: 2
  - fault: path blocked
    process: PrAutoMove
    then: skip
    max_retries: 1
)";

// A robot without a control loop: behaviors advance with the clock, a localizer double posts
// localizer.lost / localizer.ok when the world's localization changes, and global localization
// restores it.
struct World {
  SimClock clock;
  FakeBehaviors behaviors;
  FakeSectionSplitter splitter;
  ProcessRegistry processes;
  TaskLibrary tasks;
  RecoveryPolicy recovery;
  CProcessSupervisor supervisor{behaviors, clock};
  std::unique_ptr<CPlanner> planner;
  LifecycleRecorder life{true};
  bool localized = true;
  bool reported_localized = true;

  // with_modules: PrCleaning's module net is configs/petri/PrCleaning-module.xml (else the default)
  explicit World(bool with_modules = false) {
    behaviors.add("BhCleaning", 10.0);
    behaviors.add("BhAutoMove", 3.0);
    behaviors.add("BhGlobalLocalization", 2.0);
    ProcessDefinition cleaning = def("PrCleaning", pr_cleaning(5.0));
    if (with_modules) cleaning.module = load_net_or_throw(std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs/petri/PrCleaning-module.xml");
    processes.add(std::move(cleaning));
    processes.add(def("PrAutoMove", pr_auto_move(5.0)));
    processes.add(def("PrGlobalLocalization", pr_global_localization()));
    auto known = [&](std::string_view n) { return processes.contains(n); };
    tasks = TaskLibrary::load(std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs/tasks/cleaning.yaml", TaskLoadOptions{known});
    recovery = RecoveryPolicy::load_from_string(kRecovery, "recovery.yaml", known);
    planner = std::make_unique<CPlanner>(tasks, recovery, splitter, processes, supervisor, clock);
    planner->add_observer(life);
    supervisor.add_observer(life);
  }

  // Runs in 0.1 s periods until the task ends or `end_s`; `at(t)` scripts the world.
  void run(double end_s, const std::function<void(double)>& at = {}) {
    const Duration dt = from_seconds(0.1);
    planner->step();
    while (planner->busy() && to_seconds(clock.now()) < end_s - 1e-9) {
      clock.advance(dt);
      if (at) at(to_seconds(clock.now()));
      behaviors.paused = !localized && !behaviors.active("BhGlobalLocalization");
      behaviors.advance(clock.now(), dt);
      auto gl = behaviors.states.find("BhGlobalLocalization");
      if (gl != behaviors.states.end() && gl->second.active && gl->second.state == BehaviorStatus::succeeded) localized = true;
      if (localized != reported_localized) {
        supervisor.post_event(localized ? "localizer.ok" : "localizer.lost");
        reported_localized = localized;
      }
      planner->step();
    }
  }

  [[nodiscard]] std::vector<std::string> process_lines() const {
    std::vector<std::string> out;
    for (const auto& e : life.entries()) {
      if (e.text.rfind("  ", 0) == 0) continue;  // supervisor details
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.1f ", to_seconds(e.time));
      out.push_back(buf + e.text);
    }
    return out;
  }
};

}  // namespace

TEST_CASE("A two-section cleaning task runs PrAutoMove and PrCleaning in order", "[planner]") {
  World w;
  const CommandAnswer a = w.planner->command("Clean the room 3211.");
  REQUIRE(a.accepted);
  CHECK(a.text == "task 'clean': PrAutoMove(goal=A.entry) -> PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B)");
  w.run(100.0);
  CHECK(w.planner->state() == TaskState::succeeded);
  CHECK(w.process_lines() == std::vector<std::string>{
                                 "0.0 task clean started (\"Clean the room 3211.\"): PrAutoMove(goal=A.entry) -> "
                                 "PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B)",
                                 "0.0 process X0 PrAutoMove(goal=A.entry) started",
                                 "3.0 process X0 PrAutoMove succeeded",
                                 "3.0 process X1 PrCleaning(section=A) started",
                                 "13.0 process X1 PrCleaning succeeded",
                                 "13.0 process X2 PrAutoMove(goal=B.entry) started",
                                 "16.0 process X2 PrAutoMove succeeded",
                                 "16.0 process X3 PrCleaning(section=B) started",
                                 "26.0 process X3 PrCleaning succeeded",
                                 "26.0 task clean succeeded",
                             });
  // The behaviors got the plan's parameters through the nets' "$name" bindings.
  CHECK(std::find(w.behaviors.log.begin(), w.behaviors.log.end(), "t=3.000 activate BhCleaning(pattern=balloon, section=A)") !=
        w.behaviors.log.end());
  CHECK(std::find(w.behaviors.log.begin(), w.behaviors.log.end(), "t=13.000 activate BhAutoMove(goal=B.entry)") !=
        w.behaviors.log.end());
  const TaskReport& r = w.planner->report();
  CHECK(r.processes.size() == 4);
  CHECK(r.recoveries.empty());
  CHECK(to_seconds(*r.finished) == Approx(26.0));
  CHECK(w.supervisor.idle());
  CHECK(w.supervisor.active_behaviors().empty());
}

TEST_CASE("A localization loss that recovers within the delay only pauses the task", "[planner]") {
  World w;
  REQUIRE(w.planner->command("clean room 3211").accepted);
  w.run(100.0, [&](double t) {
    if (t > 5.95 && t < 6.05) w.localized = false;
    if (t > 8.95 && t < 9.05) w.localized = true;
  });
  CHECK(w.planner->state() == TaskState::succeeded);
  CHECK(w.planner->report().recoveries.empty());
  CHECK(w.planner->report().processes.size() == 4);
  // PrCleaning(section=A) took 3 s longer: the robot stood still while lost.
  CHECK(to_seconds(*w.planner->report().processes[1].finished) == Approx(16.0));
  CHECK(to_seconds(*w.planner->report().finished) == Approx(29.0));
}

TEST_CASE("A persistent loss makes the planner insert PrGlobalLocalization and retry", "[planner]") {
  World w;
  REQUIRE(w.planner->command("clean room 3211").accepted);
  w.run(100.0, [&](double t) {
    if (t > 5.95 && t < 6.05) w.localized = false;  // in PrCleaning(section=A); never recovers by itself
  });
  CHECK(w.planner->state() == TaskState::succeeded);
  const std::vector<std::string> lines = w.process_lines();
  const std::vector<std::string> expected{
      "0.0 task clean started (\"clean room 3211\"): PrAutoMove(goal=A.entry) -> PrCleaning(section=A) -> "
      "PrAutoMove(goal=B.entry) -> PrCleaning(section=B)",
      "0.0 process X0 PrAutoMove(goal=A.entry) started",
      "3.0 process X0 PrAutoMove succeeded",
      "3.0 process X1 PrCleaning(section=A) started",
      "11.0 process X1 PrCleaning failed: localization fault",
      "11.0 recovery: fault \"localization fault\" of PrCleaning: insert PrGlobalLocalization, then retry (1/2); plan: "
      "PrGlobalLocalization() -> PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B)",
      "11.0 process X0 PrGlobalLocalization() started",
      "13.0 process X0 PrGlobalLocalization succeeded",
      "13.0 process X1 PrCleaning(section=A) started",
      "23.0 process X1 PrCleaning succeeded",
      "23.0 process X2 PrAutoMove(goal=B.entry) started",
      "26.0 process X2 PrAutoMove succeeded",
      "26.0 process X3 PrCleaning(section=B) started",
      "36.0 process X3 PrCleaning succeeded",
      "36.0 task clean succeeded",
  };
  CHECK(lines == expected);
  const TaskReport& r = w.planner->report();
  REQUIRE(r.recoveries.size() == 1);
  CHECK(r.recoveries[0].failed_process == "PrCleaning");
  CHECK(r.recoveries[0].fault == "localization fault");
  // The running plan is itself a net: the last one ran the remaining plan after the recovery.
  CHECK(to_string(w.planner->current_plan()) ==
        "PrGlobalLocalization() -> PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B)");
}

TEST_CASE("The retry limit makes the task fail with a report", "[planner]") {
  World w;
  REQUIRE(w.planner->command("clean room 3211").accepted);
  // A flaky localizer: lost again one second into every cleaning run.
  Time cleaning_since = time_from_ns(-1);
  w.run(200.0, [&](double) {
    const bool cleaning = w.behaviors.active("BhCleaning");
    if (!cleaning) {
      cleaning_since = time_from_ns(-1);
      return;
    }
    if (cleaning_since < Time{}) cleaning_since = w.clock.now();
    if (w.clock.now() - cleaning_since >= from_seconds(1.0)) w.localized = false;
  });
  REQUIRE(w.planner->state() == TaskState::failed);
  const TaskReport& r = w.planner->report();
  CHECK(r.reason ==
        "retry limit reached: \"localization fault\" recovered 2 time(s) (max_retries 2), PrCleaning failed again");
  CHECK(r.recoveries.size() == 2);
  const std::string report = r.str();
  CHECK_THAT(report, Catch::StartsWith("task 'clean' (\"clean room 3211\"): failed: retry limit reached"));
  CHECK_THAT(report, Catch::Contains("X1 PrCleaning(section=A) failed at 9.100 s: localization fault"));
  CHECK_THAT(report, Catch::Contains("recovery: fault \"localization fault\" of PrCleaning: insert PrGlobalLocalization, then retry (2/2)"));
  CHECK(w.supervisor.idle());
  CHECK(w.supervisor.active_behaviors().empty());
  CHECK_THAT(w.life.str(), Catch::EndsWith("task clean failed: retry limit reached: \"localization fault\" recovered 2 time(s) "
                                           "(max_retries 2), PrCleaning failed again\n"));
}

TEST_CASE("A fault no rule handles, and a skip rule", "[planner]") {
  SECTION("skip: a blocked path skips the section") {
    World w;
    w.behaviors.specs["BhAutoMove"].fail = true;  // every move is blocked
    REQUIRE(w.planner->command("patrol rooms 2111, 2133").accepted);
    w.run(100.0);
    // First PrAutoMove fails -> skip (1/1); the second fails too -> retry limit.
    REQUIRE(w.planner->state() == TaskState::failed);
    CHECK(w.planner->report().recoveries.size() == 1);
    CHECK_THAT(w.planner->report().reason, Catch::StartsWith("retry limit reached: \"path blocked\""));
  }
  SECTION("no rule") {
    World w;
    w.behaviors.specs["BhCleaning"].fail = true;
    REQUIRE(w.planner->command("clean room 2111").accepted);
    w.run(100.0);
    REQUIRE(w.planner->state() == TaskState::failed);
    CHECK(w.planner->report().reason == "no recovery rule for fault \"cleaning behavior failed\" of PrCleaning");
  }
}

TEST_CASE("The planner runs the processes' module nets, a fault keeps the failing process's message", "[planner]") {
  World w(true);
  w.behaviors.specs["BhCleaning"].fail = true;
  REQUIRE(w.planner->command("clean room 2111").accepted);
  w.planner->step();
  REQUIRE(w.planner->net_engine() != nullptr);
  const PetriNet& net = w.planner->net_engine()->net();
  // PrCleaning's stage is Fig. 2 as configs/petri/PrCleaning-module.xml draws it; PrAutoMove's the default
  CHECK(net.transition(*net.find_transition("X1.t2")).description ==
        "Process supervisor (PS) posts fault message \"localization fault\"");
  CHECK(net.transition(*net.find_transition("X0.t2")).description ==
        "Process supervisor (PS) posts the fault message of PrAutoMove");
  w.run(100.0);
  REQUIRE(w.planner->state() == TaskState::failed);
  // not the module's "localization fault": the message PrCleaning's net ended with
  CHECK(w.planner->report().processes.at(1).message == "cleaning behavior failed");
  CHECK(w.planner->report().reason == "no recovery rule for fault \"cleaning behavior failed\" of PrCleaning");
}

TEST_CASE("An unknown command is refused and nothing runs", "[planner]") {
  World w;
  CommandAnswer a = w.planner->command("make me a coffee");
  CHECK_FALSE(a.accepted);
  CHECK_THAT(a.text, Catch::StartsWith("not understood: \"make me a coffee\"") && Catch::Contains("clean [the] room {room}"));
  CHECK(w.planner->state() == TaskState::idle);
  a = w.planner->command("clean the room 9999");
  CHECK_FALSE(a.accepted);
  CHECK(a.text == "understood the task 'clean' but cannot plan it: unknown room '9999'");
  w.run(5.0);
  CHECK(w.behaviors.log.empty());
  CHECK(w.supervisor.idle());
  REQUIRE(w.life.entries().size() == 2);
  CHECK_THAT(w.life.entries()[0].text, Catch::StartsWith("command refused: \"make me a coffee\": not understood"));
}

TEST_CASE("A plan naming a process the robot lacks is refused, a busy planner refuses", "[planner]") {
  SimClock clock;
  FakeBehaviors behaviors;
  behaviors.add("BhAutoMove", 1.0);
  FakeSectionSplitter splitter;
  ProcessRegistry processes;
  processes.add(def("PrAutoMove", pr_auto_move()));
  TaskLibrary tasks = TaskLibrary::load(std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs/tasks/cleaning.yaml");
  RecoveryPolicy recovery;
  CProcessSupervisor supervisor(behaviors, clock);
  CPlanner planner(tasks, recovery, splitter, processes, supervisor, clock);
  CommandAnswer a = planner.command("clean room 3211");
  CHECK_FALSE(a.accepted);
  CHECK(a.text == "understood the task 'clean' but cannot run it: the robot has no process 'PrCleaning' (it has: PrAutoMove)");
  a = planner.command("patrol 2111");
  REQUIRE(a.accepted);
  a = planner.command("patrol 2133");
  CHECK_FALSE(a.accepted);
  CHECK(a.text == "busy: task 'patrol' (\"patrol 2111\") is running; cancel it first");
  planner.step();
  CHECK(behaviors.active("BhAutoMove"));
  planner.cancel("user said stop");
  CHECK(planner.state() == TaskState::failed);
  CHECK(planner.report().reason == "user said stop");
  CHECK_FALSE(behaviors.active("BhAutoMove"));
  CHECK(planner.report().processes.at(0).message == "stopped: user said stop");
}

TEST_CASE("Same robot, task and event sequence give the same trace", "[planner]") {
  auto once = [] {
    World w;
    REQUIRE(w.planner->command("clean room 3211").accepted);
    w.run(200.0, [&](double t) {
      if (t > 4.95 && t < 5.05) w.localized = false;
      if (t > 6.95 && t < 7.05) w.localized = true;
      if (t > 20.95 && t < 21.05) w.localized = false;
    });
    return w.life.str();
  };
  const std::string a = once();
  const std::string b = once();
  CHECK(a == b);
  CHECK_THAT(a, Catch::Contains("X1 PrCleaning fire t3 [localizer.lost]") && Catch::Contains("recovery:"));
  CHECK_THAT(a, Catch::EndsWith("task clean succeeded\n"));
}

TEST_CASE("Parallel stages: the plan changes only at a quiet point, when every branch has ended", "[planner]") {
  SimClock clock;
  FakeBehaviors behaviors;
  behaviors.add("BhAutoMove", 3.0);
  behaviors.add("BhExplain", 5.0);
  FakeSectionSplitter splitter;
  ProcessRegistry processes;
  processes.add(def("PrAutoMove", pr_auto_move()));
  processes.add(def("PrExplain", motion_process_net("PrExplain", "BhExplain", {{"topic", "$topic"}}, {decl("topic")}, 5.0,
                                                    "explanation failed")));
  const TaskLibrary tasks = TaskLibrary::load_from_string(R"(tasks:
  - name: guide
    commands: ["guide me to [room] {room}"]
    plan:
      - parallel:
          - PrAutoMove: { goal: "{room}" }
          - PrExplain: { topic: "way to {room}" }
)", "guide.yaml");
  const RecoveryPolicy recovery = RecoveryPolicy::load_from_string(kRecovery, "recovery.yaml");
  CProcessSupervisor supervisor(behaviors, clock);
  CPlanner planner(tasks, recovery, splitter, processes, supervisor, clock);
  LifecycleRecorder life;
  planner.add_observer(life);
  auto run = [&] {
    planner.step();
    while (planner.busy() && clock.now() < time_from_seconds(60.0)) {
      clock.advance(from_seconds(0.1));
      behaviors.advance(clock.now(), from_seconds(0.1));
      planner.step();
    }
  };

  SECTION("both branches succeed") {
    REQUIRE(planner.command("guide me to room 2111").accepted);
    run();
    CHECK(planner.state() == TaskState::succeeded);
    CHECK(to_seconds(*planner.report().finished) == Approx(5.0));
    CHECK_THAT(life.str(), Catch::Contains("0.000 s  process X0 PrAutoMove(goal=2111) started") &&
                               Catch::Contains("0.000 s  process X0_1 PrExplain(topic=way to 2111) started"));
  }
  SECTION("one branch fails: the recovery waits for the other") {
    behaviors.specs["BhAutoMove"].fail = true;  // "path blocked" at 3 s -> rule: skip
    REQUIRE(planner.command("guide me to room 2111").accepted);
    run();
    CHECK(planner.state() == TaskState::succeeded);  // skipping the only stage leaves nothing to do
    const TaskReport& r = planner.report();
    REQUIRE(r.recoveries.size() == 1);
    CHECK(to_seconds(r.recoveries[0].time) == Approx(5.0));  // not 3.0: PrExplain was still running
    CHECK(r.recoveries[0].reason == "fault \"path blocked\" of PrAutoMove: skip (1/1)");
    CHECK(r.processes.at(1).success);
    CHECK(to_seconds(*r.processes.at(0).finished) == Approx(3.0));
  }
}
