#include "tripodal/sim/simulator.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include "../support/builtin_registries.hpp"
#include "../support/control_loops.hpp"
#include "../support/sim_runner.hpp"
#include "sim_test_util.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/kinematics.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/reactive/reactive_config.hpp"

using namespace tripodal;
using namespace tripodal::sim;
using namespace tripodal::sim::test;
using namespace std::chrono_literals;
using tripodal::test::make_control_loop;
using tripodal::test::SimRunner;

namespace {

constexpr double kPi = std::numbers::pi;

Time at(double s) { return time_from_seconds(s); }

void run(Simulator& sim, double seconds, Duration dt = 10ms) {
  const Time end = sim.now() + from_seconds(seconds);
  while (sim.now() < end) sim.step(std::min<Duration>(dt, end - sim.now()));
}

// FNV-1a over the bits of doubles and floats: two runs are equal only if bit-identical.
struct Hash {
  std::uint64_t h = 1469598103934665603ULL;
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
  }
  void add(double v) { bytes(&v, sizeof v); }
};

}  // namespace

TEST_CASE("Simulator: a differential base follows the analytic circle of its wheel speeds", "[sim][kinematics]") {
  Simulator sim(room_world(81, 81, {2.0, 2.0, 0.0}), differential_base(), 1);
  REQUIRE(sim.wheel_count() == 2);
  const double v = 0.3, w = 0.5, R = v / w;
  // Wheel speeds from the geometry by hand: (v -+ w * b / 2) / r.
  const std::array<double, 2> wheels = {(v - w * 0.21) / 0.09, (v + w * 0.21) / 0.09};
  REQUIRE(sim.write_wheel_velocities(wheels));
  for (int k = 1; k <= 12; ++k) {
    run(sim, 1.0);
    const double t = k;
    INFO("t = " << t);
    CHECK(sim.pose().x_m == Approx(2.0 + R * std::sin(w * t)).margin(1e-9));
    CHECK(sim.pose().y_m == Approx(2.0 + R * (1.0 - std::cos(w * t))).margin(1e-9));
    CHECK(wrap_angle(sim.pose().theta_rad - w * t) == Approx(0.0).margin(1e-9));
  }
  run(sim, 4.0 * kPi - 12.0);  // one full turn in total
  CHECK(sim.pose().x_m == Approx(2.0).margin(1e-9));
  CHECK(sim.pose().y_m == Approx(2.0).margin(1e-9));
  CHECK(sim.distance_m() == Approx(2.0 * kPi * R).margin(1e-6));
  CHECK(sim.rotation_rad() == Approx(2.0 * kPi).margin(1e-6));
  CHECK(sim.collisions() == 0);
}

TEST_CASE("Simulator: a three-wheel omni base follows the analytic circle of a body twist", "[sim][kinematics]") {
  Simulator sim(room_world(81, 81, {2.0, 2.0, 0.0}), omni3_base(), 1);
  REQUIRE(sim.wheel_count() == 3);
  const double vx = 0.2, vy = 0.1, w = 0.4;
  // Omni wheel i at angle a_i on radius L rolls tangentially: (-sin a vx + cos a vy + L w) / r.
  std::array<double, 3> wheels{};
  const std::array<double, 3> angles = {kPi / 3.0, kPi, 5.0 * kPi / 3.0};
  for (std::size_t i = 0; i < 3; ++i) {
    wheels[i] = (-std::sin(angles[i]) * vx + std::cos(angles[i]) * vy + 0.22 * w) / 0.05;
  }
  REQUIRE(sim.write_wheel_velocities(wheels));
  for (int k = 1; k <= 10; ++k) {
    run(sim, 1.5);
    const double t = 1.5 * k;
    INFO("t = " << t);
    CHECK(sim.pose().x_m == Approx(2.0 + (vx * std::sin(w * t) - vy * (1.0 - std::cos(w * t))) / w).margin(1e-9));
    CHECK(sim.pose().y_m == Approx(2.0 + (vx * (1.0 - std::cos(w * t)) + vy * std::sin(w * t)) / w).margin(1e-9));
    CHECK(wrap_angle(sim.pose().theta_rad - w * t) == Approx(0.0).margin(1e-9));
  }
  // The wheels read back what they were told, and their positions advance by speed * time.
  std::array<double, 3> vel{}, pos{};
  REQUIRE(sim.read_wheel_states(vel, pos));
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(vel[i] == Approx(wheels[i]).margin(1e-9));
    CHECK(pos[i] == Approx(wheels[i] * 15.0).margin(1e-6));
  }
}

