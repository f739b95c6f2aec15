// The PSR-2 robot assembled from configs/robots/psr2.yaml with test doubles registered under the
// profile's type names, running the cleaning task end to end through the planner, the process
// supervisor, the paper's nets (configs/petri) and CBehavior instances.
#include "tripodal/robot/robot.hpp"

#include <catch2/catch.hpp>
#include <functional>
#include <thread>

#include "robot_doubles.hpp"
#include "tripodal/behaviors/teleop.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"

using namespace tripodal;
using namespace tripodal::test;

namespace {

const std::filesystem::path kProfile = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs/robots/psr2.yaml";

struct Psr2 {
  SimClock clock;
  TestWorld world;
  RobotPlugins plugins = test_plugins(world);
  std::unique_ptr<Robot> robot;
  LifecycleRecorder life{true};

  Psr2() {
    robot = Robot::assemble(load_robot_profile(kProfile), plugins, clock);
    robot->planner().add_observer(life);
    robot->supervisor().add_observer(life);
  }

  // Runs the robot 0.1 s at a time (its loops at their own periods) while the task lasts.
  void run(double end_s, const std::function<void(double)>& at = {}) {
    robot->run_until(clock.now());
    while (robot->planner().busy() && to_seconds(clock.now()) < end_s - 1e-9) {
      robot->run_for(from_seconds(0.1));
      if (at) at(to_seconds(clock.now()));
    }
  }

  [[nodiscard]] std::vector<std::string> task_lines() const {
    std::vector<std::string> out;
    for (const auto& e : life.entries()) {
      if (e.text.rfind("  ", 0) == 0) continue;
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.2f ", to_seconds(e.time));
      out.push_back(buf + e.text);
    }
    return out;
  }
};

bool at_time(double t, double x) { return t > x - 0.05 && t < x + 0.05; }

}  // namespace

TEST_CASE("PSR-2 assembles from its profile with the paper's nets", "[robot]") {
  Psr2 p;
  CHECK(p.robot->processes().names() == std::vector<std::string>{"PrAutoMove", "PrCleaning", "PrGlobalLocalization", "PrWait"});
  CHECK(p.robot->module("localizer") != nullptr);
  CHECK(p.robot->module("BhCleaning") == nullptr);
  CHECK(p.robot->modules().size() == 6);
  CHECK(p.robot->module("mapping") != nullptr);
  CHECK(p.robot->hardware() != nullptr);
  REQUIRE(p.robot->loop("motion") != nullptr);
  CHECK(&p.robot->behavior_loop() == p.robot->loop("motion"));
  CHECK(p.robot->behavior_loop().coordinator().input_count() == 5);  // the profile's 4 behaviors and "operator" (driving by hand)
  CHECK(p.robot->behavior_loop().controller() != nullptr);
  CHECK(p.robot->behavior_loop().period() == std::chrono::milliseconds(10));
  const auto& mods = p.robot->description().modules;
  // core components, hardware, controller, six navigation modules (with the live mapper), four behaviors
  REQUIRE(mods.size() == 3 + 1 + 1 + 6 + 4);
  CHECK(mods[0].name == "planner");
  CHECK(mods[0].inputs == std::vector<std::string>{"sections", "process_result"});
}

TEST_CASE("A resource type is built with the robot's hardware and reports its type's manifest", "[robot]") {
  SimClock clock;
  TestWorld world;
  RobotPlugins plugins = test_plugins(world);
  const CHardware* given = nullptr;
  static const ModuleManifest bumper = [] {
    ModuleManifest m = resource_manifest<BumperReading>();
    m.name = "BumperBoard";
    return m;
  }();
  plugins.resources.add(bumper, [&given](const ResourceConfig& c) {
    given = c.hardware;
    return std::make_unique<BumperResource>(c.name, Duration{0}, bumper);
  });
  RobotProfile profile = load_robot_profile(kProfile);
  ModuleEntry entry;
  entry.kind = ModuleKind::resource;
  entry.name = "front_bumper";
  entry.type = "BumperBoard";
  profile.resources.push_back(entry);
  const auto robot = Robot::assemble(profile, plugins, clock);
  REQUIRE(robot->hardware() != nullptr);
  CHECK(given == robot->hardware());
  const auto* resource = robot->resources().find<BumperReading>("front_bumper");
  REQUIRE(resource != nullptr);
  CHECK(resource->manifest().name == "BumperBoard");
  // Without a manifest of its own, a typed resource is the generic one of its reading kind.
  CHECK(BumperResource("b").manifest().name == "BumperResource");
}

