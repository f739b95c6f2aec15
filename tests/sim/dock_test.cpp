// The simulator's charging docks (World::docks) and the battery they charge, up to a whole robot
// that drives to its dock and charges with the dock-and-charge process (configs/petri/
// PrDockCharge.xml), its facts provided by the BatteryMonitor module.
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <numbers>
#include <string>

#include "sim_test_util.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace tripodal::sim;
using namespace tripodal::sim::test;
using namespace std::chrono_literals;

namespace {

const std::string kWorlds = std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/";
const std::string kHead =
    "map: " + kWorlds + "workspace_map.yaml\nregions: " + kWorlds + "workspace_regions.yaml\nstart_pose: [0.8, 0.8, 0.0]\n";

void run(Simulator& sim, double seconds) {
  const auto steps = static_cast<int>(seconds / 0.01 + 0.5);
  for (int i = 0; i < steps; ++i) sim.step(10ms);
}

std::size_t count(const Simulator& sim, SimEvent::Kind kind) {
  return static_cast<std::size_t>(
      std::count_if(sim.events().begin(), sim.events().end(), [&](const SimEvent& e) { return e.kind == kind; }));
}

}  // namespace

TEST_CASE("parse_world: docks by pose or by a node of the regions, with their contact", "[sim][world][dock]") {
  const World w = parse_world(kHead +
                                  "docks:\n"
                                  "  - {name: pad, pose: [2.0, 3.0, 1.5708], contact_radius_m: 0.05, heading_tolerance_deg: 10}\n"
                                  "  - {node: charger}\n",
                              "world.yaml");
  REQUIRE(w.docks.size() == 2);
  CHECK(w.docks[0].name == "pad");
  CHECK(w.docks[0].pose.x_m == 2.0);
  CHECK(w.docks[0].pose.theta_rad == Approx(1.5708));
  CHECK(w.docks[0].contact_radius_m == 0.05);
  CHECK(w.docks[0].heading_tolerance_rad == Approx(10.0 * std::numbers::pi / 180.0));
  CHECK(w.docks[1].name == "charger");  // the node's name and pose
  CHECK(w.docks[1].pose.x_m == 0.8);
  CHECK(w.docks[1].contact_radius_m == 0.1);

  CHECK(load_world(kWorlds + "workspace_dock.yaml").docks.size() == 1);
}

TEST_CASE("parse_world: a wrong dock is located", "[sim][world][dock][errors]") {
  CHECK_THAT(world_error_of(kHead + "docks:\n  - {name: d, pose: [1, 1], node: charger}\n"),
             Catch::Contains("world.yaml:5:5: error: a docks entry needs exactly one of pose"));
  CHECK_THAT(world_error_of(kHead + "docks:\n  - {node: chargr}\n"),
             Catch::Contains("world.yaml:5:12: error: unknown node 'chargr'"));
  CHECK_THAT(world_error_of(kHead + "docks:\n  - {pose: [1, 1], contact_radius_m: 0}\n"),
             Catch::Contains("world.yaml:5:38: error: dock 'dock 1'.contact_radius_m: expected a number > 0, got 0"));
  CHECK_THAT(world_error_of(kHead + "docks:\n  - {name: in_wall, pose: [0.0, 0.0]}\n"),
             Catch::Contains("world.yaml:5:5: error: dock 'in_wall': docked there, the robot's footprint"));
  CHECK_THAT(world_error_of(kHead + "docks:\n  - {pose: [1, 1], voltage: 24}\n"), Catch::Contains("unknown key 'voltage'"));
}