TEST_CASE("Simulator: a mecanum base moves sideways, bad wheel commands are refused", "[sim][kinematics]") {
  Simulator sim(room_world(81, 81, {2.0, 1.0, 0.0}), mecanum_base4(), 1);
  REQUIRE(sim.wheel_count() == 4);
  sim.command_twist({0.0, 0.3, 0.0});
  run(sim, 2.0);
  CHECK(sim.pose().x_m == Approx(2.0).margin(1e-9));
  CHECK(sim.pose().y_m == Approx(1.6).margin(1e-9));
  CHECK(sim.pose().theta_rad == Approx(0.0).margin(1e-9));
  const std::array<double, 3> three{};
  CHECK_FALSE(sim.write_wheel_velocities(three));
  const std::array<double, 4> nan = {0.0, std::nan(""), 0.0, 0.0};
  CHECK_FALSE(sim.write_wheel_velocities(nan));
  ControllerConfig bad = differential_base();
  bad.type = "tracked";
  CHECK_THROWS_WITH(Simulator(room_world(20, 20, {0.5, 0.5, 0.0}), bad, 1), Catch::Contains("\"tracked\""));
}

TEST_CASE("Simulator: a wall stops the base against it and trips the facing bumper", "[sim][collision]") {
  World world = room_world(81, 81, {2.0, 2.0, 0.0});  // inner faces at 0.05 and 4.0
  world.robot.radius_m = 0.25;
  Simulator sim(std::move(world), differential_base(), 1);
  CHECK(sim.bumpers().latest().count == 4);
  CHECK_FALSE(sim.bumpers().latest().any());
  sim.command_twist({0.5, 0.0, 0.0});
  run(sim, 5.0);
  CHECK(sim.blocked());
  CHECK(sim.collisions() == 1);
  CHECK(sim.pose().x_m == Approx(4.0 - 0.25).margin(1e-4));
  CHECK(sim.pose().x_m < 3.75);
  CHECK(sim.velocity() == Twist2D{});
  CHECK(sim.bumpers().latest().pressed_mask == 0x1U);  // sector 0: the front
  std::array<double, 2> vel{}, pos{};
  REQUIRE(sim.read_wheel_states(vel, pos));
  CHECK(vel[0] == 0.0);
  CHECK(vel[1] == 0.0);
  REQUIRE(sim.events().size() == 1);
  CHECK(sim.events()[0].kind == SimEvent::Kind::collision);
  CHECK(sim.events()[0].detail == "at (3.75, 2.00)");
  CHECK(to_seconds(sim.events()[0].stamp) == Approx(3.5).margin(0.01));

  // Backing off releases the bumper; turning to face the wall with the left side presses sector 1.
  sim.command_twist({-0.2, 0.0, 0.0});
  run(sim, 0.5);
  CHECK_FALSE(sim.blocked());
  CHECK(sim.pose().x_m == Approx(3.65).margin(1e-3));
  CHECK_FALSE(sim.bumpers().latest().any());
  sim.command_twist({0.0, 0.0, -kPi / 2.0});
  run(sim, 1.0);
  sim.command_twist({0.0, 0.0, 0.0});
  // A differential base cannot move sideways: drive around to touch the wall on the left.
  REQUIRE(sim.set_pose({3.75 - 1e-6, 2.0, -kPi / 2.0}));
  run(sim, 0.1);
  CHECK(sim.bumpers().latest().pressed_mask == 0x2U);  // left (sector 1) faces +x
  CHECK_FALSE(sim.set_pose({3.9, 2.0, 0.0}));           // inside the wall: refused
}

