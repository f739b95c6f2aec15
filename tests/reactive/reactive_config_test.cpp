// YAML configuration of controllers and loops: typed structs, and located errors.
#include "tripodal/reactive/reactive_config.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "../support/control_loops.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"

using namespace tripodal;
using namespace std::chrono_literals;
using tripodal::test::make_control_loop;

namespace {
// The built-in controller types, as an application's plugin set has them.
const ControllerRegistry& builtins() {
  static const ControllerRegistry registry = [] {
    ControllerRegistry r;
    register_builtin_controllers(r);
    return r;
  }();
  return registry;
}
}  // namespace

TEST_CASE("The shipped configurations load into typed structs") {
  const ReactiveConfig jinny =
      load_reactive_config(std::string(TRIPODAL_SOURCE_DIR) + "/configs/reactive/jinny_differential.yaml", builtins());
  REQUIRE(jinny.controllers.size() == 1);
  const ControllerConfig& base = jinny.controllers[0];
  CHECK(base.type == "differential");
  CHECK(base.period == 10ms);
  CHECK(base.cmd_timeout == 250ms);
  CHECK(base.differential.wheel_separation_m == 0.42);
  CHECK(base.differential.wheel_radius_m == 0.09);
  CHECK(base.max_wheel_speed_rad_s == 12.0);
  CHECK(base.limits.vx.max_jerk == 8.0);
  CHECK_FALSE(base.limits.wz.max_deceleration.has_value());
  CHECK_FALSE(base.limits.vy.max_velocity.has_value());
  CHECK(base.where.line == 3);
  REQUIRE(jinny.loops.size() == 1);
  const LoopConfig& loop = jinny.loops[0];
  CHECK(loop.controller == "base");
  CHECK(loop.coordinator.mode == CoordinationMode::priority);
  REQUIRE(loop.coordinator.inputs.size() == 5);
  CHECK(loop.coordinator.inputs[0].role == InputRole::safety);
  CHECK(loop.coordinator.inputs[0].timeout == 200ms);
  CHECK(loop.coordinator.inputs[4].timeout == 0ms);
  REQUIRE(loop.coordinator.locks.size() == 2);
  CHECK(loop.coordinator.locks[1].timeout == 500ms);

  IdealWheelHardware hw(2, 10ms);
  ResourceTable resources;
  auto built = make_control_loop(jinny, loop, resources, &hw, builtins());
  CHECK(built->controller()->type_name() == "differential");
  CHECK(built->coordinator().input_count() == 5);
  CHECK(built->period() == 10ms);

  const ReactiveConfig psr =
      load_reactive_config(std::string(TRIPODAL_SOURCE_DIR) + "/configs/reactive/psr_omni.yaml", builtins());
  REQUIRE(psr.controllers[0].holonomic.wheels.size() == 3);
  CHECK(psr.controllers[0].holonomic.wheels[1].x_m == Approx(-0.22));
  CHECK(psr.loops.size() == 2);
  CHECK(psr.loops[0].coordinator.mode == CoordinationMode::weighted_sum);
  CHECK(psr.loops[1].controller.empty());
  CHECK(psr.loops[1].period == 50ms);
  IdealWheelHardware hw3(3, 10ms);
  CHECK(make_control_loop(psr, psr.loops[0], resources, &hw3, builtins())->controller()->type_name() == "omni");
  CHECK(make_control_loop(psr, psr.loops[1], resources, nullptr, builtins())->controller() == nullptr);
}

TEST_CASE("Omni wheels given one by one, and mecanum bases") {
  const ReactiveConfig c = parse_reactive_config(R"(
controllers:
  - name: custom
    type: omni
    wheel_radius_m: 0.04
    wheels:
      - {x_m: 0.2, y_m: 0.0, drive_angle_deg: 90}
      - {x_m: -0.1, y_m: 0.17, drive_angle_deg: 210}
      - {x_m: -0.1, y_m: -0.17, drive_angle_deg: 330, roller_angle_deg: 0}
      - {x_m: 0.0, y_m: 0.0, drive_angle_deg: 0}
  - name: mec
    type: mecanum
    wheel_radius_m: 0.05
    half_length_m: 0.2
    half_width_m: 0.15
)",
                                                 "inline.yaml", builtins());
  REQUIRE(c.controllers.size() == 2);
  CHECK(c.controllers[0].holonomic.wheels.size() == 4);
  CHECK(c.controllers[0].holonomic.wheels[1].drive_angle_rad == Approx(210 * std::numbers::pi / 180));
  CHECK(c.controllers[1].holonomic.wheels.size() == 4);
  CHECK(c.controllers[1].holonomic.wheels[0].roller_angle_rad == Approx(-std::numbers::pi / 4));
}