TEST_CASE("Simulator: on a dock's contacts the battery charges, off them it drains", "[sim][battery][dock]") {
  World world = room_world(121, 81, {1.0, 2.0, 0.0});
  world.robot.battery.initial = 0.5;
  world.robot.battery.drain_per_s = 0.001;
  world.robot.battery.drain_per_m = 0.0;
  world.robot.battery.charge_per_s = 0.004;
  world.docks.push_back(Dock{"pad", {2.0, 2.0, 0.0}, 0.05, 0.2, {}});
  Simulator sim(std::move(world), omni3_base(), 1);

  run(sim, 5.0);  // 1 m short of the dock: draining
  CHECK_FALSE(sim.charging());
  CHECK(sim.battery_charge() == Approx(0.5 - 0.005).margin(1e-9));
  CHECK_FALSE(sim.battery().latest().charging);

  sim.command_twist({0.5, 0.0, 0.0});
  run(sim, 2.0);  // to x = 2.0: on the contacts
  sim.command_twist({});
  run(sim, 0.01);
  REQUIRE(sim.dock() == 0);
  CHECK(sim.charging());
  CHECK(count(sim, SimEvent::Kind::docked) == 1);
  const double docked_at = sim.battery_charge();
  run(sim, 10.0);
  CHECK(sim.battery_charge() == Approx(docked_at + 10.0 * 0.003).margin(1e-6));  // 4e-3 in, 1e-3 out
  CHECK(sim.battery().latest().charging);
  CHECK(sim.battery().latest().current_a > 0.0);

  sim.command_twist({-0.5, 0.0, 0.0});
  run(sim, 0.5);  // 0.25 m back: off the contacts
  sim.command_twist({});
  CHECK(sim.dock() == -1);
  CHECK_FALSE(sim.charging());
  CHECK(count(sim, SimEvent::Kind::undocked) == 1);

  // An extra load (a lamp) drains on top of the electronics.
  const double before = sim.battery_charge();
  sim.set_extra_drain_per_s(0.002);
  run(sim, 5.0);
  CHECK(sim.battery_charge() == Approx(before - 5.0 * 0.003).margin(1e-6));
}

TEST_CASE("Simulator: a dock's contacts need the heading within its tolerance", "[sim][battery][dock]") {
  World world = room_world(121, 81, {2.0, 2.0, std::numbers::pi / 2.0});
  world.docks.push_back(Dock{"wall_dock", {2.0, 2.0, 0.0}, 0.05, 0.2, {}});
  Simulator sim(std::move(world), omni3_base(), 1);
  run(sim, 0.1);
  CHECK(sim.dock() == -1);  // on the spot, turned 90 degrees away
  sim.command_twist({0.0, 0.0, -0.5});
  run(sim, 2.9);  // 1.45 rad of the 1.57: within 0.2 rad
  sim.command_twist({});
  run(sim, 0.01);
  CHECK(sim.dock() == 0);
  CHECK(sim.charging());
}

TEST_CASE("A robot drives to its dock and charges: PrDockCharge on the simulator with BatteryMonitor's facts",
          "[sim][dock][robot]") {
  auto world = std::make_shared<const World>(load_world(kWorlds + "workspace_dock.yaml"));
  RobotPlugins plugins = builtin_plugins(world);
  SimClock clock;
  const RobotProfile profile = load_robot_profile(std::string(TRIPODAL_TEST_DATA_DIR) + "/robot/dock_charge.yaml");
  auto robot = Robot::assemble(profile, plugins, clock);
  LifecycleRecorder life(true);
  robot->planner().add_observer(life);
  robot->supervisor().add_observer(life);
  auto* hw = dynamic_cast<SimHardware*>(robot->hardware());
  REQUIRE(hw != nullptr);
  const Simulator& sim = hw->simulator();

  REQUIRE(robot->command("charge at the charger").accepted);
  robot->run_until(clock.now());
  double lowest = 1.0;
  double docked_s = -1.0;
  while (robot->planner().busy() && to_seconds(clock.now()) < 600.0) {
    robot->run_for(from_seconds(0.1));
    lowest = std::min(lowest, sim.battery_charge());
    if (docked_s < 0.0 && sim.charging()) docked_s = to_seconds(clock.now());
  }
  INFO(life.str());
  CHECK_FALSE(robot->planner().busy());
  REQUIRE(docked_s > 0.0);  // it drove there: the contacts touched
  CHECK(count(sim, SimEvent::Kind::docked) >= 1);
  CHECK(sim.dock() == 0);
  CHECK(lowest < 0.9);                  // the drive drained it ...
  CHECK(sim.battery_charge() >= 0.95);  // ... the dock charged it to full_percent
  CHECK(sim.battery_charge() < 0.96);   // and the net ended the charge there
  CHECK_THAT(life.str(), Catch::Contains("PrDockCharge fire t3") && Catch::Contains("PrDockCharge fire t5") &&
                             Catch::Contains("PrDockCharge succeeded"));
  CHECK_THAT(life.str(), Catch::Contains("task charge succeeded"));
}
