// Limits, timeout and registry of the controllers (through the differential and omni bases).
#include "tripodal/controllers/controller.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <numbers>

#include "../support/builtin_registries.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/controllers/differential_drive_controller.hpp"
#include "tripodal/controllers/holonomic_controller.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

ControllerConfig diff_config() {
  ControllerConfig c;
  c.name = "jinny";
  c.type = "differential";
  c.period = 10ms;
  c.differential = {0.4, 0.1};
  return c;
}

ControllerConfig omni_config() {
  ControllerConfig c;
  c.name = "psr";
  c.type = "omni";
  c.period = 10ms;
  const double angles[] = {std::numbers::pi / 2, std::numbers::pi / 2 + 2 * std::numbers::pi / 3,
                           std::numbers::pi / 2 + 4 * std::numbers::pi / 3};
  c.holonomic = omni_base(0.05, 0.2, angles);
  return c;
}

}  // namespace

TEST_CASE("A step command ramps at the configured acceleration within 1e-6") {
  ControllerConfig c = diff_config();
  c.limits.vx.max_acceleration = 0.5;
  c.limits.vx.max_velocity = 0.4;
  c.limits.wz.max_acceleration = 2.0;
  IdealWheelHardware hw(2, c.period);
  DifferentialDriveController ctl(c, hw);
  Time t = Time{0ms};
  ctl.set_command({1.0, 0.0, 1.0}, t);
  for (int k = 1; k <= 150; ++k) {
    t += 10ms;
    const ControlStatus s = ctl.update(t);
    // The first update uses the nominal period; later ones the measured 10 ms: same ramp.
    const double expected_v = std::min(0.4, 0.5 * 0.01 * k);
    const double expected_w = std::min(1.0, 2.0 * 0.01 * k);
    REQUIRE(ctl.limited_command().vx_m_s == Approx(expected_v).margin(1e-6));
    REQUIRE(ctl.limited_command().wz_rad_s == Approx(expected_w).margin(1e-6));
    REQUIRE(s == ControlStatus::limited);  // vx is clipped to 0.4 at the end
  }
}

TEST_CASE("Limits use the measured period") {
  ControllerConfig c = diff_config();
  c.limits.vx.max_acceleration = 1.0;
  IdealWheelHardware hw(2, c.period);
  DifferentialDriveController ctl(c, hw);
  ctl.set_command({1.0, 0.0, 0.0}, Time{0ms});
  ctl.update(Time{0ms});  // nominal period: 0.01
  CHECK(ctl.limited_command().vx_m_s == Approx(0.01).margin(1e-9));
  ctl.update(Time{5ms});
  CHECK(ctl.limited_command().vx_m_s == Approx(0.015).margin(1e-9));
  ctl.update(Time{20ms});
  CHECK(ctl.limited_command().vx_m_s == Approx(0.030).margin(1e-9));
  // A stall longer than two periods is counted as two: no jump.
  ctl.update(Time{1020ms});
  CHECK(ctl.limited_command().vx_m_s == Approx(0.050).margin(1e-9));
  // Same time again: no change.
  ctl.update(Time{1020ms});
  CHECK(ctl.limited_command().vx_m_s == Approx(0.050).margin(1e-9));
}

TEST_CASE("Deceleration limit applies when braking, acceleration when speeding up") {
  BodyLimits lim;
  lim.vx.max_acceleration = 1.0;
  lim.vx.max_deceleration = 4.0;
  TwistLimiter limiter(lim);
  bool limited = false;
  for (int k = 0; k < 100; ++k) limiter.apply({1.0, 0, 0}, 0.01, limited);
  CHECK(limiter.velocity().vx_m_s == Approx(1.0));
  limiter.apply({0.0, 0, 0}, 0.01, limited);
  CHECK(limiter.velocity().vx_m_s == Approx(0.96).margin(1e-12));
  CHECK(limited);
  // Reversing: braking to zero at 4, then speeding up backwards at 1.
  for (int k = 0; k < 24; ++k) limiter.apply({-1.0, 0, 0}, 0.01, limited);
  CHECK(limiter.velocity().vx_m_s == Approx(0.0).margin(1e-9));
  limiter.apply({-1.0, 0, 0}, 0.01, limited);
  CHECK(limiter.velocity().vx_m_s == Approx(-0.01).margin(1e-12));
}