TEST_CASE("A negative radius is reported at its value") {
  REQUIRE_THROWS_WITH(
      parse_reactive_config(R"(controllers:
  - name: base
    type: differential
    wheel_separation_m: 0.4
    wheel_radius_m: -0.05
)",
                            "robot.yaml", builtins()),
      Catch::Contains("robot.yaml:5:21: error: controller 'base': parameter 'wheel_radius_m' = -0.05 m is outside (0, inf]"));
}

TEST_CASE("A missing wheel is reported") {
  REQUIRE_THROWS_WITH(parse_reactive_config(R"(controllers:
  - name: psr
    type: omni
    wheel_radius_m: 0.05
    base_radius_m: 0.2
    wheel_angles_deg: [90, 210]
)",
                                            "psr.yaml", builtins()),
                      Catch::Contains("psr.yaml:6:23: error: controller 'psr': an omni base needs 3 to 8 wheels, got 2"));
  REQUIRE_THROWS_WITH(parse_reactive_config(R"(controllers:
  - name: psr
    type: omni
    wheel_radius_m: 0.05
)",
                                            "psr.yaml", builtins()),
                      Catch::Contains("psr.yaml:2:5: error: controller 'psr': missing wheel geometry"));
  REQUIRE_THROWS_WITH(parse_reactive_config(R"(controllers:
  - name: psr
    type: omni
    wheel_radius_m: 0.05
    wheels:
      - {x_m: 0.2, drive_angle_deg: 90}
)",
                                            "psr.yaml", builtins()),
                      Catch::Contains("psr.yaml:6:9: error: controller 'psr' wheel #1: missing 'y_m' (a number)") &&
                          Catch::Contains("psr.yaml:6:7: error: controller 'psr': an omni base needs 3 to 8 wheels, got 1"));
  REQUIRE_THROWS_WITH(parse_reactive_config(R"(controllers:
  - name: jinny
    type: differential
    wheel_radius_m: 0.05
)",
                                            "jinny.yaml", builtins()),
                      Catch::Contains("jinny.yaml:2:5: error: controller 'jinny': missing 'wheel_separation_m' (a number)"));
}

TEST_CASE("An unknown controller type is reported at the type, with the known ones") {
  REQUIRE_THROWS_WITH(
      parse_reactive_config(R"(controllers:
  - name: base
    type: tracked
loops:
  - name: motion
    period_s: 0.01
    controller: basis
)",
                            "robot.yaml", builtins()),
      Catch::Contains(
          "robot.yaml:3:11: error: controller 'base': unknown controller type 'tracked'; known: differential, mecanum, omni") &&
          Catch::Contains("robot.yaml:7:17: error: loop 'motion': unknown controller 'basis'"));
}