TEST_CASE("Simulator: the same seed gives a bit-identical run, another seed another", "[sim][determinism]") {
  auto run_hash = [](std::uint64_t seed) {
    World world = room_world(121, 101, {3.0, 2.5, 0.3});
    world.robot.laser.noise_stddev_m = 0.02;
    world.robot.odometry.noise_ratio = 0.02;
    world.robot.odometry.scale_error_stddev = 0.01;
    world.robot.gyro.noise_stddev_rad_s = 0.01;
    world.obstacles.push_back({"box", {{4.0, 3.5}, {4.6, 3.5}, {4.6, 4.1}, {4.0, 4.1}}, at(3.0), std::nullopt, {}});
    Simulator sim(std::move(world), omni3_base(), seed);
    Hash h;
    std::size_t scans = 0;
    std::size_t last_seq = sim.laser().sequence();
    for (int k = 0; k < 2000; ++k) {
      const double t = k * 0.01;
      sim.command_twist({0.4 * std::cos(0.3 * t), 0.3 * std::sin(0.7 * t), 0.5 * std::sin(0.2 * t)});
      sim.step(10ms);
      h.add(sim.pose().x_m);
      h.add(sim.pose().y_m);
      h.add(sim.pose().theta_rad);
      h.add(sim.odometry().latest().pose.x_m);
      h.add(sim.gyro().latest().yaw_rate_rad_s);
      if (sim.laser().sequence() != last_seq) {
        last_seq = sim.laser().sequence();
        ++scans;
        const auto& r = sim.laser().latest().ranges_m;
        h.bytes(r.data(), r.size() * sizeof(float));
      }
    }
    // 20 s at 5.5 Hz; the period rounds to 181,818,182 ns, which puts the 110th scan just past 20 s.
    CHECK(scans == 109);
    return std::make_pair(h.h, sim.collisions());
  };
  const auto a = run_hash(7), b = run_hash(7), c = run_hash(8);
  CHECK(a.first == b.first);
  CHECK(a.second == b.second);
  CHECK(a.first != c.first);
}

TEST_CASE("Simulator: a dead laser stops publishing and its resource goes stale", "[sim][faults]") {
  World world = room_world(81, 81, {2.0, 2.0, 0.0});
  world.faults.dead_sensors.push_back({SensorKind::laser, at(2.0), at(4.0), {}});
  Simulator sim(std::move(world), omni3_base(), 1);
  REQUIRE(sim.laser().has_reading());
  CHECK(sim.laser().max_age() == 3 * from_seconds(1.0 / 5.5));
  run(sim, 2.1);
  const std::size_t seq = sim.laser().sequence();
  // t = 0, 0.18, ..., 1.82: the 12th scan falls at 11 x 181,818,182 ns, just inside the window.
  CHECK(seq == 11);
  CHECK(sim.laser().is_fresh(sim.now()));
  run(sim, 1.0);
  CHECK(sim.laser().sequence() == seq);
  CHECK(sim.laser().is_stale(sim.now()));
  CHECK(sim.sensor_dead(SensorKind::laser, at(3.0)));
  CHECK_FALSE(sim.sensor_dead(SensorKind::gyro, at(3.0)));
  CHECK(sim.gyro().is_fresh(sim.now()));
  run(sim, 1.2);  // t = 4.3
  CHECK(sim.laser().sequence() > seq);
  CHECK(sim.laser().is_fresh(sim.now()));
  REQUIRE(sim.events().size() == 2);
  CHECK(sim.events()[0].kind == SimEvent::Kind::sensor_dead);
  CHECK(sim.events()[0].detail == "laser");
  CHECK(sim.events()[0].stamp == at(2.0));
  CHECK(sim.events()[1].kind == SimEvent::Kind::sensor_restored);
  CHECK(sim.events()[1].stamp == at(4.0));
}

TEST_CASE("Simulator: a dead odometry makes the wheel states stale for the controller", "[sim][faults]") {
  World world = room_world(40, 40, {1.0, 1.0, 0.0});
  world.faults.dead_sensors.push_back({SensorKind::odometry, at(1.0), at(2.0), {}});
  Simulator sim(std::move(world), differential_base(), 1);
  std::array<double, 2> vel{}, pos{};
  CHECK(sim.read_wheel_states(vel, pos));
  run(sim, 1.5);
  CHECK_FALSE(sim.read_wheel_states(vel, pos));
  run(sim, 1.0);
  CHECK(sim.read_wheel_states(vel, pos));
}

TEST_CASE("Simulator: a box appearing on the path is seen by the laser and blocks the robot", "[sim][faults]") {
  World world = room_world(121, 81, {1.0, 2.0, 0.0});  // right wall's inner face at x = 6.0
  world.obstacles.push_back({"cart", {{3.0, 1.5}, {3.5, 1.5}, {3.5, 2.5}, {3.0, 2.5}}, at(1.0), at(8.0), {}});
  world.robot.laser.beams = 1440;
  Simulator sim(std::move(world), omni3_base(), 1);
  CHECK(sim.laser().latest().ranges_m[720] == Approx(5.0).margin(1e-5));
  run(sim, 1.2);
  CHECK(sim.laser().latest().ranges_m[720] == Approx(2.0).margin(1e-5));
  sim.command_twist({0.5, 0.0, 0.0});
  run(sim, 6.0);
  CHECK(sim.blocked());
  CHECK(sim.pose().x_m == Approx(3.0 - 0.25).margin(1e-4));
  CHECK(sim.bumpers().latest().pressed_mask == 0x1U);
  // Once the cart is gone the path is open again.
  run(sim, 1.5);  // t = 8.7
  CHECK_FALSE(sim.blocked());
  CHECK(sim.pose().x_m > 3.0);
  std::vector<SimEvent::Kind> kinds;
  for (const SimEvent& e : sim.events()) kinds.push_back(e.kind);
  CHECK(kinds == std::vector<SimEvent::Kind>{SimEvent::Kind::obstacle_appeared, SimEvent::Kind::collision,
                                             SimEvent::Kind::obstacle_removed});
  CHECK(sim.events()[0].detail == "cart");
}

