#include "tripodal/controllers/holonomic_controller.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "tripodal/controllers/kinematics.hpp"

namespace tripodal {

namespace {
std::vector<ParameterSpec> holonomic_parameters(bool mecanum) {
  std::vector<ParameterSpec> p = {parameter::positive("wheel_radius_m", {}, "m", "wheel radius")};
  if (mecanum) {
    p.push_back(parameter::positive("half_length_m", {}, "m", "half the distance between front and rear axles"));
    p.push_back(parameter::positive("half_width_m", {}, "m", "half the track width"));
  } else {
    // The wheel lists are read by the YAML loader's omni geometry code: a parameter is a scalar.
    p.push_back(parameter::optional(
        parameter::positive("base_radius_m", {}, "m", "distance of the wheels from the centre (with wheel_angles_deg)")));
    p.push_back(parameter::optional(
        parameter::text("wheel_angles_deg", {}, "list of wheel angles in degrees (3 to 8), with base_radius_m")));
    p.push_back(parameter::optional(
        parameter::text("wheels", {}, "list of {x_m, y_m, drive_angle_deg, roller_angle_deg}, instead of wheel_angles_deg")));
  }
  return p;
}
}  // namespace

const ModuleManifest& HolonomicController::omni_manifest() {
  static const ModuleManifest m =
      controller_manifest("omni", "three or more omni wheels at given angles (PSR bases)", holonomic_parameters(false));
  return m;
}

const ModuleManifest& HolonomicController::mecanum_manifest() {
  static const ModuleManifest m =
      controller_manifest("mecanum", "four mecanum wheels, X arrangement", holonomic_parameters(true));
  return m;
}

const ModuleManifest& HolonomicController::do_manifest() const noexcept {
  return type_ == "mecanum" ? mecanum_manifest() : omni_manifest();
}

HolonomicController::HolonomicController(const ControllerConfig& config, HardwareInterface& hardware)
    : CController(config.period), config_(config), hardware_(hardware), limiter_(config.limits) {
  type_ = config_.type == "mecanum" ? std::string_view("mecanum") : std::string_view("omni");
  Diagnostics d = validate(config_);
  if (config_.type != "omni" && config_.type != "mecanum") {
    d.error(config_.where, "controller type must be \"omni\" or \"mecanum\", got \"" + config_.type + "\"");
  }
  const std::size_t n = config_.holonomic.wheels.size();
  if (!d.has_errors() && hardware_.wheel_count() != n) {
    d.error(config_.where, "the hardware interface has " + std::to_string(hardware_.wheel_count()) +
                               " wheels, the configuration " + std::to_string(n));
  }
  if (d.has_errors()) throw ConfigError(std::move(d));

  const double r = config_.holonomic.wheel_radius_m;
  jacobian_.resize(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    const OmniWheelConfig& w = config_.holonomic.wheels[i];
    // The wheel turns with the contact point's velocity along u = d + tan(roller) * n, where d is
    // the drive direction and n its normal; the rollers absorb the rest.
    const double t = std::tan(w.roller_angle_rad);
    const double ux = std::cos(w.drive_angle_rad) - t * std::sin(w.drive_angle_rad);
    const double uy = std::sin(w.drive_angle_rad) + t * std::cos(w.drive_angle_rad);
    const auto row = static_cast<Eigen::Index>(i);
    jacobian_(row, 0) = ux / r;
    jacobian_(row, 1) = uy / r;
    jacobian_(row, 2) = (uy * w.x_m - ux * w.y_m) / r;
  }
  const Eigen::MatrixXd dense = jacobian_;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(dense);
  if (cod.rank() < 3) {
    throw ConfigError(config_.where, "the wheels do not span planar motion (Jacobian rank " + std::to_string(cod.rank()) +
                                         " < 3): check the wheel angles");
  }
  pinv_ = cod.pseudoInverse();
  wheel_cmd_ = WheelVector::Zero(static_cast<Eigen::Index>(n));
  wheel_vel_ = wheel_cmd_;
  wheel_pos_ = wheel_cmd_;
  last_pos_ = wheel_cmd_;
}

BaseCapabilities HolonomicController::do_capabilities() const noexcept {
  BaseCapabilities c;
  const auto& l = config_.limits;
  c.max_vx_m_s = l.vx.max_velocity.value_or(c.max_vx_m_s);
  c.max_vy_m_s = l.vy.max_velocity.value_or(c.max_vy_m_s);
  c.max_wz_rad_s = l.wz.max_velocity.value_or(c.max_wz_rad_s);
  if (config_.max_wheel_speed_rad_s) {
    // Pure motion along one axis saturates when the busiest wheel reaches its limit.
    const double w = *config_.max_wheel_speed_rad_s;
    c.max_vx_m_s = std::min(c.max_vx_m_s, w / jacobian_.col(0).cwiseAbs().maxCoeff());
    c.max_vy_m_s = std::min(c.max_vy_m_s, w / jacobian_.col(1).cwiseAbs().maxCoeff());
    c.max_wz_rad_s = std::min(c.max_wz_rad_s, w / jacobian_.col(2).cwiseAbs().maxCoeff());
  }
  return c;
}

void HolonomicController::inverse(const Twist2D& twist, std::span<double> wheels_rad_s) const noexcept {
  const Eigen::Vector3d v(twist.vx_m_s, twist.vy_m_s, twist.wz_rad_s);
  for (Eigen::Index i = 0; i < jacobian_.rows(); ++i) {
    wheels_rad_s[static_cast<std::size_t>(i)] = jacobian_.row(i).dot(v);
  }
}

Twist2D HolonomicController::forward(std::span<const double> wheels_rad_s) const noexcept {
  const Eigen::Map<const Eigen::VectorXd> w(wheels_rad_s.data(), jacobian_.rows());
  const Eigen::Vector3d v = pinv_ * w;
  return {v.x(), v.y(), v.z()};
}

ControlStatus HolonomicController::on_update(Time now, Duration period, const Twist2D& command, bool /*timed_out*/,
                                             Twist2D& limited, OdometryReading& odometry) noexcept {
  const double dt = to_seconds(period);
  bool clipped = false;
  Twist2D out = limiter_.apply(command, dt, clipped);
  const Eigen::Vector3d v(out.vx_m_s, out.vy_m_s, out.wz_rad_s);
  wheel_cmd_.noalias() = jacobian_ * v;
  if (config_.max_wheel_speed_rad_s) {
    const double peak = wheel_cmd_.cwiseAbs().maxCoeff();
    if (peak > *config_.max_wheel_speed_rad_s) {
      const double s = *config_.max_wheel_speed_rad_s / peak;
      const Twist2D vel = limiter_.velocity();
      const Twist2D acc = limiter_.acceleration();
      const Twist2D prev{vel.vx_m_s - acc.vx_m_s * dt, vel.vy_m_s - acc.vy_m_s * dt, vel.wz_rad_s - acc.wz_rad_s * dt};
      out = {out.vx_m_s * s, out.vy_m_s * s, out.wz_rad_s * s};
      wheel_cmd_ *= s;
      limiter_.set_state(out, dt > 0.0 ? Twist2D{(out.vx_m_s - prev.vx_m_s) / dt, (out.vy_m_s - prev.vy_m_s) / dt,
                                                 (out.wz_rad_s - prev.wz_rad_s) / dt}
                                       : Twist2D{});
      clipped = true;
    }
  }
  limited = out;
  const auto n = static_cast<std::size_t>(wheel_cmd_.size());
  const bool wrote = hardware_.write_wheel_velocities({wheel_cmd_.data(), n});
  const bool read = hardware_.read_wheel_states({wheel_vel_.data(), n}, {wheel_pos_.data(), n});
  if (read) {
    if (has_positions_) {
      const Eigen::Vector3d d = pinv_ * (wheel_pos_ - last_pos_);
      odometry.pose = integrate_body_displacement(odometry.pose, d.x(), d.y(), d.z());
    }
    last_pos_ = wheel_pos_;
    has_positions_ = true;
    const Eigen::Vector3d t = pinv_ * wheel_vel_;
    odometry.twist = {t.x(), t.y(), t.z()};
    odometry.stamp = now;
  }
  if (!wrote || !read) return ControlStatus::hardware_fault;
  return clipped ? ControlStatus::limited : ControlStatus::ok;
}

}  // namespace tripodal
