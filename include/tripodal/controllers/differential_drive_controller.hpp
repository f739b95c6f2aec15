// The differential-drive base controller (Jinny, the disinfection robot): two wheels [left,
// right] on one axle. Registered as "differential".
#pragma once

#include <array>

#include "tripodal/controllers/controller.hpp"
#include "tripodal/controllers/controller_config.hpp"

namespace tripodal {

/// Per period: the command's vy is dropped (the base cannot move sideways), the body limits are
/// applied with the measured period, the wheel speeds are computed and, when one exceeds
/// max_wheel_speed_rad_s, the whole twist is scaled down by one factor, which keeps the
/// commanded curvature (vx / wz). Odometry integrates the measured wheel position increments
/// along exact arcs. No allocation after construction.
class DifferentialDriveController final : public CController {
 public:
  /// Throws ConfigError (at config.where) when the configuration is invalid or `hardware` does
  /// not have two wheels.
  DifferentialDriveController(const ControllerConfig& config, HardwareInterface& hardware);

  static const ModuleManifest& static_manifest();
  [[nodiscard]] const ControllerConfig& config() const noexcept { return config_; }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  BaseCapabilities do_capabilities() const noexcept override;
  std::span<const double> do_wheel_commands() const noexcept override { return wheel_cmd_; }
  ControlStatus on_update(Time now, Duration period, const Twist2D& command, bool timed_out,
                          Twist2D& limited, OdometryReading& odometry) noexcept override;
  [[nodiscard]] Duration command_timeout() const noexcept override { return config_.cmd_timeout; }
  void on_reset_odometry() noexcept override { has_positions_ = false; }

 private:
  ControllerConfig config_;
  HardwareInterface& hardware_;
  TwistLimiter limiter_;
  std::array<double, 2> wheel_cmd_{};
  std::array<double, 2> wheel_vel_{};
  std::array<double, 2> wheel_pos_{};
  std::array<double, 2> last_pos_{};
  bool has_positions_ = false;
};

}  // namespace tripodal