TEST_CASE("Simulator: localization loss windows drive the navi localizer from ground truth", "[sim][faults]") {
  World world = room_world(81, 81, {2.0, 2.0, 0.0});
  world.faults.localization_loss = navi::parse_fault_schedule("1-2");
  Simulator sim(std::move(world), omni3_base(), 1);
  navi::CGroundTruthLocalizer loc(&sim);
  loc.configure({{"seed", Value{3.0}}});
  for (const navi::LocalizationFault& f : sim.world().faults.localization_loss) loc.add_fault(f);
  std::vector<ModuleEvent> ev;
  sim.command_twist({0.2, 0.0, 0.0});
  for (int k = 0; k < 30; ++k) {
    loc.step(sim.now(), ev);
    run(sim, 0.1);
  }
  REQUIRE(ev.size() >= 2);
  CHECK(ev[0].name == "localizer.ok");
  CHECK(ev[1].name == "localizer.lost");
  CHECK(to_seconds(ev[1].stamp) == Approx(1.0).margin(0.11));
  CHECK(sim.localization_lost(at(1.5)));
  CHECK_FALSE(sim.localization_lost(at(2.0)));
  REQUIRE(loc.relocalize(sim.now()));
  CHECK(sim.true_pose(sim.now())->x_m == Approx(2.6).margin(1e-9));
  CHECK(sim.events().size() == 2);
  CHECK(sim.events()[0].kind == SimEvent::Kind::localization_loss_start);
  CHECK(sim.events()[1].kind == SimEvent::Kind::localization_loss_end);
}

TEST_CASE("Simulator: a localization loss dazzles the laser, which keeps publishing scans without a return",
          "[sim][faults]") {
  World world = room_world(81, 81, {2.0, 2.0, 0.0});
  world.faults.localization_loss = navi::parse_fault_schedule("1-2");
  Simulator sim(std::move(world), omni3_base(), 1);
  const auto returns = [&] {
    std::size_t n = 0;
    for (float r : sim.laser().latest().ranges_m) n += std::isfinite(r) ? 1 : 0;
    return n;
  };
  run(sim, 0.5);
  CHECK(returns() > 0);
  run(sim, 1.0);  // t = 1.5
  const Time blinded = sim.laser().latest().stamp;
  CHECK(to_seconds(blinded) > 1.0);
  CHECK(returns() == 0);
  run(sim, 1.0);  // t = 2.5
  CHECK(sim.laser().latest().stamp > blinded);
  CHECK(returns() > 0);
}

TEST_CASE("Simulator: a kidnapping moves the robot, not its odometry", "[sim][faults]") {
  World world = room_world(81, 81, {2.0, 2.0, 0.0});
  world.faults.kidnappings.push_back({time_from_seconds(1.0), Pose2D{1.0, 3.0, 1.0}, {}});
  // Into the wall: refused, the robot stays where it is.
  world.faults.kidnappings.push_back({time_from_seconds(2.0), Pose2D{0.0, 0.0, 0.0}, {}});
  Simulator sim(std::move(world), omni3_base(), 1);
  run(sim, 0.95);
  const Pose2D odom_before = sim.odometry().latest().pose;
  CHECK(sim.pose().x_m == Approx(2.0));
  run(sim, 0.1);
  CHECK(sim.pose() == Pose2D{1.0, 3.0, 1.0});
  CHECK(std::abs(sim.odometry().latest().pose.x_m - odom_before.x_m) < 1e-6);
  CHECK(std::abs(sim.odometry().latest().pose.y_m - odom_before.y_m) < 1e-6);
  run(sim, 1.0);
  CHECK(sim.pose() == Pose2D{1.0, 3.0, 1.0});
  REQUIRE(sim.events().size() == 2);
  CHECK(sim.events()[0].kind == SimEvent::Kind::kidnapped);
  CHECK(sim.events()[0].detail == "to (1.00, 3.00, 1.00)");
  CHECK(sim.events()[1].detail == "refused, stays; to (0.00, 0.00, 0.00)");
}

