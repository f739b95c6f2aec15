// Start-up checks of a robot profile: located load errors, exactly one provider per input, the
// layering rules R1-R5 (docs/processes.md), refusals to assemble, and the describe renderings.
#include "tripodal/robot/layering.hpp"

#include <catch2/catch.hpp>

#include "../support/file_lines.hpp"
#include "robot_doubles.hpp"
#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/board/board_monitor.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;
using namespace tripodal::test;

namespace {

const std::filesystem::path kRobots = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs/robots";

// A small valid robot: a laser, a map, a localizer, a section splitter, two behaviors, a base.
std::string profile(const std::string& resources, const std::string& navigation, const std::string& behaviors,
                    const std::string& extra = {}) {
  return "robot: {name: testbot}\n"
         "controllers:\n  - {name: base, type: omni}\n"
         "resources:\n" + resources +
         "navigation:\n" + navigation +
         "behaviors:\n" + behaviors +
         "processes:\n"
         "  - {name: PrAutoMove, net: ../petri/PrAutoMove.xml}\n"
         "tasks: ../tasks/cleaning.yaml\n" + extra;
}

const std::string kResources = "  - {name: front_laser, type: LaserScanner}\n";
const std::string kNavigation =
    "  - {name: maps, type: GridMaps}\n"
    "  - {name: localizer, type: ScanMatchingLocalizer}\n"
    "  - {name: section_splitter, type: SectionSplitter}\n";
const std::string kBehaviors = "  - BhAutoMove\n  - BhCleaning\n";

struct Catalog {
  TestWorld world;
  RobotPlugins plugins = test_plugins(world);

  // Runs the checks the robot runs at start-up; returns every diagnostic.
  std::string check(const std::string& yaml, RobotDescription* out = nullptr) {
    RobotProfile p = load_robot_profile_from_string(yaml, "testbot.yaml", kRobots);
    TaskLibrary tasks = TaskLibrary::load(p.tasks);
    Diagnostics d;
    RobotDescription r = describe_robot(p, plugins, knowledge_inputs(tasks), d);
    if (out) *out = r;
    return d.str();
  }
};

}  // namespace

TEST_CASE("A valid profile passes the checks", "[robot]") {
  Catalog c;
  RobotDescription r;
  CHECK(c.check(profile(kResources, kNavigation, kBehaviors), &r).empty());
  CHECK(r.modules.size() == 3 + 1 + 1 + 3 + 2);
}

TEST_CASE("Missing providers are refused with the consumer and the information named", "[robot]") {
  Catalog c;
  // No section splitter: the clean task asks sections(room); no map: the localizer needs grid_map.
  const std::string diag = c.check(profile(kResources,
                                           "  - {name: localizer, type: ScanMatchingLocalizer}\n", kBehaviors));
  CHECK_THAT(diag, Catch::Contains("testbot.yaml:1:8: error: missing provider: deliberate core component 'planner' needs "
                                   "'sections', but no module provides it"));
  CHECK_THAT(diag, Catch::Contains("testbot.yaml:7:5: error: missing provider: sequencing navigation 'localizer' needs "
                                   "'grid_map', but no module provides it"));
  std::size_t errors = 0;
  for (std::size_t at = diag.find("error:"); at != std::string::npos; at = diag.find("error:", at + 1)) ++errors;
  CHECK(errors == 2);
}

TEST_CASE("Duplicate providers are refused with every provider located", "[robot]") {
  Catalog c;
  const std::string diag = c.check(profile(kResources + "  - {name: rear_laser, type: LaserScanner}\n", kNavigation, kBehaviors));
  CHECK_THAT(diag, Catch::Contains("testbot.yaml:9:5: error: duplicate providers: sequencing navigation 'localizer' needs "
                                   "'laser_scan', which 2 modules provide: front_laser (testbot.yaml:5:5), rear_laser "
                                   "(testbot.yaml:6:5); exactly one must"));
  // A registered type's manifest is its own: the profile cannot rewire it...
  CHECK_THAT(c.check(profile(kResources + "  - {name: rear_laser, type: LaserScanner, outputs: [rear_scan]}\n", kNavigation,
                             kBehaviors)),
             Catch::Contains("testbot.yaml:6:5: error: module 'rear_laser' re-declares outputs of its registered type "
                             "'LaserScanner' (a reactive-layer resource); remove layer, inputs and outputs: the diagram "
                             "comes from the type's own manifest"));
  // ...but a type designed before it is implemented is declared with what it provides.
  CHECK(c.check(profile(kResources + "  - {name: rear_laser, type: RearLaser, layer: reactive, outputs: [rear_scan]}\n",
                        kNavigation, kBehaviors))
            .empty());
}

