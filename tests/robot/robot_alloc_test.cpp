// Proves that the whole PSR-2 demo robot's reactive loop allocates nothing in steady state: the
// robot of configs/robots/psr2.yaml on the simulator, mid-cleaning (BhCleaning following the
// coverage planner's path, the laser and bumpers read every cycle, the omni controller driving the
// wheels), counted with a replaced global operator new over 10,000 reactive periods. The sequencing
// loop (planning, the supervisor) and the simulator may allocate: only the loop's cycles are counted.
// Its own executable, so the replacement affects no other suite.
#include <catch2/catch.hpp>

#include <memory>

#include "../support/counting_new.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;

TEST_CASE("The PSR-2 robot's reactive loop allocates nothing over 10,000 periods mid-cleaning", "[robot][alloc]") {
  const std::filesystem::path configs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
  RobotPlugins plugins;
  register_all(plugins, std::make_shared<sim::World>(sim::load_world(configs / "worlds/workspace.yaml")));
  SimClock clock;
  const auto robot = Robot::assemble(load_robot_profile(configs / "robots/psr2.yaml"), plugins, clock);
  REQUIRE(robot->command("clean the room 3211").accepted);
  // Into the first section's coverage, past the first seconds of it.
  while (!robot->behavior_active("BhCleaning") && clock.now() < time_from_seconds(300)) robot->run_for(std::chrono::milliseconds(100));
  REQUIRE(robot->behavior_active("BhCleaning"));
  robot->run_for(std::chrono::seconds(20));

  // The same order as Robot::run_until (hardware, sequencing when due, then the reactive loop),
  // with only the reactive cycles counted.
  ControlLoop& loop = robot->behavior_loop();
  auto& sim = dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator();
  const auto* coverage = robot->module<navi::CCoverageModule>();
  REQUIRE(coverage->progress().count("A") == 1);
  const double progress_before = coverage->progress().at("A").done_m;
  const double distance_before = sim.distance_m();
  const std::uint64_t cycles_before = loop.cycles();
  const Duration period = loop.period();
  const auto sequencing_every = from_seconds(0.05) / period;  // the profile's sequencing period
  std::size_t in_loop = 0;
  Time t = clock.now();
  for (int i = 0; i < 10'000; ++i) {
    t += period;
    clock.set(t);
    robot->hardware()->advance_to(t);
    if (i % sequencing_every == 0) robot->step_sequencing();
    const std::size_t before = test::allocations();
    (void)loop.step(t);
    in_loop += test::allocations() - before;
  }
  CHECK(in_loop == 0);
  CHECK(loop.cycles() - cycles_before == 10'000);
  // The cycles did real work: the robot kept cleaning along its path.
  CHECK(robot->behavior_active("BhCleaning"));
  CHECK(sim.distance_m() - distance_before > 5.0);  // 100 s at up to 0.3 m/s
  CHECK(coverage->progress().at("A").done_m > progress_before + 5.0);
  CHECK(loop.last_cycle().controller_status != ControlStatus::hardware_fault);
}