TEST_CASE("Simulator: cliff sensors see a drop ahead, a robot driving into it falls", "[sim][cliff]") {
  World world = room_world(81, 81, {2.0, 2.0, 0.0});
  world.drops.push_back({"stairs", {{3.0, 1.0}, {3.5, 1.0}, {3.5, 3.0}, {3.0, 3.0}}, {}});
  Simulator sim(std::move(world), differential_base(), 1);
  REQUIRE(sim.cliff().latest().cliff.size() == 3);
  CHECK(sim.cliff().latest().cliff == std::vector<std::uint8_t>{0, 0, 0});
  sim.command_twist({0.5, 0.0, 0.0});
  run(sim, 1.7);  // x = 2.85: the front sensor (0.2 ahead) is over the drop, the side ones not
  CHECK(sim.cliff().latest().cliff == std::vector<std::uint8_t>{1, 0, 0});
  CHECK_FALSE(sim.fallen());
  run(sim, 1.0);
  CHECK(sim.fallen());
  const double x = sim.pose().x_m;
  CHECK(x == Approx(3.0).margin(0.01));
  run(sim, 1.0);
  CHECK(sim.pose().x_m == x);  // it does not move any more
  REQUIRE_FALSE(sim.events().empty());
  CHECK(sim.events().back().kind == SimEvent::Kind::fell);
}

TEST_CASE("Simulator: the battery drains per second and per metre and charges", "[sim][battery]") {
  World world = room_world(121, 81, {1.0, 2.0, 0.0});
  world.robot.battery.drain_per_s = 0.001;
  world.robot.battery.drain_per_m = 0.01;
  world.robot.battery.charge_per_s = 0.004;
  world.robot.battery.voltage_empty_v = 20.0;
  world.robot.battery.voltage_full_v = 25.0;
  world.robot.battery.capacity_ah = 10.0;
  Simulator sim(std::move(world), omni3_base(), 1);
  CHECK(sim.battery().latest().percentage == 1.0);
  CHECK(sim.battery().latest().voltage_v == 25.0);
  run(sim, 10.0);
  CHECK(sim.battery_charge() == Approx(0.99).margin(1e-9));
  sim.command_twist({0.5, 0.0, 0.0});
  run(sim, 4.0);  // 2 m
  CHECK(sim.battery_charge() == Approx(0.99 - 0.004 - 0.02).margin(1e-9));
  const BatteryReading& b = sim.battery().latest();
  CHECK(b.percentage == Approx(0.966).margin(1e-9));
  CHECK(b.voltage_v == Approx(20.0 + 5.0 * 0.966).margin(1e-9));
  CHECK(b.current_a == Approx(-(0.001 + 0.005) * 10.0 * 3600.0).margin(1e-6));  // A, discharging
  CHECK_FALSE(b.charging);
  sim.command_twist({});
  sim.set_charging(true);
  run(sim, 5.0);
  CHECK(sim.battery_charge() == Approx(0.966 + 5.0 * 0.003).margin(1e-9));
  CHECK(sim.battery().latest().charging);
  CHECK(sim.battery().latest().current_a > 0.0);
}

TEST_CASE("Simulator: an empty battery stops the wheels", "[sim][battery]") {
  World world = room_world(121, 81, {1.0, 2.0, 0.0});
  world.robot.battery.initial = 0.01;
  world.robot.battery.drain_per_m = 0.01;
  world.robot.battery.drain_per_s = 0.0;
  Simulator sim(std::move(world), omni3_base(), 1);
  sim.command_twist({0.5, 0.0, 0.0});
  run(sim, 5.0);
  CHECK(sim.pose().x_m == Approx(2.0).margin(0.01));  // 1 m of charge left
  REQUIRE_FALSE(sim.events().empty());
  CHECK(sim.events().back().kind == SimEvent::Kind::battery_empty);
}