TEST_CASE("Every problem of a file is reported in one pass") {
  try {
    (void)parse_reactive_config(R"(controllers:
  - name: base
    type: differential
    wheel_separation_m: zero
    wheel_radius_m: 0.1
    cmd_timeout_s: -1
    wheel_radus_m: 0.1
    limits:
      vx: {max_velocity: 0.5, max_acceleration: -2}
      yaw: {max_velocity: 1}
loops:
  - name: motion
    period_s: 0
    realtime_priority: 120
    coordinator:
      mode: fastest
      inputs:
        - {name: a, role: boss}
        - {name: a, priority: 1.5}
)",
                                "many.yaml", builtins());
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    INFO(what);
    CHECK(e.diagnostics().error_count() == 11);
    CHECK_THAT(what, Catch::Contains("many.yaml:4:25: error: controller 'base': parameter 'wheel_separation_m' expects a number, got \"zero\""));
    CHECK_THAT(what, Catch::Contains("many.yaml:6:20: error: controller 'base': parameter 'cmd_timeout_s' = -1 s is outside [0, inf]"));
    CHECK_THAT(what, Catch::Contains("many.yaml:7:5: error: unknown key 'wheel_radus_m' in controller 'base'; expected one of: name, type, "
                                     "wheel_separation_m, wheel_radius_m, period_s, cmd_timeout_s, max_wheel_speed_rad_s, limits; "
                                     "did you mean 'wheel_radius_m'?"));
    CHECK_THAT(what, Catch::Contains("many.yaml:9:49: error: controller 'base': parameter 'limits.vx.max_acceleration' = -2 m/s^2 is outside (0, inf]"));
    CHECK_THAT(what, Catch::Contains("many.yaml:10:7: error: unknown key 'yaw' in controller 'base' limits; expected one of: vx, vy, wz"));
    CHECK_THAT(what, Catch::Contains("many.yaml:13:15: error: loop 'motion': 'period_s' must be > 0, got 0"));
    CHECK_THAT(what, Catch::Contains("many.yaml:14:24: error: loop 'motion': 'realtime_priority' must be an integer in [0, 99], got 120"));
    CHECK_THAT(what, Catch::Contains("many.yaml:16:13: error: loop 'motion' coordinator: unknown mode 'fastest'"));
    CHECK_THAT(what, Catch::Contains("unknown role 'boss' (expected normal or safety)"));
    CHECK_THAT(what, Catch::Contains("many.yaml:19:18: error: loop 'motion' coordinator input #2: duplicate input 'a'"));
    CHECK_THAT(what, Catch::Contains("many.yaml:19:31: error: loop 'motion' coordinator input #2: 'priority' must be an integer"));
  }
}

TEST_CASE("Syntax errors and unreadable files are located too") {
  REQUIRE_THROWS_WITH(parse_reactive_config("controllers: [\n  {name: a\n", "broken.yaml", builtins()),
                      Catch::Contains("broken.yaml:") && Catch::Contains("YAML syntax error"));
  REQUIRE_THROWS_WITH(parse_reactive_config("- 1\n- 2\n", "list.yaml", builtins()),
                      Catch::Contains("list.yaml:1:1: error: expected a map with 'controllers' and 'loops'"));
  REQUIRE_THROWS_WITH(load_reactive_config("/nonexistent/reactive.yaml", builtins()),
                      Catch::Contains("/nonexistent/reactive.yaml: error: cannot read the file"));
}

namespace {

// An application's controller type with a parameter of its own: one wheel driven at gain * vx.
class GainController final : public CController {
 public:
  GainController(const ControllerConfig& config, HardwareInterface& hardware)
      : CController(config.period), hardware_(hardware), gain_(config.parameters.number("gain")) {}

  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m =
        controller_manifest("gain", "one wheel at gain times the forward speed",
                            {parameter::number("gain", 1.0, "rad/m", "wheel speed per forward speed", 0.0, 100.0)});
    return m;
  }
  [[nodiscard]] double gain() const noexcept { return gain_; }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  BaseCapabilities do_capabilities() const noexcept override { return {}; }
  std::span<const double> do_wheel_commands() const noexcept override { return {&wheel_, 1}; }
  ControlStatus on_update(Time, Duration, const Twist2D& command, bool, Twist2D& limited, OdometryReading&) noexcept override {
    wheel_ = gain_ * command.vx_m_s;
    limited = command;
    return hardware_.write_wheel_velocities({&wheel_, 1}) ? ControlStatus::ok : ControlStatus::hardware_fault;
  }
  [[nodiscard]] Duration command_timeout() const noexcept override { return Duration{0}; }

 private:
  HardwareInterface& hardware_;
  double gain_;
  double wheel_ = 0.0;
};

ControllerRegistry registry_with_gain() {
  ControllerRegistry r;
  register_builtin_controllers(r);
  r.add<GainController>();
  return r;
}

}  // namespace