TEST_CASE("PSR-2 cleans a room of two sections: PrAutoMove and PrCleaning in order", "[robot]") {
  Psr2 p;
  REQUIRE(p.robot->command("clean the room 3211").accepted);
  p.run(200.0);
  CHECK(p.robot->planner().state() == TaskState::succeeded);
  CHECK(p.task_lines() == std::vector<std::string>{
                              "0.00 task clean started (\"clean the room 3211\"): PrAutoMove(goal=A.entry) -> "
                              "PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B)",
                              "0.00 process X0 PrAutoMove(goal=A.entry) started",
                              "3.05 process X0 PrAutoMove succeeded",
                              "3.05 process X1 PrCleaning(section=A) started",
                              "13.10 process X1 PrCleaning succeeded",
                              "13.10 process X2 PrAutoMove(goal=B.entry) started",
                              "16.15 process X2 PrAutoMove succeeded",
                              "16.15 process X3 PrCleaning(section=B) started",
                              "26.20 process X3 PrCleaning succeeded",
                              "26.20 task clean succeeded",
                          });
  // wheel_type = omni (profile) selects BhCleaning in the PrCleaning net, with the section.
  CHECK_THAT(p.life.str(), Catch::Contains("X1 activate BhCleaning(section=A)") &&
                               Catch::Contains("X1 PrCleaning fire t0") && !Catch::Contains("BhCleaningTwoWheel("));
  CHECK(p.robot->behavior_loop().last_cycle().coordinator.winner.empty());  // nothing drives once the task is done
}

TEST_CASE("PSR-2: a localization loss that recovers within the delay only pauses", "[robot]") {
  Psr2 p;
  REQUIRE(p.robot->command("clean the room 3211").accepted);
  p.run(200.0, [&](double t) {
    if (at_time(t, 6.0)) p.world.localized = false;
    if (at_time(t, 9.0)) p.world.localized = true;
  });
  CHECK(p.robot->planner().state() == TaskState::succeeded);
  CHECK(p.robot->planner().report().recoveries.empty());
  CHECK_THAT(p.life.str(), Catch::Contains("X1 PrCleaning fire t3 [localizer.lost]") &&
                               Catch::Contains("X1 PrCleaning fire t2 [localizer.ok]"));
  // Three seconds standing still: 26.20 s of work and detection (as without the loss) + 3 s.
  CHECK(to_seconds(*p.robot->planner().report().finished) == Approx(29.2));
}

TEST_CASE("PSR-2: a persistent loss inserts PrGlobalLocalization, retries, and the task succeeds", "[robot]") {
  Psr2 p;
  REQUIRE(p.robot->command("clean the room 3211").accepted);
  p.run(200.0, [&](double t) {
    if (at_time(t, 6.0)) p.world.localized = false;
  });
  CHECK(p.robot->planner().state() == TaskState::succeeded);
  const auto lines = p.task_lines();
  CHECK(lines == std::vector<std::string>{
                     "0.00 task clean started (\"clean the room 3211\"): PrAutoMove(goal=A.entry) -> PrCleaning(section=A) -> "
                     "PrAutoMove(goal=B.entry) -> PrCleaning(section=B)",
                     "0.00 process X0 PrAutoMove(goal=A.entry) started",
                     "3.05 process X0 PrAutoMove succeeded",
                     "3.05 process X1 PrCleaning(section=A) started",
                     "16.05 process X1 PrCleaning failed: localization fault",
                     "16.05 recovery: fault \"localization fault\" of PrCleaning: insert PrGlobalLocalization, then retry (1/2); "
                     "plan: PrGlobalLocalization() -> PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B)",
                     "16.05 process X0 PrGlobalLocalization() started",
                     "18.10 process X0 PrGlobalLocalization succeeded",
                     "18.10 process X1 PrCleaning(section=A) started",
                     "28.15 process X1 PrCleaning succeeded",
                     "28.15 process X2 PrAutoMove(goal=B.entry) started",
                     "31.20 process X2 PrAutoMove succeeded",
                     "31.20 process X3 PrCleaning(section=B) started",
                     "41.25 process X3 PrCleaning succeeded",
                     "41.25 task clean succeeded",
                 });
  CHECK_THAT(p.life.str(), Catch::Contains("16.050 s    X1 PrCleaning fire t5") &&
                               Catch::Contains("16.050 s    X1 deactivate BhCleaning"));
}

