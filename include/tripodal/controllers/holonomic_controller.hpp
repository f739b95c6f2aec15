// The holonomic base controller: three or more omni wheels at given angles (the PSR bases,
// registered as "omni") or four mecanum wheels ("mecanum"). Inverse kinematics by the wheel
// Jacobian, forward kinematics by its pseudo-inverse computed once at configuration.
#pragma once

#include <Eigen/Core>

#include "tripodal/controllers/controller.hpp"
#include "tripodal/controllers/controller_config.hpp"

namespace tripodal {

/// Per period: body limits with the measured period, wheel speeds = J * twist, and when a wheel
/// exceeds max_wheel_speed_rad_s the twist is scaled by one factor (direction and curvature
/// kept). Odometry: body displacement = pinv(J) * wheel position increments, integrated along
/// the exact arc. Matrices have a fixed maximum size (HolonomicConfig::kMaxWheels): nothing is
/// allocated after construction.
class HolonomicController final : public CController {
 public:
  using Jacobian = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, HolonomicConfig::kMaxWheels, 3>;
  using PseudoInverse = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, HolonomicConfig::kMaxWheels>;
  using WheelVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, HolonomicConfig::kMaxWheels, 1>;

  /// Throws ConfigError (at config.where): invalid configuration, fewer than 3 or more than
  /// kMaxWheels wheels, wheels whose directions do not span the plane (rank < 3), or a hardware
  /// interface with a different wheel count.
  HolonomicController(const ControllerConfig& config, HardwareInterface& hardware);

  static const ModuleManifest& omni_manifest();
  static const ModuleManifest& mecanum_manifest();
  [[nodiscard]] const ControllerConfig& config() const noexcept { return config_; }

  /// Wheel angular velocities (rad/s) of a body twist, and the twist of wheel velocities
  /// (least squares when the wheels disagree). `wheels` must have wheel_count() entries.
  void inverse(const Twist2D& twist, std::span<double> wheels_rad_s) const noexcept;
  [[nodiscard]] Twist2D forward(std::span<const double> wheels_rad_s) const noexcept;
  [[nodiscard]] std::size_t wheel_count() const noexcept { return static_cast<std::size_t>(jacobian_.rows()); }
  [[nodiscard]] const Jacobian& jacobian() const noexcept { return jacobian_; }

 protected:
  const ModuleManifest& do_manifest() const noexcept override;
  BaseCapabilities do_capabilities() const noexcept override;
  std::span<const double> do_wheel_commands() const noexcept override {
    return {wheel_cmd_.data(), static_cast<std::size_t>(wheel_cmd_.size())};
  }
  ControlStatus on_update(Time now, Duration period, const Twist2D& command, bool timed_out,
                          Twist2D& limited, OdometryReading& odometry) noexcept override;
  [[nodiscard]] Duration command_timeout() const noexcept override { return config_.cmd_timeout; }
  void on_reset_odometry() noexcept override { has_positions_ = false; }

 private:
  ControllerConfig config_;
  std::string_view type_;
  HardwareInterface& hardware_;
  TwistLimiter limiter_;
  Jacobian jacobian_;
  PseudoInverse pinv_;
  WheelVector wheel_cmd_, wheel_vel_, wheel_pos_, last_pos_;
  bool has_positions_ = false;
};

}  // namespace tripodal