TEST_CASE("from: binds an input several modules provide to the one named", "[robot]") {
  Catalog c;
  const std::string two_lasers = kResources + "  - {name: rear_laser, type: LaserScanner}\n";
  const auto navigation = [](const std::string& from) {
    return "  - {name: maps, type: GridMaps}\n"
           "  - {name: localizer, type: ScanMatchingLocalizer, from: " +
           from +
           "}\n"
           "  - {name: section_splitter, type: SectionSplitter}\n";
  };
  // Bound: the two providers are no longer ambiguous, and the diagram's edge comes from the one.
  RobotDescription r;
  CHECK(c.check(profile(two_lasers, navigation("{laser_scan: rear_laser}"), kBehaviors), &r).empty());
  const std::string dot = describe_dot(r);
  CHECK_THAT(dot, Catch::Contains("\"rear_laser\" -> \"localizer\""));
  CHECK_THAT(dot, !Catch::Contains("\"front_laser\" -> \"localizer\""));
  // A provider that does not provide it, and an input the module does not have: both located.
  const std::string diag = c.check(profile(two_lasers, navigation("{laser_scan: maps, sonar: front_laser}"), kBehaviors));
  CHECK_THAT(diag,
             Catch::Contains("testbot.yaml:9:5: error: from: sequencing navigation 'localizer' takes 'laser_scan' from 'maps', "
                             "which does not provide it; its providers: front_laser, rear_laser"));
  CHECK_THAT(diag,
             Catch::Contains("testbot.yaml:9:5: error: from: sequencing navigation 'localizer' has no input 'sonar' to bind to "
                             "'front_laser'; its inputs: laser_scan, odometry, grid_map"));
}

TEST_CASE("The disinfection robot on its lidar binds the localizer's odometry and passes the checks", "[robot]") {
  Catalog c;
  RobotProfile p = load_robot_profile(kRobots / "disinfection_lidar.yaml");
  REQUIRE(p.navigation.size() >= 2);
  CHECK(p.navigation[1].type == "ScanMatchingLocalizer");
  CHECK(p.navigation[1].from.at("odometry") == "base");
}

TEST_CASE("Layering rules R1-R5 are enforced with the rule named", "[robot]") {
  Catalog c;
  SECTION("R1: a navigation module in the reactive layer") {
    const std::string diag = c.check(profile(
        kResources, kNavigation + "  - {name: planner_helper, type: Helper, layer: reactive, outputs: [hint]}\n", kBehaviors));
    CHECK_THAT(diag, Catch::Contains("testbot.yaml:10:5: error: module 'planner_helper' is a navigation but sits in the reactive "
                                     "layer; navigation modules belong to the sequencing layer (rule R1)"));
  }
  SECTION("R2: a resource depending on the deliberate layer") {
    const std::string diag = c.check(profile(
        kResources + "  - {name: display, type: Display, layer: reactive, inputs: [user_goal]}\n", kNavigation, kBehaviors,
        "hri:\n  - {name: voice, type: Voice, layer: deliberate, outputs: [user_goal]}\n"));
    CHECK_THAT(diag, Catch::Contains("testbot.yaml:6:5: error: layering: reactive resource 'display' takes 'user_goal' from "
                                     "deliberate hri 'voice'; reactive modules must not depend on the deliberate layer (rule R2)"));
  }
  SECTION("R3: the deliberate layer reading raw sensor data") {
    const std::string diag = c.check(profile(kResources, kNavigation, kBehaviors,
                                             "hri:\n  - {name: voice, type: Voice, layer: deliberate, inputs: [laser_scan]}\n"));
    CHECK_THAT(diag, Catch::Contains("error: layering: deliberate hri 'voice' takes 'laser_scan' from reactive resource "
                                     "'front_laser'; raw data reaches the deliberate layer only through a sequencing module (rule R3)"));
  }
  SECTION("R4: a behavior driving the controller directly") {
    const std::string diag = c.check(
        "robot: {name: testbot}\n"
        "controllers:\n  - {name: base, type: StoppableBase, layer: reactive, inputs: [cmd_vel, stop_command], outputs: [odometry]}\n"
        "resources:\n" + kResources + "navigation:\n" + kNavigation +
        "behaviors:\n" + kBehaviors + "  - {name: BhEmergencyStop, type: Stop, layer: reactive, outputs: [stop_command]}\n"
        "tasks: ../tasks/cleaning.yaml\n");
    CHECK_THAT(diag, Catch::Contains("testbot.yaml:3:5: error: layering: controller 'base' takes 'stop_command' directly from "
                                     "behavior 'BhEmergencyStop'; motion commands reach controllers only through the behavior "
                                     "coordinator (rule R4)"));
  }
  SECTION("R5: a behavior depending on another behavior") {
    const std::string diag = c.check(profile(
        kResources, kNavigation,
        kBehaviors + "  - {name: BhA, type: A, layer: reactive, outputs: [waypoint, behavior_command]}\n"
                     "  - {name: BhB, type: B, layer: reactive, inputs: [waypoint], outputs: [behavior_command]}\n"));
    CHECK_THAT(diag, Catch::Contains("testbot.yaml:14:5: error: layering: behavior 'BhB' takes 'waypoint' from behavior 'BhA'; "
                                     "behaviors are independent and combined only by the behavior coordinator (rule R5)"));
  }
}

