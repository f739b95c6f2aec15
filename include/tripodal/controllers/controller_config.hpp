// Typed configuration of the base controllers and the registry that creates a controller by its
// type name ("differential", "omni", "mecanum", or an application's) from that configuration.
// Each type's manifest declares its parameters; the YAML loader (reactive_config.hpp) checks a
// configuration against them and produces these structs; nothing past it sees YAML.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/controllers/controller.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/registry.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal {

/// Two driven wheels on one axle (Jinny, the disinfection robot).
struct DifferentialDriveConfig {
  double wheel_separation_m = 0.0;  ///< distance between the wheels' contact points, > 0
  double wheel_radius_m = 0.0;      ///< > 0
};

/// One wheel of a holonomic base, in the body frame. The wheel rolls along drive_angle_rad; its
/// rollers are at roller_angle_rad to the drive direction (0 for omni wheels, +-pi/4 for mecanum).
struct OmniWheelConfig {
  double x_m = 0.0;
  double y_m = 0.0;
  double drive_angle_rad = 0.0;
  double roller_angle_rad = 0.0;
};

/// A holonomic base: three or more omni wheels (the PSR bases) or four mecanum wheels.
struct HolonomicConfig {
  double wheel_radius_m = 0.0;  ///< > 0
  std::vector<OmniWheelConfig> wheels;  ///< at least 3, at most kMaxWheels
  static constexpr std::size_t kMaxWheels = 8;
};

/// Omni wheels on a circle of radius `base_radius_m` at the given angles, each driving
/// tangentially (counter-clockwise): the usual three- or four-wheel omni base.
[[nodiscard]] HolonomicConfig omni_base(double wheel_radius_m, double base_radius_m,
                                        std::span<const double> wheel_angles_rad);
/// Four mecanum wheels (front-left, front-right, rear-left, rear-right) at (+-half_length,
/// +-half_width), rollers at 45 degrees in the usual X arrangement.
[[nodiscard]] HolonomicConfig mecanum_base(double wheel_radius_m, double half_length_m,
                                           double half_width_m);

/// Everything a controller needs, whatever its type.
struct ControllerConfig {
  std::string name = "base";       ///< instance name
  std::string type;                ///< registered type: "differential", "omni", "mecanum", or an application's
  Duration period{std::chrono::milliseconds(10)};  ///< nominal sampling period, > 0
  Duration cmd_timeout{0};         ///< 0 disables; on expiry brake to zero through the limits
  BodyLimits limits;
  std::optional<double> max_wheel_speed_rad_s;  ///< wheel saturation, scaled keeping curvature
  DifferentialDriveConfig differential;         ///< type "differential"
  HolonomicConfig holonomic;                    ///< types "omni" and "mecanum"
  /// The configured parameters, resolved against the type's manifest (defaults filled in): an
  /// application's controller type reads its own here (parameters.number("gain")). Loaders fill
  /// it and then the typed fields above with apply_parameters(); empty when built in code.
  ParameterSet parameters;
  SourceLocation where;                         ///< of the controller's entry, for messages
};

/// Checks a configuration; every problem is reported at `config.where`.
[[nodiscard]] Diagnostics validate(const ControllerConfig& config);

/// The manifest of a controller type: reactive layer, kind controller, "cmd_vel" in, "odometry"
/// and "wheel_commands" out; its parameters are `specific` followed by those every controller
/// takes (period_s, cmd_timeout_s, max_wheel_speed_rad_s, limits.<vx|vy|wz>.<max_velocity|
/// max_acceleration|max_deceleration|max_jerk>). A dotted name is a key of nested maps in YAML.
[[nodiscard]] ModuleManifest controller_manifest(std::string name, std::string description,
                                                 std::vector<ParameterSpec> specific);

/// Sets the typed fields of `config` from config.parameters: the common ones, and the geometry
/// of the built-in types (differential wheels, mecanum half length and width, omni wheel radius).
/// Parameters that are not set leave their field as it is.
void apply_parameters(ControllerConfig& config);

/// Controller types by name; each is created from its configuration on a hardware interface
/// (which must outlive it). register_builtin_controllers() adds the built-in types.
class ControllerRegistry : public Registry<CController, const ControllerConfig&, HardwareInterface&> {
 public:
  ControllerRegistry() : Registry("controller type") {}
  using Registry::create;
  /// Creates a controller of config.type. Throws ConfigError located at config.where for an
  /// unknown type, an invalid configuration, or a hardware interface whose wheel count differs
  /// from the configuration's.
  [[nodiscard]] std::unique_ptr<CController> create(const ControllerConfig& config, HardwareInterface& hardware) const {
    return create_at(config.where, config.type, config, hardware);
  }
};

/// The controllers area's types: adds "differential", "omni" and "mecanum" to `registry`. An
/// application's plugin set gets them from register_all (builtin/register_all.hpp).
void register_builtin_controllers(ControllerRegistry& registry);

}  // namespace tripodal
