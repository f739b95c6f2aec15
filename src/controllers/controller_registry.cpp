#include <cmath>
#include <numbers>
#include <stdexcept>

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
  constexpr double q = std::numbers::pi / 4.0;
  HolonomicConfig c;
  c.wheel_radius_m = wheel_radius_m;
  // X arrangement: front-left and rear-right rollers at -45 degrees, the others at +45.
  c.wheels = {{half_length_m, half_width_m, 0.0, -q},
              {half_length_m, -half_width_m, 0.0, q},
              {-half_length_m, half_width_m, 0.0, q},
              {-half_length_m, -half_width_m, 0.0, -q}};
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

void ControllerRegistry::add(const ModuleManifest& manifest, Factory factory) {
  if (manifest.name.empty()) throw std::invalid_argument("a controller type needs a name");
  if (!entries_.emplace(manifest.name, Entry{&manifest, std::move(factory)}).second) {
    throw std::invalid_argument("controller type '" + manifest.name + "' is already registered");
  }
}

bool ControllerRegistry::contains(std::string_view type) const noexcept { return entries_.find(type) != entries_.end(); }

const ModuleManifest* ControllerRegistry::manifest(std::string_view type) const noexcept {
  auto it = entries_.find(type);
  return it == entries_.end() ? nullptr : it->second.manifest;
}

std::vector<std::string> ControllerRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [n, e] : entries_) out.push_back(n);
  return out;
}

std::unique_ptr<CController> ControllerRegistry::create(const ControllerConfig& config, HardwareInterface& hardware) const {
  auto it = entries_.find(config.type);
  if (it == entries_.end()) {
    std::string known;
    for (const auto& [n, e] : entries_) known += (known.empty() ? "" : ", ") + n;
    throw ConfigError(config.where, "unknown controller type '" + config.type + "' (expected one of: " + known + ")");
  }
  return it->second.factory(config, hardware);
}

void register_builtin_controllers(ControllerRegistry& registry) {
  registry.add(DifferentialDriveController::static_manifest(), [](const ControllerConfig& c, HardwareInterface& h) {
    return std::unique_ptr<CController>(std::make_unique<DifferentialDriveController>(c, h));
  });
  auto holonomic = [](const ControllerConfig& c, HardwareInterface& h) {
    return std::unique_ptr<CController>(std::make_unique<HolonomicController>(c, h));
  };
  registry.add(HolonomicController::omni_manifest(), holonomic);
  registry.add(HolonomicController::mecanum_manifest(), holonomic);
}

ControllerRegistry& default_controller_registry() {
  static ControllerRegistry registry = [] {
    ControllerRegistry r;
    register_builtin_controllers(r);
    return r;
  }();
  return registry;
}

}  // namespace tripodal