TEST_CASE("Simulator: odometry drift grows with distance and depends only on the seed", "[sim][odometry]") {
  auto drift = [](std::uint64_t seed, double ratio, double seconds) {
    World world = room_world(401, 81, {1.0, 2.0, 0.0});
    world.robot.odometry.noise_ratio = ratio;
    Simulator sim(std::move(world), differential_base(), seed);
    sim.command_twist({0.5, 0.0, 0.0});
    run(sim, seconds);
    const OdometryReading& o = sim.odometry().latest();
    return std::hypot(o.pose.x_m - sim.pose().x_m, o.pose.y_m - sim.pose().y_m) + std::abs(wrap_angle(o.pose.theta_rad - sim.pose().theta_rad));
  };
  CHECK(drift(1, 0.0, 10.0) == Approx(0.0).margin(1e-9));
  CHECK(drift(1, 0.05, 10.0) > 0.0);
  CHECK(drift(1, 0.05, 10.0) == drift(1, 0.05, 10.0));
  // Averaged over seeds, driving four times as far drifts more.
  double short_sum = 0.0, long_sum = 0.0;
  for (std::uint64_t s = 1; s <= 8; ++s) {
    short_sum += drift(s, 0.05, 1.0);
    long_sum += drift(s, 0.05, 4.0);
  }
  CHECK(long_sum > short_sum);
}

TEST_CASE("Simulator: a controller drives the simulated base through the HardwareInterface", "[sim][controller]") {
  for (const ControllerConfig& base : {differential_base(), omni3_base()}) {
    INFO(base.type);
    Simulator sim(room_world(81, 81, {1.0, 1.0, 0.0}), base, 1);
    std::unique_ptr<CController> ctrl = tripodal::test::builtin_controllers().create(base, sim);
    ctrl->reset_odometry(sim.world().start_pose);
    const Twist2D cmd{0.3, 0.0, 0.2};
    for (int k = 0; k < 500; ++k) {
      ctrl->set_command(cmd, sim.now());
      REQUIRE(ctrl->update(sim.now()) != ControlStatus::hardware_fault);
      sim.step(10ms);
    }
    ctrl->update(sim.now());
    // The controller's odometry (noise-free encoders) agrees with the ground truth.
    const Pose2D& odom = ctrl->odometry().pose;
    CHECK(odom.x_m == Approx(sim.pose().x_m).margin(1e-6));
    CHECK(odom.y_m == Approx(sim.pose().y_m).margin(1e-6));
    CHECK(sim.distance_m() == Approx(1.5).margin(0.01));
  }
}

TEST_CASE("SimRunner: control loops and the simulator step together, BhGoToPose reaches a goal", "[sim][runner]") {
  const ReactiveConfig rc = load_reactive_config(std::string(TRIPODAL_SOURCE_DIR) + "/configs/reactive/psr_omni.yaml",
                                                 tripodal::test::builtin_controllers());
  const ControllerConfig& base = *rc.find_controller("base");
  Simulator sim(room_world(81, 81, {1.0, 1.0, 0.0}), base, 5);
  SimClock clock;
  OdometryResource odom("odom", 100ms);
  ResourceTable table;
  table.add(odom);
  sim.add_resources(table);
  CHECK(table.size() == 6);
  std::unique_ptr<ControlLoop> loop =
      make_control_loop(rc, *rc.find_loop("motion"), table, &sim, tripodal::test::builtin_controllers());
  loop->set_odometry_output(&odom);
  loop->controller()->reset_odometry(sim.world().start_pose);
  const BehaviorRegistry& reg = tripodal::test::builtin_behaviors();
  const BehaviorHandle go = loop->activate(reg.create("BhGoToPose"), {{"goal_x_m", Value{3.0}}, {"goal_y_m", Value{2.5}}}, "BhGoToPose");
  loop->activate(reg.create("BhAvoidObstacle"), {}, "BhAvoidObstacle");
  SimRunner runner(sim, clock);
  runner.add(*loop);
  const std::size_t cycles = runner.run_for(20s);
  std::vector<LoopEvent> events;
  loop->collect_events(events);
  for (const LoopEvent& e : events) UNSCOPED_INFO(e.event_name() << " " << e.reason << " at " << to_seconds(e.stamp));
  CHECK(cycles == 2001);
  CHECK(clock.now() == at(20.0));
  CHECK(sim.now() == at(20.0));
  CHECK(loop->status(go) == BehaviorStatus::succeeded);
  CHECK(sim.pose().x_m == Approx(3.0).margin(0.1));
  CHECK(sim.pose().y_m == Approx(2.5).margin(0.1));
  CHECK(sim.collisions() == 0);
}

namespace {
// A wall clock for the pacer's test: sleeping moves it to the deadline, and records it.
class FakeWall final : public Clock {
 public:
  [[nodiscard]] Time now() const noexcept override { return now_; }
  void sleep_until(Time deadline) const noexcept override {
    deadlines.push_back(deadline);
    if (deadline > now_) now_ = deadline;
  }
  mutable Time now_{at(100.0)};
  mutable std::vector<Time> deadlines;
};
}  // namespace