TEST_CASE("Module types: a registered type's manifest is not declared again, unknown types must be declared", "[robot]") {
  Catalog c;
  std::string diag = c.check(profile("  - {name: front_laser, type: LaserScanner, layer: sequencing}\n", kNavigation, kBehaviors));
  CHECK_THAT(diag, Catch::Contains("testbot.yaml:5:5: error: module 'front_laser' re-declares layer of its registered type "
                                   "'LaserScanner' (a reactive-layer resource)"));
  diag = c.check(profile(kResources, kNavigation, kBehaviors + "  - BhCleanig\n"));
  CHECK_THAT(diag, Catch::Contains("testbot.yaml:13:5: error: unknown behavior type 'BhCleanig'; known: BhAutoMove, BhCleaning, "
                                   "BhCleaningTwoWheel, BhGlobalLocalization; did you mean 'BhCleaning'?; register it, or declare "
                                   "it here with layer, inputs and outputs"));
  // Types are looked up in their own family: a navigation module is no resource.
  diag = c.check(profile("  - {name: front_laser, type: GridMaps}\n", kNavigation, kBehaviors));
  CHECK_THAT(diag, Catch::Contains("testbot.yaml:5:5: error: unknown resource type 'GridMaps'; known: LaserScanner;"));
}

TEST_CASE("Profile load errors are all reported, located", "[robot]") {
  const std::string bad =
      "robot: {name: bad}\n"
      "colour: red\n"
      "controllers:\n  - {name: base, type: omni}\n"
      "loops:\n  - {name: fast, period_s: -1, controller: wheels}\n"
      "resources:\n  - {name: laser, type: LaserScanner, layer: upstairs, wires: 3}\n"
      "navigation:\n  - {name: laser, type: GridMaps}\n"
      "processes:\n  - {name: PrX, net: nowhere.xml}\n  - {name: PrY}\n";
  try {
    (void)load_robot_profile_from_string(bad, "bad.yaml", kRobots);
    FAIL("no error");
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    CHECK_THAT(m, Catch::Contains("bad.yaml:2:1: error: unknown key 'colour' in the robot profile; expected one of: robot, hardware, controllers, loops"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:6:28: error: period_s: expected seconds from 1e-06 to 9e+09, got '-1'"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:6:5: error: loop 'fast' drives controller 'wheels', which the profile does not list"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:8:46: error: unknown layer 'upstairs'; expected one of: deliberate, sequencing, reactive"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:8:56: error: unknown key 'wires' in a resource entry"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:10:5: error: module name 'laser' is used twice (first at bad.yaml:8:5)"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:12:22: error: net file 'nowhere.xml' not found"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:13:5: error: process 'PrY' needs a net file (net: FILE)"));
    CHECK(e.diagnostics().error_count() == 8);
  }
}

TEST_CASE("Profile periods out of range are refused where written, with the range", "[robot][errors]") {
  // 1e-12 s rounds to no time at all on the nanosecond clock: the control loop then refused its
  // period while being built, and `tripodal run` reported that as a --monitor error.
  const std::string bad =
      "robot: {name: bad, sequencing_period_s: 1e-9}\n"
      "controllers:\n  - {name: base, type: omni}\n"
      "loops:\n  - {name: fast, period_s: 1e-12, controller: base}\n"
      "dds: {period_s: 1e10}\n";
  try {
    (void)load_robot_profile_from_string(bad, "bad.yaml", kRobots);
    FAIL("no error");
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    CHECK_THAT(m, Catch::Contains("bad.yaml:1:41: error: sequencing_period_s: expected seconds from 1e-06 to 9e+09, got '1e-9'"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:5:28: error: period_s: expected seconds from 1e-06 to 9e+09, got '1e-12'"));
    CHECK_THAT(m, Catch::Contains("bad.yaml:6:17: error: dds period_s: expected seconds from 1e-06 to 9e+09, got '1e10'"));
  }
}

TEST_CASE("Profile keys given twice are refused with both places", "[robot][errors]") {
  const std::string bad =
      "robot: {name: twice}\n"
      "controllers:\n  - {name: base, type: omni}\n"
      "loops:\n  - name: fast\n    period_s: 0.05\n    controller: base\n    period_s: 0.01\n";
  CHECK_THROWS_WITH(load_robot_profile_from_string(bad, "twice.yaml", kRobots),
                    Catch::Contains("twice.yaml:8:5: error: duplicate key 'period_s' (first at twice.yaml:6:5)"));
}

// A list or a map as a key (`? [a]: b`, `{a: 1}: b`) is valid YAML; it once escaped the loader as a
// yaml-cpp conversion exception without the file's name (found by fuzz_robot_profile in CI).
TEST_CASE("Profile keys that are not text are refused, located", "[robot]") {
  const std::string bad =
      "robot: {name: bad}\n"
      "? [colour]\n: red\n"
      "behaviors:\n  - name: BhX\n    {a: 1}: 2\n    parameters: {[speed]: 3, gain: 4}\n"
      "processes:\n  - {name: PrX, net: nowhere.xml, parameters: {{k: v}: 1}}\n";
  try {
    (void)load_robot_profile_from_string(bad, "keys.yaml", kRobots);
    FAIL("no error");
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    CHECK_THAT(m, Catch::Contains("keys.yaml:2:3: error: unknown key 'a list' in the robot profile"));
    CHECK_THAT(m, Catch::Contains("keys.yaml:6:5: error: unknown key 'a map' in a behavior entry"));
    CHECK_THAT(m, Catch::Contains("keys.yaml:7:18: error: parameters: a key must be text, got a list"));
    CHECK_THAT(m, Catch::Contains("keys.yaml:9:48: error: parameters: a key must be text, got a map"));
    CHECK_THAT(m, !Catch::Contains("yaml-cpp"));
  }
}

TEST_CASE("The robot refuses to start with every problem listed", "[robot]") {
  SimClock clock;
  SECTION("modules without implementations") {
    RobotPlugins nothing;
    try {
      (void)Robot::assemble(load_robot_profile(kRobots / "psr2.yaml"), nothing, clock);
      FAIL("started");
    } catch (const ConfigError& e) {
      const std::string m = e.what();
      CHECK_THAT(m, Catch::Contains("psr2.yaml:13:3: error: unknown hardware type 'sim'; known: none; register it"));
      CHECK_THAT(m, Catch::Contains("psr2.yaml:16:5: error: unknown controller type 'omni'; known: none; register it"));
      CHECK_THAT(m, Catch::Contains("psr2.yaml:26:5: error: unknown navigation type 'GridMaps'; known: none; register it"));
      CHECK_THAT(m, Catch::Contains("psr2.yaml:55:13: error: unknown behavior type 'BhAutoMove'; known: none; register it"));
    }
  }
  SECTION("a process binding a behavior the robot lacks; a task naming a process it lacks") {
    Catalog c;
    const std::string yaml = profile(kResources, kNavigation, "  - BhCleaning\n");  // PrAutoMove binds BhAutoMove
    try {
      (void)Robot::assemble(load_robot_profile_from_string(yaml, "testbot.yaml", kRobots), c.plugins, clock);
      FAIL("started");
    } catch (const ConfigError& e) {
      const std::string m = e.what();
      CHECK_THAT(m, Catch::Contains("unknown behavior 'BhAutoMove'"));
      CHECK_THAT(m, Catch::Contains("cleaning.yaml:15:15: error: unknown process 'PrCleaning'"));
    }
  }
  SECTION("a process module net the planner cannot compose") {
    Catalog c;
    std::string yaml = profile(kResources, kNavigation, kBehaviors);
    const std::string entry = "{name: PrAutoMove, net: ../petri/PrAutoMove.xml}";
    yaml.replace(yaml.find(entry), entry.size(), "{name: PrAutoMove, net: ../petri/PrAutoMove.xml, module: ../petri/PrCleaning-module.xml}");
    REQUIRE_THROWS_WITH(Robot::assemble(load_robot_profile_from_string(yaml, "testbot.yaml", kRobots), c.plugins, clock),
                        Catch::Contains("PrCleaning-module.xml:15:3: error: process module of PrAutoMove: place 'P1' runs process "
                                        "'PrCleaning'; the module's executing place must run 'PrAutoMove'"));
  }
  SECTION("a layering violation") {
    Catalog c;
    const std::string yaml = profile(kResources, kNavigation, kBehaviors,
                                     "hri:\n  - {name: voice, type: Voice, layer: deliberate, inputs: [laser_scan]}\n");
    REQUIRE_THROWS_WITH(Robot::assemble(load_robot_profile_from_string(yaml, "testbot.yaml", kRobots), c.plugins, clock),
                        Catch::Contains("(rule R3)"));
  }
}

TEST_CASE("describe_text lists modules by layer, describe_dot draws clusters and information edges", "[robot]") {
  Catalog c;
  RobotDescription r;
  REQUIRE(c.check(profile(kResources, kNavigation, kBehaviors), &r).empty());
  const std::string text = describe_text(r);
  CHECK_THAT(text, Catch::StartsWith("robot testbot\n\ndeliberate layer\n  planner (core, CPlanner)\n      in:  sections, process_result\n"));
  CHECK_THAT(text, Catch::Contains("sequencing layer\n  process_supervisor (core, CProcessSupervisor)\n"));
  CHECK_THAT(text, Catch::Contains("  localizer (navigation, ScanMatchingLocalizer)\n      in:  laser_scan, odometry, grid_map\n      out: map_from_base\n"));
  CHECK_THAT(text, Catch::Contains("  configurations (core): PrAutoMove\n"));
  CHECK_THAT(text, Catch::Contains("reactive layer\n  behavior_coordinator (core, CBehaviorCoordinator)\n      in:  behavior_command*\n"));
  const std::string dot = describe_dot(r);
  CHECK_THAT(dot, Catch::StartsWith("digraph \"testbot\" {"));
  CHECK_THAT(dot, Catch::Contains("subgraph cluster_deliberate") && Catch::Contains("subgraph cluster_reactive"));
  CHECK_THAT(dot, Catch::Contains("\"section_splitter\" -> \"planner\" [label=\"sections\", constraint=false];"));
  CHECK_THAT(dot, Catch::Contains("\"front_laser\" -> \"localizer\" [label=\"laser_scan\", constraint=false];"));
  CHECK_THAT(dot, Catch::Contains("\"behavior_coordinator\" -> \"base\" [label=\"cmd_vel\"];"));
  CHECK_THAT(dot, Catch::Contains("\"process_supervisor\" -> \"BhCleaning\" [style=dashed"));
}

TEST_CASE("describe shows command channels, who writes and who exports them, R6 refuses a channel the hardware lacks",
          "[robot][channels]") {
  RobotPlugins plugins = builtin_plugins(nullptr);
  RobotProfile p = load_robot_profile(std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/disinfection.yaml");
  Diagnostics d;
  const RobotDescription r = describe_robot(p, plugins, knowledge_inputs(TaskLibrary::load(p.tasks)), d);
  INFO(d.str());
  REQUIRE_FALSE(d.has_errors());
  const std::string text = describe_text(r);
  CHECK_THAT(
      text, Catch::Contains(
                "  BhAtomize (behavior)\n      in:  -\n      out: -\n      writes: atomizer (analog), atomizer_fan (digital)\n"));
  CHECK_THAT(text, Catch::Contains("      channel: uv_lamp (digital) <- BhUvLamp\n"));
  CHECK_THAT(text, Catch::Contains("      channel: voice (track) <- BhVoicePrompt\n      channel: lcd (text) <- BhLcdStatus\n"));
  const std::string dot = describe_dot(r);
  CHECK_THAT(dot, Catch::Contains("\"BhUvLamp\" -> \"behavior_coordinator\" [label=\"uv_lamp\", style=bold"));
  CHECK_THAT(dot,
             Catch::Contains(
                 "\"behavior_coordinator\" -> \"hardware\" [label=\"uv_lamp, atomizer, atomizer_fan, voice, lcd\", style=bold"));

  // The same behaviors on hardware that exports no lamp: refused at the behaviors' entry.
  p.hardware->type = "sim";
  p.hardware->parameters.clear();
  Diagnostics bad;
  (void)describe_robot(p, plugins, knowledge_inputs(TaskLibrary::load(p.tasks)), bad);
  CHECK_THAT(bad.str(),
             Catch::Contains(tripodal::test::located_line(std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/disinfection.yaml",
                                                          "  - BhUvLamp")) &&
                 Catch::Contains("behavior 'BhUvLamp' writes the command channel 'uv_lamp' (digital), which hardware 'sim' does "
                                 "not export; it exports none (rule R6)"));
}

TEST_CASE("A loop's thread settings are read from the profile, every bad one located", "[robot][errors]") {
  const RobotProfile p = load_robot_profile_from_string(
      "robot: {name: rt, sequencing_loop: {budget_s: 0.08, deadline_overruns: 20, realtime_priority: 70}}\n"
      "loops:\n"
      "  - {name: motion, period_s: 0.01, realtime_priority: 80, cpu: 1, lock_memory: true, budget_s: 0.004, deadline_overruns: "
      "5}\n"
      "  - {name: arm, period_s: 0.002}\n",
      "rt.yaml", kRobots);
  REQUIRE(p.loops.size() == 2);
  const LoopTimingOptions& t = p.loops[0].timing;
  CHECK(t.realtime_priority == 80);
  CHECK(t.cpu == 1);
  CHECK(t.lock_memory);
  CHECK(t.budget == std::chrono::milliseconds(4));
  CHECK(t.deadline_overruns == 5);
  // Unset: normal scheduling, no pinning, the period as the budget, overruns counted only.
  CHECK(p.loops[1].timing.realtime_priority == 0);
  CHECK(p.loops[1].timing.cpu == -1);
  CHECK_FALSE(p.loops[1].timing.lock_memory);
  CHECK(p.loops[1].timing.budget == Duration{0});
  CHECK(p.loops[1].timing.deadline_overruns == 0);
  CHECK(p.sequencing_timing.budget == std::chrono::milliseconds(80));
  CHECK(p.sequencing_timing.deadline_overruns == 20);
  CHECK(p.sequencing_timing.realtime_priority == 70);

  const std::string bad =
      "robot: {name: rt, sequencing_loop: {priority: 3}}\n"
      "loops:\n"
      "  - {name: motion, period_s: 0.01, realtime_priority: 100, cpu: -2, lock_memory: maybe, budget_s: 0, deadline_overruns: "
      "-1}\n";
  try {
    (void)load_robot_profile_from_string(bad, "bad.yaml", kRobots);
    FAIL("no error");
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    CHECK_THAT(m, Catch::Contains("bad.yaml:1:37: error: unknown key 'priority' in robot sequencing_loop"));
    CHECK_THAT(m, Catch::Contains("loop 'motion' realtime_priority: expected a whole number from 0 to 99, got '100'"));
    CHECK_THAT(m, Catch::Contains("loop 'motion' cpu: expected a whole number from -1 to 1023, got '-2'"));
    CHECK_THAT(m, Catch::Contains("loop 'motion' lock_memory: expected true or false, got 'maybe'"));
    CHECK_THAT(m, Catch::Contains("loop 'motion' budget_s: expected seconds from 1e-06 to 9e+09, got '0'"));
    CHECK_THAT(m, Catch::Contains("loop 'motion' deadline_overruns: expected a whole number from 0 to 1000000, got '-1'"));
    CHECK(e.diagnostics().error_count() == 6);
  }
}