TEST_CASE("Jerk limit bounds the change of acceleration and does not overshoot") {
  BodyLimits lim;
  lim.wz.max_acceleration = 2.0;
  lim.wz.max_jerk = 10.0;
  TwistLimiter limiter(lim);
  bool limited = false;
  double prev_a = 0.0, prev_v = 0.0, peak_v = 0.0;
  int steps = 0;
  for (; steps < 1000 && std::abs(limiter.velocity().wz_rad_s - 1.0) > 1e-12; ++steps) {
    limiter.apply({0, 0, 1.0}, 0.01, limited);
    const double a = limiter.acceleration().wz_rad_s;
    const bool last = std::abs(limiter.velocity().wz_rad_s - 1.0) <= 1e-12;
    // The final period lands exactly on the target (a residual smaller than one jerk step).
    if (!last) REQUIRE(std::abs(a - prev_a) <= 10.0 * 0.01 * (1 + 1e-6));
    REQUIRE(std::abs(a) <= 2.0 + 1e-9);
    REQUIRE(limiter.velocity().wz_rad_s >= prev_v - 1e-12);  // monotonic: no overshoot-and-return
    peak_v = std::max(peak_v, limiter.velocity().wz_rad_s);
    prev_a = a;
    prev_v = limiter.velocity().wz_rad_s;
  }
  CHECK(limiter.velocity().wz_rad_s == Approx(1.0));
  CHECK(peak_v <= 1.0 + 1e-12);
  CHECK(steps > 50);  // slower than the acceleration limit alone (50 steps)
}

TEST_CASE("Unset limits mean no limit") {
  TwistLimiter limiter{BodyLimits{}};
  bool limited = true;
  const Twist2D out = limiter.apply({5.0, -3.0, 7.0}, 0.01, limited);
  CHECK(out == Twist2D{5.0, -3.0, 7.0});
  CHECK_FALSE(limited);
}

TEST_CASE("Wheel saturation scales the twist and keeps the curvature (differential)") {
  ControllerConfig c = diff_config();
  c.max_wheel_speed_rad_s = 10.0;  // 1 m/s at the rim
  IdealWheelHardware hw(2, c.period);
  DifferentialDriveController ctl(c, hw);
  const Twist2D cmd{1.5, 0.0, 2.0};  // curvature 4/3; wheels (1.5 -+ 0.4)/0.1 = 11, 19 rad/s
  ctl.set_command(cmd, Time{0ms});
  CHECK(ctl.update(Time{0ms}) == ControlStatus::limited);
  const Twist2D out = ctl.limited_command();
  CHECK(out.wz_rad_s / out.vx_m_s == Approx(cmd.wz_rad_s / cmd.vx_m_s).epsilon(1e-12));
  const auto w = ctl.wheel_commands();
  CHECK(std::max(std::abs(w[0]), std::abs(w[1])) == Approx(10.0));
  CHECK(hw.commands()[1] == Approx(10.0));
  // Capabilities reflect the wheel limit.
  CHECK(ctl.capabilities().max_vx_m_s == Approx(1.0));
  CHECK(ctl.capabilities().max_vy_m_s == 0.0);
  CHECK_FALSE(ctl.capabilities().holonomic());
}

TEST_CASE("Wheel saturation keeps direction and curvature (omni)") {
  ControllerConfig c = omni_config();
  c.max_wheel_speed_rad_s = 8.0;
  IdealWheelHardware hw(3, c.period);
  HolonomicController ctl(c, hw);
  const Twist2D cmd{0.9, -0.6, 1.2};
  ctl.set_command(cmd, Time{0ms});
  CHECK(ctl.update(Time{0ms}) == ControlStatus::limited);
  const Twist2D out = ctl.limited_command();
  const double s = out.vx_m_s / cmd.vx_m_s;
  CHECK(s < 1.0);
  CHECK(out.vy_m_s == Approx(s * cmd.vy_m_s));
  CHECK(out.wz_rad_s == Approx(s * cmd.wz_rad_s));
  double peak = 0;
  for (double w : ctl.wheel_commands()) peak = std::max(peak, std::abs(w));
  CHECK(peak == Approx(8.0));
}