TEST_CASE("RealtimePacer: sleeps on the injected clock until wall time matches simulated time", "[sim][runner]") {
  FakeWall wall;
  RealtimePacer pacer(wall, 2.0);
  pacer.pace(at(10.0));
  CHECK(wall.deadlines.empty());
  pacer.pace(at(11.0));
  REQUIRE(wall.deadlines.size() == 1);
  CHECK(wall.deadlines[0] == at(100.5));  // twice as fast as real time
  Simulator sim(room_world(40, 40, {1.0, 1.0, 0.0}), omni3_base(), 1);
  SimClock clock;
  SimRunner runner(sim, clock, 50ms);
  RealtimePacer paced(wall);
  runner.set_pacer(&paced);
  runner.run_for(1s);
  CHECK(wall.now() == at(100.5) + from_seconds(1.0) - from_seconds(0.05));  // the first period only starts the pacing
  CHECK(sim.now() == at(1.0));
}

TEST_CASE("Simulator: the map's edge is a wall for the base and the bumpers", "[sim][collision]") {
  World world;
  world.grid = navi::OccupancyGrid(40, 40, 0.05, {}, navi::Occupancy::free);  // 2 m, no walls drawn
  world.start_pose = {1.0, 1.0, kPi / 2.0};
  Simulator sim(std::move(world), omni3_base(), 1);
  sim.command_twist({0.4, 0.0, 0.0});  // forward = +y
  run(sim, 5.0);
  CHECK(sim.blocked());
  CHECK(sim.pose().y_m == Approx(2.0 - 0.25).margin(1e-4));
  CHECK(sim.bumpers().latest().pressed_mask == 0x1U);
}

TEST_CASE("Simulator: a world of 10^5 obstacles starts, laid as the whole-map method lays them", "[sim][faults][limits]") {
  // Before, each obstacle was rasterised over the whole map and each appearance laid every present
  // obstacle again: 10^4 obstacles took 30 s to start, 10^5 did not start in 120 s. Now an obstacle
  // costs its bounding box and those appearing together are laid once (timings: bench/sim).
  const auto boxes = [](World& world, int columns, int rows, double spacing_m, double x0_m, double y0_m) {
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < columns; ++c) {
        const double x = x0_m + c * spacing_m, y = y0_m + r * spacing_m;
        // Every third box comes later, every fifth goes again: appearing and leaving in one step.
        const Time appear = at((r * columns + c) % 3 == 0 ? 0.1 : 0.0);
        const std::optional<Time> gone = (r * columns + c) % 5 == 0 ? std::optional<Time>(at(0.1)) : std::nullopt;
        world.obstacles.push_back({"b" + std::to_string(r * columns + c), {{x, y}, {x + 0.08, y}, {x + 0.08, y + 0.08}, {x, y + 0.08}},
                                   appear, gone, {}});
      }
    }
  };
  // The reference, the old method: every cell of the map tested against every present obstacle.
  const auto expected_solid = [](const World& world, Time t, Pose2D robot) {
    std::vector<std::uint8_t> solid = SolidMap(world.grid).cells();
    const double keep_out = world.robot.radius_m + world.grid.resolution_m();
    for (const DynamicObstacle& o : world.obstacles) {
      if (!(t >= o.appear && (!o.disappear || t < *o.disappear))) continue;
      const navi::Region region{o.name, o.polygon, o.where};
      for (std::size_t i = 0; i < world.grid.size(); ++i) {
        const navi::Point2D p = world.grid.cell_center(world.grid.cell(i));
        if (region.contains(p) && std::hypot(p.x_m - robot.x_m, p.y_m - robot.y_m) >= keep_out) solid[i] = 1;
      }
    }
    return solid;
  };
  SECTION("a small world, the same cells as the old method at each step") {
    World world = room_world(121, 81, {0.6, 0.6, 0.0});  // 6 m x 4 m
    boxes(world, 20, 12, 0.27, 0.5, 0.5);  // some boxes under the robot's keep-out disc
    const World copy = world;
    Simulator sim(std::move(world), omni3_base(), 1);
    sim.step(10ms);
    CHECK(sim.solid_map().cells() == expected_solid(copy, sim.now(), sim.pose()));
    run(sim, 0.1);  // the late third appears, every fifth box goes
    CHECK(sim.solid_map().cells() == expected_solid(copy, sim.now(), sim.pose()));
  }
  SECTION("10^5 obstacles on a 1000 x 1000 cell map") {
    World world = room_world(1000, 1000, {0.5, 0.5, 0.0});  // 50 m x 50 m
    boxes(world, 320, 313, 0.15, 1.5, 1.5);
    REQUIRE(world.obstacles.size() >= 100000U);
    Simulator sim(std::move(world), omni3_base(), 1);
    sim.step(10ms);
    // Each box covers 2 x 2 cells; at t = 0 the boxes not late and not gone... every fifth is
    // gone only at 0.1 s, so present now: all but the late third.
    std::size_t late = 0;
    for (std::size_t k = 0; k < 320U * 313U; ++k) late += k % 3 == 0 ? 1 : 0;
    const auto solid_cells = [&] { return static_cast<std::size_t>(std::count(sim.solid_map().cells().begin(), sim.solid_map().cells().end(), 1)); };
    const std::size_t walls = 4U * 1000U - 4U;
    CHECK(solid_cells() == walls + 4U * (320U * 313U - late));
    CHECK(sim.events().size() == 320U * 313U - late);
  }
}

