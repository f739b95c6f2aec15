// Proves that stepping the simulator (physics, every sensor, the HardwareInterface calls a
// controller makes) allocates nothing once running: the simulator sits under a real-time loop.
#include <catch2/catch.hpp>

#include <array>

#include "../support/counting_new.hpp"
#include "sim_test_util.hpp"
#include "tripodal/sim/simulator.hpp"

using namespace tripodal;
using namespace tripodal::sim;
using namespace tripodal::sim::test;
using namespace std::chrono_literals;

TEST_CASE("Simulator: steady-state steps allocate nothing", "[sim][alloc]") {
  World world = room_world(121, 101, {3.0, 2.5, 0.0});
  world.robot.laser.noise_stddev_m = 0.01;
  world.robot.odometry.noise_ratio = 0.01;
  // A visitor walking up and down by the far wall (seen by the laser, its legs and pauses drawn
  // as it goes) and a neck turning: the guide robot's world.
  Visitor v;
  v.name = "walker";
  v.path = {{5.3, 0.6}, {5.3, 4.4}};
  v.pause_max_s = 0.5;
  world.visitors.push_back(v);
  world.robot.joints.push_back({"neck", -0.7, 0.7, 1.0, 0.0, 50.0, {}});
  Simulator sim(std::move(world), omni3_base(), 3);
  std::array<double, 3> wheels{}, vel{}, pos{};
  sim.inverse_kinematics({0.3, 0.1, 0.5}, wheels);
  sim.step(1s);  // every sensor has published at least once
  const std::size_t before = tripodal::test::allocations();
  for (int k = 0; k < 1000; ++k) {
    if (k % 200 == 0) sim.command_joint(0, k % 400 == 0 ? 0.6 : -0.6);
    REQUIRE(sim.write_wheel_velocities(wheels));
    sim.step(10ms);
    REQUIRE(sim.read_wheel_states(vel, pos));
  }
  CHECK(tripodal::test::allocations() == before);
  CHECK(sim.laser().sequence() > 50);
  CHECK(sim.collisions() == 0);
  CHECK(sim.visitors()[0].position.y_m != Approx(0.6));
}
