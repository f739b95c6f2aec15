// Test rig: a control loop with resources, the eight-behavior set of the reactive benchmarks and a
// controller on ideal wheels, for the loop and allocation tests.
#pragma once

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include "../support/builtin_registries.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/reactive/control_loop.hpp"

namespace tripodal::test {

inline ControllerConfig differential_base() {
  ControllerConfig c;
  c.name = "jinny";
  c.type = "differential";
  c.period = std::chrono::milliseconds(10);
  c.cmd_timeout = std::chrono::milliseconds(200);
  c.differential = {0.42, 0.09};
  c.max_wheel_speed_rad_s = 12.0;
  c.limits.vx = {0.8, 1.0, 2.0, std::nullopt};
  c.limits.wz = {2.0, 4.0, 6.0, std::nullopt};
  return c;
}

inline ControllerConfig omni_base_psr() {
  ControllerConfig c;
  c.name = "psr2";
  c.type = "omni";
  c.period = std::chrono::milliseconds(10);
  c.cmd_timeout = std::chrono::milliseconds(200);
  constexpr double kPi = std::numbers::pi;
  const double angles[] = {kPi / 3, kPi, 5 * kPi / 3};
  c.holonomic = omni_base(0.05, 0.22, angles);
  c.max_wheel_speed_rad_s = 16.0;
  c.limits.vx = {0.8, 1.0, 2.0, std::nullopt};
  c.limits.vy = {0.8, 1.0, 2.0, std::nullopt};
  c.limits.wz = {2.0, 4.0, 6.0, std::nullopt};
  return c;
}

/// The coordinator inputs of the eight-behavior set.
inline CoordinatorConfig eight_inputs(CoordinationMode mode) {
  using namespace std::chrono_literals;
  CoordinatorConfig c;
  c.mode = mode;
  c.inputs = {{"avoid_front", 1000, 200ms, 1.0, InputRole::safety},
              {"avoid_back", 1000, 200ms, 1.0, InputRole::safety},
              {"back_off", 50, 200ms, 2.0},
              {"goto_a", 20, 200ms, 1.0},
              {"goto_b", 20, 200ms, 0.5},
              {"rotate_a", 10, 200ms, 0.5},
              {"rotate_b", 10, 200ms, 0.5},
              {"stop", 0, 0ms, 0.1}};
  c.locks = {{"pause", 500, 0ms}};
  return c;
}

struct ReactiveRig {
  SimClock clock;
  OdometryResource odom{"odom", std::chrono::milliseconds(100)};
  LaserResource laser{"laser", std::chrono::milliseconds(200)};
  ResourceTable resources;
  LaserScan scan;
  std::unique_ptr<IdealWheelHardware> hardware;
  std::unique_ptr<ControlLoop> loop;

  ReactiveRig(const ControllerConfig& base, CoordinationMode mode, std::size_t beams = 360) {
    resources.add(odom);
    resources.add(laser);
    hardware = std::make_unique<IdealWheelHardware>(base.type == "differential" ? 2 : base.holonomic.wheels.size(), base.period);
    ControlLoopOptions o;
    o.name = "motion";
    o.period = base.period;
    loop = std::make_unique<ControlLoop>(o, resources, CBehaviorCoordinator(eight_inputs(mode)),
                                         test::builtin_controllers().create(base, *hardware));
    loop->set_odometry_output(&odom);
    constexpr double kPi = std::numbers::pi;
    scan.angle_min_rad = -kPi;
    scan.angle_increment_rad = 2 * kPi / static_cast<double>(beams);
    scan.angle_max_rad = scan.angle_min_rad + static_cast<double>(beams - 1) * scan.angle_increment_rad;
    scan.range_min_m = 0.05;
    scan.range_max_m = 20.0;
    scan.scan_time_s = 0.1;
    scan.ranges_m.resize(beams);
    for (std::size_t i = 0; i < beams; ++i) {
      // Obstacles between 0.5 and 3 m all around: every beam is examined, some limit the speed.
      scan.ranges_m[i] = static_cast<float>(0.5 + 2.5 * std::abs(std::sin(static_cast<double>(i) * 0.05)));
    }
    scan.ranges_m[0] = 0.3f;  // right behind, inside the stop distance: backing up is blocked
  }

  /// Activates the eight behaviors (2 go-to-pose, 2 rotate, back-off, stop, 2 obstacle guards).
  void activate_eight() {
    const BehaviorRegistry& reg = test::builtin_behaviors();
    auto act = [&](const char* type, const char* input, ParameterValues params) {
      loop->activate(reg.create(type), params, input);
    };
    // Goals far away and turns of many revolutions keep every behavior running for long runs.
    act("BhAvoidObstacle", "avoid_front", {});
    act("BhAvoidObstacle", "avoid_back", {{"laser_yaw_rad", Value{3.14159}}});
    act("BhBackOff", "back_off", {{"distance_m", Value{9.0}}, {"speed_m_s", Value{0.05}}});
    act("BhGoToPose", "goto_a", {{"goal_x_m", Value{1000.0}}, {"goal_y_m", Value{5.0}}});
    act("BhGoToPose", "goto_b", {{"goal_x_m", Value{-500.0}}, {"goal_y_m", Value{300.0}}});
    act("BhRotateInPlace", "rotate_a", {{"angle_rad", Value{90.0}}});
    act("BhRotateInPlace", "rotate_b", {{"angle_rad", Value{-90.0}}});
    act("BhStop", "stop", {});
  }

  /// One cycle at the clock's time, with a freshly published scan; then time moves one period.
  const CycleReport& cycle() {
    const Time now = clock.now();
    scan.stamp = now;
    laser.publish(scan);
    const CycleReport& r = loop->step(now);
    clock.advance(loop->period());
    return r;
  }
};

}  // namespace tripodal::test