TEST_CASE("Simulator: a sonar-only obstacle (glass) is invisible to the laser, solid to the body and the bumpers",
          "[sim][safety]") {
  World world = room_world(81, 81, {1.0, 2.0, 0.0});
  world.robot.laser.angle_min_rad = 0.0;  // one beam, straight ahead
  world.robot.laser.angle_max_rad = 0.0;
  world.robot.laser.beams = 1;
  world.sonar_only.push_back({"glass", {{2.5, 1.0}, {2.6, 1.0}, {2.6, 3.0}, {2.5, 3.0}}, {}});
  Simulator sim(std::move(world), differential_base(), 1);
  // The laser sees the far wall (x = 4.0), the body's map holds the glass.
  CHECK(sim.laser().latest().ranges_m[0] == Approx(2.95).margin(0.06));
  CHECK(sim.solid_map().cast({1.0, 2.0}, 0.0, 5.0) == Approx(1.5).margin(0.06));
  CHECK(sim.laser_map().cast({1.0, 2.0}, 0.0, 5.0) == Approx(2.95).margin(0.06));
  sim.command_twist({0.5, 0.0, 0.0});
  run(sim, 4.0);
  CHECK(sim.pose().x_m == Approx(2.25).margin(0.06));  // stopped against the glass
  CHECK(sim.collisions() == 1);
  CHECK(sim.sonar_only_collisions() == 1);
  CHECK((sim.bumpers().latest().pressed_mask & 1U) != 0);
  REQUIRE_FALSE(sim.events().empty());
  CHECK_THAT(sim.events().back().detail, Catch::Contains("sonar-only"));
}

TEST_CASE("Simulator: a wheel over a ledge is a fall, whatever the centre", "[sim][cliff][safety]") {
  // Driving along the ledge 0.15 m beside it: the centre stays on the floor, the right wheel
  // (0.21 m from it) goes over.
  World world = room_world(81, 81, {1.0, 2.0, 0.0});
  world.drops.push_back({"ledge", {{0.5, 0.5}, {3.5, 0.5}, {3.5, 1.85}, {0.5, 1.85}}, {}});
  Simulator sim(std::move(world), differential_base(), 1);
  run(sim, 0.1);
  CHECK(sim.fallen());
  REQUIRE_FALSE(sim.events().empty());
  CHECK(sim.events().back().kind == SimEvent::Kind::fell);
  CHECK_THAT(sim.events().back().detail, Catch::Contains("wheel over the edge"));
}

TEST_CASE("Simulator: a drop's depth under each cliff sensor, a stuck sensor reads its fault", "[sim][cliff][safety]") {
  World world = room_world(81, 81, {2.0, 2.0, 0.0});
  world.drops.push_back({"step", {{2.15, 1.0}, {3.5, 1.0}, {3.5, 3.0}, {2.15, 3.0}}, {}, 0.17});
  world.faults.stuck_cliff.push_back({0, false, {}});
  world.faults.stuck_cliff.push_back({2, true, {}});
  Simulator sim(std::move(world), differential_base(), 1);
  CHECK(sim.cliff_depth_m(0) == 0.0);       // over the step, stuck at the floor's reading
  CHECK(sim.cliff_depth_m(1) == 0.0);       // at x = 2.1: floor
  CHECK(std::isinf(sim.cliff_depth_m(2)));  // stuck at a drop's
  CHECK(sim.cliff_depth_m(7) == 0.0);
  CHECK(sim.cliff().latest().cliff == std::vector<std::uint8_t>{0, 0, 1});
  sim.set_pose({2.1, 2.0, 0.0});
  CHECK(sim.cliff_depth_m(1) == Approx(0.17));  // (0.1, 0.17) ahead: x = 2.2, over the step
}