TEST_CASE("Command timeout brakes to zero through the deceleration limit") {
  ControllerConfig c = diff_config();
  c.cmd_timeout = 100ms;
  c.limits.vx.max_acceleration = 10.0;
  c.limits.vx.max_deceleration = 1.0;
  IdealWheelHardware hw(2, c.period);
  DifferentialDriveController ctl(c, hw);
  ctl.set_command({0.5, 0.0, 0.0}, Time{0ms});
  Time t = Time{0ms};
  ctl.update(t);
  for (int k = 0; k < 10; ++k) ctl.update(t += 10ms);
  REQUIRE(ctl.limited_command().vx_m_s == Approx(0.5));
  REQUIRE(ctl.last_status() == ControlStatus::ok);  // 100 ms old: not yet expired
  // Expired from here on: 1 m/s^2 down from 0.5 m/s is 50 periods.
  double prev = 0.5;
  for (int k = 1; k <= 50; ++k) {
    REQUIRE(ctl.update(t += 10ms) == ControlStatus::timed_out);
    REQUIRE(ctl.limited_command().vx_m_s == Approx(prev - 0.01).margin(1e-9));
    prev = ctl.limited_command().vx_m_s;
  }
  CHECK(ctl.limited_command().vx_m_s == Approx(0.0).margin(1e-9));
  CHECK(hw.commands()[0] == Approx(0.0).margin(1e-9));
  // A fresh command ends the timeout.
  ctl.set_command({0.2, 0.0, 0.0}, t);
  CHECK(ctl.update(t += 10ms) == ControlStatus::limited);
}

TEST_CASE("A zero command timeout disables the timeout") {
  ControllerConfig c = diff_config();
  c.cmd_timeout = 0ms;
  IdealWheelHardware hw(2, c.period);
  HolonomicController* unused = nullptr;
  (void)unused;
  DifferentialDriveController ctl(c, hw);
  ctl.set_command({0.3, 0.0, 0.1}, Time{0ms});
  for (int k = 0; k <= 1000; ++k) REQUIRE(ctl.update(Time{k * 10ms}) == ControlStatus::ok);
  CHECK(ctl.limited_command() == Twist2D{0.3, 0.0, 0.1});
}

TEST_CASE("With a timeout and no command at all the base stays still") {
  ControllerConfig c = omni_config();
  c.cmd_timeout = 50ms;
  IdealWheelHardware hw(3, c.period);
  HolonomicController ctl(c, hw);
  CHECK(ctl.update(Time{0ms}) == ControlStatus::timed_out);
  CHECK(ctl.limited_command() == Twist2D{});
}

TEST_CASE("Hardware faults are reported, not thrown") {
  ControllerConfig c = diff_config();
  IdealWheelHardware hw(2, c.period);
  DifferentialDriveController ctl(c, hw);
  ctl.set_command({0.1, 0, 0}, Time{0ms});
  CHECK(ctl.update(Time{0ms}) == ControlStatus::ok);
  hw.set_refuse_writes(true);
  CHECK(ctl.update(Time{10ms}) == ControlStatus::hardware_fault);
  hw.set_refuse_writes(false);
  hw.set_stale_reads(true);
  CHECK(ctl.update(Time{20ms}) == ControlStatus::hardware_fault);
  hw.set_stale_reads(false);
  CHECK(ctl.update(Time{30ms}) == ControlStatus::ok);
}