TEST_CASE("An application's controller type takes its own parameters through its manifest") {
  const ControllerRegistry registry = registry_with_gain();
  const ReactiveConfig c = parse_reactive_config(R"(controllers:
  - name: winch
    type: gain
    gain: 2.5
    period_s: 0.02
    limits:
      vx: {max_velocity: 0.3}
  - name: winch_default
    type: gain
loops:
  - name: motion
    period_s: 0.02
    controller: winch
)", "winch.yaml", registry);
  REQUIRE(c.controllers.size() == 2);
  CHECK(c.controllers[0].parameters.number("gain") == 2.5);
  CHECK(c.controllers[0].period == 20ms);
  CHECK(c.controllers[0].limits.vx.max_velocity == 0.3);
  CHECK(c.controllers[1].parameters.number("gain") == 1.0);  // the manifest's default
  CHECK_FALSE(c.controllers[1].parameters.contains("max_wheel_speed_rad_s"));

  IdealWheelHardware one(1, 20ms);
  ResourceTable resources;
  auto loop = make_control_loop(c, c.loops[0], resources, &one, registry);
  REQUIRE(loop->controller() != nullptr);
  CHECK(loop->controller()->type_name() == "gain");
  CHECK(dynamic_cast<const GainController&>(*loop->controller()).gain() == 2.5);

  // Its keys are checked against its manifest, and so are its values.
  REQUIRE_THROWS_WITH(parse_reactive_config(R"(controllers:
  - name: winch
    type: gain
    gian: 3
    wheel_radius_m: 0.1
)", "winch.yaml", registry),
                      Catch::Contains("winch.yaml:4:5: error: unknown key 'gian' in controller 'winch'; expected one of: "
                                      "name, type, gain, period_s, cmd_timeout_s, max_wheel_speed_rad_s, limits; did you "
                                      "mean 'gain'?") &&
                          Catch::Contains("winch.yaml:5:5: error: unknown key 'wheel_radius_m' in controller 'winch'"));
  REQUIRE_THROWS_WITH(parse_reactive_config("controllers:\n  - {name: winch, type: gain, gain: 300}\n", "winch.yaml", registry),
                      Catch::Contains("winch.yaml:2:37: error: controller 'winch': parameter 'gain' = 300 rad/m is outside [0, 100]"));
  REQUIRE_THROWS_WITH(parse_reactive_config("controllers:\n  - {name: winch, type: gian}\n", "winch.yaml", registry),
                      Catch::Contains("winch.yaml:2:25: error: controller 'winch': unknown controller type 'gian'; known: "
                                      "differential, gain, mecanum, omni; did you mean 'gain'?"));
  REQUIRE_THROWS_WITH(parse_reactive_config("controllers:\n  - {name: winch, type: gain, limits: {vx: 5, yaw: {}}}\n",
                                            "winch.yaml", registry),
                      Catch::Contains("winch.yaml:2:44: error: controller 'winch' limits.vx: expected a map, got '5'") &&
                          Catch::Contains("unknown key 'yaw' in controller 'winch' limits; expected one of: vx, vy, wz"));
  // A plugin set without it does not know it.
  REQUIRE_THROWS_WITH(parse_reactive_config("controllers:\n  - {name: winch, type: gain}\n", "winch.yaml", builtins()),
                      Catch::Contains("unknown controller type 'gain'; known: differential, mecanum, omni"));
}

TEST_CASE("A loop period too short for the clock is refused at the file, with the range", "[errors]") {
  // 1e-12 s rounds to 0 ns: the control loop refused it as it was built, unlocated.
  REQUIRE_THROWS_WITH(
      parse_reactive_config(R"(loops:
  - name: motion
    period_s: 1e-12
  - name: slow
    period_s: 1e10
)",
                            "tiny.yaml", builtins()),
      Catch::Contains("tiny.yaml:3:15: error: loop 'motion': 'period_s': expected seconds from 1e-06 to 9e+09, got 1e-12") &&
          Catch::Contains("tiny.yaml:5:15: error: loop 'slow': 'period_s': expected seconds from 1e-06 to 9e+09, got 1e10"));
}