TEST_CASE("PSR-2: the retry limit makes the task fail with a report", "[robot]") {
  Psr2 p;
  REQUIRE(p.robot->command("clean the room 3211").accepted);
  int cleaning_ticks = 0;
  p.run(300.0, [&](double) {
    // Lost one second into every cleaning run; only global localization finds the way again.
    cleaning_ticks = p.robot->behavior_active("BhCleaning") ? cleaning_ticks + 1 : 0;
    if (cleaning_ticks == 10) p.world.localized = false;
  });
  REQUIRE(p.robot->planner().state() == TaskState::failed);
  const TaskReport& r = p.robot->planner().report();
  CHECK(r.reason == "retry limit reached: \"localization fault\" recovered 2 time(s) (max_retries 2), PrCleaning failed again");
  CHECK(r.recoveries.size() == 2);
  CHECK(std::count_if(r.processes.begin(), r.processes.end(), [](const ProcessRecord& x) { return x.step.process == "PrCleaning"; }) == 3);
  CHECK(p.robot->supervisor().active_behaviors().empty());
  CHECK_THAT(r.str(), Catch::Contains("failed: retry limit reached") && Catch::Contains("recovery: fault \"localization fault\""));
}

TEST_CASE("PSR-2 refuses an unknown command and runs nothing", "[robot]") {
  Psr2 p;
  const CommandAnswer a = p.robot->command("fetch me the newspaper");
  CHECK_FALSE(a.accepted);
  CHECK_THAT(a.text, Catch::Contains("not understood") && Catch::Contains("Possible commands:") &&
                         Catch::Contains("clean [the] room {room}") && Catch::Contains("patrol [the] [rooms] {rooms...}"));
  p.run(5.0);
  CHECK(p.robot->planner().state() == TaskState::idle);
  CHECK(p.robot->supervisor().active_behaviors().empty());
}

TEST_CASE("PSR-2: a module that throws becomes a fault, the loop goes on", "[robot]") {
  Psr2 p;
  REQUIRE(p.robot->command("clean the room 3211").accepted);
  REQUIRE_NOTHROW(p.run(200.0, [&](double t) {
    if (at_time(t, 5.0)) p.world.localizer_throws = true;
  }));
  REQUIRE(p.robot->planner().state() == TaskState::failed);
  CHECK(p.robot->planner().report().processes.back().message == "module localizer failed: scan matcher crashed");
  CHECK(p.robot->planner().report().reason ==
        "no recovery rule for fault \"module localizer failed: scan matcher crashed\" of PrCleaning");
  // The robot still answers and runs after the failed task once the localizer works again.
  p.world.localizer_throws = false;
  REQUIRE(p.robot->command("clean room 2111").accepted);
  p.run(400.0);
  CHECK(p.robot->planner().state() == TaskState::succeeded);
}

TEST_CASE("PSR-2: a silent localizer trips the watchdog, which the net treats as a loss", "[robot]") {
  Psr2 p;
  REQUIRE(p.robot->command("clean the room 2111").accepted);
  p.run(200.0, [&](double t) {
    if (at_time(t, 5.0)) p.world.localizer_silent = true;
  });
  // Watchdog 1 s: localizer.lost at 6.0 s (last heartbeat at the 5.0 s sequencing period); the
  // completion of BhCleaning is then refused by the net until the 10 s delay ends in the fault
  // place. The watchdog fires once per silence, so the retried PrCleaning (after global
  // localization) completes.
  CHECK_THAT(p.life.str(), Catch::Contains("6.000 s    fault localizer: stopped answering (no heartbeat for 1.000 s)"));
  CHECK_THAT(p.life.str(), Catch::Contains("16.000 s  process X1 PrCleaning failed: localization fault"));
  CHECK(p.robot->planner().state() == TaskState::succeeded);
  CHECK(p.robot->planner().report().recoveries.size() == 1);
}