TEST_CASE("Controllers are created by name from configuration") {
  const ControllerRegistry& reg = test::builtin_controllers();
  CHECK(reg.names() == std::vector<std::string>{"differential", "mecanum", "omni"});
  IdealWheelHardware two(2, 10ms), three(3, 10ms), four(4, 10ms);
  auto d = reg.create(diff_config(), two);
  CHECK(d->type_name() == "differential");
  CHECK(d->manifest().name == "differential");
  CHECK(d->manifest().kind == ModuleKind::controller);
  auto o = reg.create(omni_config(), three);
  CHECK(o->type_name() == "omni");
  CHECK(o->capabilities().holonomic());
  ControllerConfig m;
  m.type = "mecanum";
  m.holonomic = mecanum_base(0.05, 0.2, 0.15);
  auto mc = reg.create(m, four);
  CHECK(mc->type_name() == "mecanum");
  CHECK(mc->manifest().find_parameter("half_width_m") != nullptr);

  // Every registered type is created by name from a configuration of its own.
  std::map<std::string, std::pair<ControllerConfig, HardwareInterface*>> examples{
      {"differential", {diff_config(), &two}}, {"omni", {omni_config(), &three}}, {"mecanum", {m, &four}}};
  for (const auto& name : reg.names()) {
    INFO(name);
    REQUIRE(examples.count(name) == 1);
    const ModuleManifest& manifest = reg.manifest(name);
    CHECK(manifest.kind == ModuleKind::controller);
    CHECK(manifest.layer == Layer::reactive);
    CHECK(manifest.find_parameter("period_s") != nullptr);
    REQUIRE(manifest.find_parameter("limits.wz.max_velocity") != nullptr);
    CHECK(manifest.find_parameter("limits.wz.max_velocity")->unit == "rad/s");
    CHECK(manifest.find_parameter("limits.vx.max_jerk")->unit == "m/s^3");
    CHECK(manifest.find_parameter("limits.vx.max_jerk")->optional);
    CHECK(manifest.find_parameter("wheel_radius_m") != nullptr);
    for (const auto& p : manifest.parameters) {
      INFO(p.name);
      CHECK_FALSE(p.description.empty());
    }
    auto [config, hardware] = examples.at(name);
    auto made = reg.create(name, config, *hardware);
    CHECK(made->type_name() == name);
    CHECK(made->update(Time{10ms}) == ControlStatus::ok);
  }

  ControllerConfig bad = diff_config();
  bad.type = "tank";
  bad.where = {"robot.yaml", 7, 5};
  REQUIRE_THROWS_WITH(reg.create(bad, two),
                      Catch::Contains("robot.yaml:7:5: error: unknown controller type 'tank'; known: differential, mecanum, omni") &&
                          !Catch::Contains("did you mean"));
  bad.type = "Omni";
  REQUIRE_THROWS_WITH(reg.create(bad, two), Catch::Contains("unknown controller type 'Omni'; known: differential, mecanum, "
                                                            "omni; did you mean 'omni'?"));
}

TEST_CASE("Invalid controller configurations are rejected with every problem") {
  IdealWheelHardware two(2, 10ms), three(3, 10ms);
  ControllerConfig c = diff_config();
  c.where = {"base.yaml", 3, 3};
  c.differential.wheel_radius_m = -0.1;
  c.differential.wheel_separation_m = 0.0;
  c.limits.vx.max_acceleration = -1.0;
  REQUIRE_THROWS_WITH(DifferentialDriveController(c, two),
                      Catch::Contains("base.yaml:3:3: error: wheel_radius_m must be > 0, got -0.1") &&
                          Catch::Contains("wheel_separation_m must be > 0, got 0") &&
                          Catch::Contains("limits.vx.max_acceleration must be a positive number, got -1"));
  REQUIRE_THROWS_WITH(DifferentialDriveController(diff_config(), three), Catch::Contains("needs a hardware interface with 2 wheels, got 3"));

  ControllerConfig o = omni_config();
  o.holonomic.wheels.pop_back();
  IdealWheelHardware w2(2, 10ms);
  REQUIRE_THROWS_WITH(HolonomicController(o, w2), Catch::Contains("an omni base needs 3 to 8 wheels, got 2"));
  // Three wheels all driving along x cannot move sideways: rank 2.
  ControllerConfig p = omni_config();
  p.holonomic.wheels = {{0.2, 0.0, 0.0, 0.0}, {-0.1, 0.17, 0.0, 0.0}, {-0.1, -0.17, 0.0, 0.0}};
  REQUIRE_THROWS_WITH(HolonomicController(p, three), Catch::Contains("Jacobian rank 2 < 3"));
  REQUIRE_THROWS_WITH(HolonomicController(omni_config(), two), Catch::Contains("the hardware interface has 2 wheels, the configuration 3"));
}
