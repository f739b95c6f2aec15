#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/controllers/differential_drive_controller.hpp"
#include "tripodal/controllers/holonomic_controller.hpp"

namespace tripodal {

HolonomicConfig omni_base(double wheel_radius_m, double base_radius_m, std::span<const double> wheel_angles_rad) {
  HolonomicConfig c;
  c.wheel_radius_m = wheel_radius_m;
  for (double a : wheel_angles_rad) {
    c.wheels.push_back({base_radius_m * std::cos(a), base_radius_m * std::sin(a), a + std::numbers::pi / 2.0, 0.0});
  }
  return c;
}

HolonomicConfig mecanum_base(double wheel_radius_m, double half_length_m, double half_width_m) {
  constexpr double kQuarterPi = std::numbers::pi / 4.0;
  HolonomicConfig c;
  c.wheel_radius_m = wheel_radius_m;
  // X arrangement: front-left and rear-right rollers at -45 degrees, the others at +45.
  c.wheels = {{half_length_m, half_width_m, 0.0, -kQuarterPi},
              {half_length_m, -half_width_m, 0.0, kQuarterPi},
              {-half_length_m, half_width_m, 0.0, kQuarterPi},
              {-half_length_m, -half_width_m, 0.0, -kQuarterPi}};
  return c;
}

namespace {

void check_axis(Diagnostics& d, const SourceLocation& where, const char* axis, const AxisLimits& a) {
  auto positive = [&](const std::optional<double>& v, const char* what) {
    if (v && !(*v > 0.0 && std::isfinite(*v))) {
      d.error(where, std::string("limits.") + axis + "." + what + " must be a positive number, got " +
                         to_string(Value{*v}));
    }
  };
  positive(a.max_velocity, "max_velocity");
  positive(a.max_acceleration, "max_acceleration");
  positive(a.max_deceleration, "max_deceleration");
  positive(a.max_jerk, "max_jerk");
}

}  // namespace

Diagnostics validate(const ControllerConfig& c) {
  Diagnostics d;
  const auto& w = c.where;
  auto num = [](double v) { return to_string(Value{v}); };
  if (c.period.count() <= 0) d.error(w, "period_s must be > 0");
  if (c.cmd_timeout.count() < 0) d.error(w, "cmd_timeout_s must be >= 0 (0 disables the timeout)");
  check_axis(d, w, "vx", c.limits.vx);
  check_axis(d, w, "vy", c.limits.vy);
  check_axis(d, w, "wz", c.limits.wz);
  if (c.max_wheel_speed_rad_s && !(*c.max_wheel_speed_rad_s > 0.0)) {
    d.error(w, "max_wheel_speed_rad_s must be > 0, got " + num(*c.max_wheel_speed_rad_s));
  }
  if (c.type == "differential") {
    if (!(c.differential.wheel_radius_m > 0.0 && std::isfinite(c.differential.wheel_radius_m))) {
      d.error(w, "wheel_radius_m must be > 0, got " + num(c.differential.wheel_radius_m));
    }
    if (!(c.differential.wheel_separation_m > 0.0 && std::isfinite(c.differential.wheel_separation_m))) {
      d.error(w, "wheel_separation_m must be > 0, got " + num(c.differential.wheel_separation_m));
    }
  } else if (c.type == "omni" || c.type == "mecanum") {
    if (!(c.holonomic.wheel_radius_m > 0.0 && std::isfinite(c.holonomic.wheel_radius_m))) {
      d.error(w, "wheel_radius_m must be > 0, got " + num(c.holonomic.wheel_radius_m));
    }
    const std::size_t n = c.holonomic.wheels.size();
    if (c.type == "mecanum" && n != 4) {
      d.error(w, "a mecanum base needs exactly 4 wheels, got " + std::to_string(n));
    } else if (n < 3 || n > HolonomicConfig::kMaxWheels) {
      d.error(w, "an omni base needs 3 to " + std::to_string(HolonomicConfig::kMaxWheels) + " wheels, got " +
                     std::to_string(n));
    }
  }
  return d;
}

ModuleManifest controller_manifest(std::string name, std::string description, std::vector<ParameterSpec> specific) {
  ManifestBuilder b(std::move(name), ModuleKind::controller, Layer::reactive);
  b.description(std::move(description)).input("cmd_vel").outputs({"odometry", "wheel_commands"});
  b.parameters(std::move(specific));
  b.parameter(parameter::positive("period_s", 0.01, "s", "nominal sampling period"));
  b.number("cmd_timeout_s", 0.0, "s", "brake to zero when no command came for this long; 0 disables", 0.0);
  b.parameter(parameter::optional(
      parameter::positive("max_wheel_speed_rad_s", {}, "rad/s", "wheel saturation (unset: none); scaled keeping curvature")));
  for (const char* axis : {"vx", "vy", "wz"}) {
    const std::string a = std::string("limits.") + axis + ".";
    const bool linear = std::string_view(axis) != "wz";
    auto limit = [&](const char* what, const char* linear_unit, const char* angular_unit, const char* unset) {
      b.parameter(parameter::optional(
          parameter::positive(a + what, {}, linear ? linear_unit : angular_unit, std::string("unset: ") + unset)));
    };
    limit("max_velocity", "m/s", "rad/s", "no limit");
    limit("max_acceleration", "m/s^2", "rad/s^2", "no limit");
    limit("max_deceleration", "m/s^2", "rad/s^2", "max_acceleration");
    limit("max_jerk", "m/s^3", "rad/s^3", "no limit");
  }
  return std::move(b).build();
}

void apply_parameters(ControllerConfig& c) {
  const ParameterSet& p = c.parameters;
  auto set = [&](std::string_view name, auto&& assign) {
    if (p.contains(name)) assign(p.number(name));
  };
  set("period_s", [&](double s) { c.period = from_seconds(s); });
  set("cmd_timeout_s", [&](double s) { c.cmd_timeout = from_seconds(s); });
  set("max_wheel_speed_rad_s", [&](double v) { c.max_wheel_speed_rad_s = v; });
  for (const auto& axis_limits : {std::pair{"vx", &c.limits.vx}, std::pair{"vy", &c.limits.vy}, std::pair{"wz", &c.limits.wz}}) {
    // Not a structured binding: clang 14 (the fuzzing compiler) cannot capture one in a lambda.
    auto* const limits = axis_limits.second;
    const std::string a = std::string("limits.") + axis_limits.first + ".";
    set(a + "max_velocity", [&](double v) { limits->max_velocity = v; });
    set(a + "max_acceleration", [&](double v) { limits->max_acceleration = v; });
    set(a + "max_deceleration", [&](double v) { limits->max_deceleration = v; });
    set(a + "max_jerk", [&](double v) { limits->max_jerk = v; });
  }
  if (c.type == "differential") {
    set("wheel_separation_m", [&](double v) { c.differential.wheel_separation_m = v; });
    set("wheel_radius_m", [&](double v) { c.differential.wheel_radius_m = v; });
  } else if (c.type == "mecanum") {
    if (p.contains("half_length_m") && p.contains("half_width_m")) {
      c.holonomic = mecanum_base(0.0, p.number("half_length_m"), p.number("half_width_m"));
    }
    set("wheel_radius_m", [&](double v) { c.holonomic.wheel_radius_m = v; });
  } else if (c.type == "omni") {
    set("wheel_radius_m", [&](double v) { c.holonomic.wheel_radius_m = v; });
  }
}

void register_builtin_controllers(ControllerRegistry& registry) {
  registry.add<DifferentialDriveController>();
  auto holonomic = [](const ControllerConfig& c, HardwareInterface& h) {
    return std::unique_ptr<CController>(std::make_unique<HolonomicController>(c, h));
  };
  registry.add(HolonomicController::omni_manifest(), holonomic);
  registry.add(HolonomicController::mecanum_manifest(), holonomic);
}

}  // namespace tripodal
