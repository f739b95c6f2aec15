// Typed configuration of the base controllers and the registry that creates a controller by its
// type name ("differential", "omni", "mecanum") from that configuration. The YAML loader
// (reactive_config.hpp) produces these structs; nothing past it sees YAML.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/controllers/controller.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
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
  std::string type;                ///< registered type: "differential", "omni", "mecanum"
  Duration period{std::chrono::milliseconds(10)};  ///< nominal sampling period, > 0
  Duration cmd_timeout{0};         ///< 0 disables; on expiry brake to zero through the limits
  BodyLimits limits;
  std::optional<double> max_wheel_speed_rad_s;  ///< wheel saturation, scaled keeping curvature
  DifferentialDriveConfig differential;         ///< type "differential"
  HolonomicConfig holonomic;                    ///< types "omni" and "mecanum"
  SourceLocation where;                         ///< of the controller's entry, for messages
};

/// Checks a configuration; every problem is reported at `config.where`.
[[nodiscard]] Diagnostics validate(const ControllerConfig& config);

/// Creates controllers by type name. The built-in types are registered by
/// default_controller_registry().
class ControllerRegistry {
 public:
  using Factory =
      std::function<std::unique_ptr<CController>(const ControllerConfig&, HardwareInterface&)>;
  /// Throws std::invalid_argument for an empty or duplicate name.
  void add(const ModuleManifest& manifest, Factory factory);
  [[nodiscard]] bool contains(std::string_view type) const noexcept;
  [[nodiscard]] const ModuleManifest* manifest(std::string_view type) const noexcept;
  [[nodiscard]] std::vector<std::string> names() const;
  /// Creates a controller of config.type driving `hardware` (which must outlive it). Throws
  /// ConfigError located at config.where for an unknown type, an invalid configuration, or a
  /// hardware interface whose wheel count differs from the configuration's.
  [[nodiscard]] std::unique_ptr<CController> create(const ControllerConfig& config,
                                                    HardwareInterface& hardware) const;

 private:
  struct Entry {
    const ModuleManifest* manifest;
    Factory factory;
  };
  std::map<std::string, Entry, std::less<>> entries_;
};

/// Adds "differential", "omni" and "mecanum" to `registry`.
void register_builtin_controllers(ControllerRegistry& registry);
/// A process-wide registry holding the built-in controllers, created on first use.
[[nodiscard]] ControllerRegistry& default_controller_registry();

}  // namespace tripodal