TEST_CASE("PSR-2: the same task and event sequence give the same trace", "[robot]") {
  auto once = [] {
    Psr2 p;
    REQUIRE(p.robot->command("clean the room 3211").accepted);
    p.run(300.0, [&](double t) {
      if (at_time(t, 4.0)) p.world.localized = false;
      if (at_time(t, 6.0)) p.world.localized = true;
      if (at_time(t, 20.0)) p.world.localized = false;
    });
    return p.life.str();
  };
  const std::string a = once();
  CHECK(a == once());
  CHECK_THAT(a, Catch::Contains("recovery:") && Catch::EndsWith("task clean succeeded\n"));
}

TEST_CASE("PSR-2 on its threads takes a command from another thread and stops cleanly", "[robot][threads]") {
  // Real time: the hardware, a LoopRunner per reactive loop and the sequencing thread run while a
  // second thread commands the planner (scripts/tsan.sh runs this under ThreadSanitizer). What is
  // checked does not depend on how far the robot got.
  SteadyClock clock;
  TestWorld world;
  const RobotPlugins plugins = test_plugins(world);
  const std::unique_ptr<Robot> robot = Robot::assemble(load_robot_profile(kProfile), plugins, clock);
  robot->start();
  CHECK(robot->started());
  CHECK_THROWS_AS(robot->start(), std::logic_error);
  bool accepted = false;
  std::thread operator_thread([&] { accepted = robot->command("clean the room 3211").accepted; });
  operator_thread.join();
  // Driving by hand from another thread, as the monitor does: BhTeleop's input and the lock.
  auto* teleop = dynamic_cast<TeleopResource*>(robot->behavior_loop().resources().find(kTeleopResource));
  REQUIRE(teleop != nullptr);
  std::thread console([&] {
    robot->behavior_loop().set_lock(kTeleopInput, true, clock.now());
    for (int i = 0; i < 20; ++i) {
      teleop->set(true, Twist2D{0.0, 0.0, 0.2}, clock.now());
      clock.sleep_until(clock.now() + std::chrono::milliseconds(5));
    }
    teleop->set(false, Twist2D{}, clock.now());
    robot->behavior_loop().set_lock(kTeleopInput, false, clock.now());
  });
  console.join();
  clock.sleep_until(clock.now() + std::chrono::milliseconds(200));
  robot->stop();
  robot->stop();  // idempotent
  CHECK_FALSE(robot->started());
  CHECK(accepted);
  CHECK(robot->planner().busy());
}

TEST_CASE(
    "Driving by hand is an ordinary coordinator input: BhTeleop runs from the start on 'operator', its resource set from outside",
    "[robot][teleop]") {
  Psr2 p;
  ControlLoop& loop = p.robot->behavior_loop();
  const CBehaviorCoordinator& co = loop.coordinator();
  // Configured at assembly, above every normal input; nothing is added later.
  const std::optional<InputId> op = co.find_input(kTeleopInput);
  REQUIRE(op.has_value());
  const std::size_t inputs = co.input_count();
  auto* teleop = dynamic_cast<TeleopResource*>(loop.resources().find(kTeleopResource));
  REQUIRE(teleop != nullptr);
  REQUIRE(p.robot->command("clean the room 3211").accepted);
  p.robot->run_for(std::chrono::seconds(2));
  CHECK(loop.last_cycle().coordinator.winner != kTeleopInput);  // not engaged: gives nothing

  teleop->set(true, Twist2D{0.0, 0.0, 0.4}, p.clock.now());
  loop.set_lock(kTeleopInput, true, p.clock.now());
  p.robot->run_for(std::chrono::milliseconds(100));
  const CoordinatorOutput& out = loop.last_cycle().coordinator;
  CHECK(out.winner == kTeleopInput);
  CHECK(out.command == Twist2D{0.0, 0.0, 0.4});
  CHECK(out.lock == kTeleopInput);
  CHECK(co.input_count() == inputs);

  teleop->set(false, Twist2D{}, p.clock.now());
  loop.set_lock(kTeleopInput, false, p.clock.now());
  p.robot->run_for(std::chrono::milliseconds(100));
  CHECK(loop.last_cycle().coordinator.winner != kTeleopInput);
  CHECK(p.robot->planner().busy());
}
