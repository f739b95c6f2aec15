#include "tripodal/controllers/differential_drive_controller.hpp"

#include <algorithm>
#include <cmath>

#include "tripodal/controllers/kinematics.hpp"

namespace tripodal {

const ModuleManifest& DifferentialDriveController::static_manifest() {
  static const ModuleManifest m = controller_manifest(
      "differential", "two-wheel differential drive, wheels [left, right]",
      {parameter::positive("wheel_separation_m", {}, "m", "distance between the wheel contact points (track width)"),
       parameter::positive("wheel_radius_m", {}, "m", "wheel radius")});
  return m;
}

DifferentialDriveController::DifferentialDriveController(const ControllerConfig& config, HardwareInterface& hardware)
    : CController(config.period), config_(config), hardware_(hardware), limiter_(config.limits) {
  Diagnostics d = validate(config_);
  if (config_.type != "differential") d.error(config_.where, "controller type must be \"differential\", got \"" + config_.type + "\"");
  if (hardware_.wheel_count() != 2) {
    d.error(config_.where, "a differential base needs a hardware interface with 2 wheels, got " +
                               std::to_string(hardware_.wheel_count()));
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
}

BaseCapabilities DifferentialDriveController::do_capabilities() const noexcept {
  BaseCapabilities c;
  const auto& l = config_.limits;
  const auto& k = config_.differential;
  c.max_vx_m_s = l.vx.max_velocity.value_or(BaseCapabilities{}.max_vx_m_s);
  c.max_vy_m_s = 0.0;
  c.max_wz_rad_s = l.wz.max_velocity.value_or(BaseCapabilities{}.max_wz_rad_s);
  if (config_.max_wheel_speed_rad_s) {
    const double v_wheel = *config_.max_wheel_speed_rad_s * k.wheel_radius_m;
    c.max_vx_m_s = std::min(c.max_vx_m_s, v_wheel);
    c.max_wz_rad_s = std::min(c.max_wz_rad_s, 2.0 * v_wheel / k.wheel_separation_m);
  }
  return c;
}

ControlStatus DifferentialDriveController::on_update(Time now, Duration period, const Twist2D& command,
                                                     bool /*timed_out*/, Twist2D& limited,
                                                     OdometryReading& odometry) noexcept {
  const auto& k = config_.differential;
  const double dt = to_seconds(period);
  Twist2D target = command;
  target.vy_m_s = 0.0;  // cannot move sideways
  bool clipped = false;
  Twist2D out = limiter_.apply(target, dt, clipped);

  double left = 0.0, right = 0.0;
  differential_inverse(k.wheel_separation_m, k.wheel_radius_m, out, left, right);
  if (config_.max_wheel_speed_rad_s) {
    const double peak = std::max(std::abs(left), std::abs(right));
    if (peak > *config_.max_wheel_speed_rad_s) {
      // One factor for both axes keeps vx / wz, i.e. the path's curvature.
      const double s = *config_.max_wheel_speed_rad_s / peak;
      const Twist2D before = limiter_.velocity();
      const Twist2D prev{before.vx_m_s - limiter_.acceleration().vx_m_s * dt, 0.0,
                         before.wz_rad_s - limiter_.acceleration().wz_rad_s * dt};
      out = {out.vx_m_s * s, 0.0, out.wz_rad_s * s};
      left *= s;
      right *= s;
      limiter_.set_state(out, dt > 0.0 ? Twist2D{(out.vx_m_s - prev.vx_m_s) / dt, 0.0, (out.wz_rad_s - prev.wz_rad_s) / dt}
                                       : Twist2D{});
      clipped = true;
    }
  }
  wheel_cmd_ = {left, right};
  limited = out;
  const bool wrote = hardware_.write_wheel_velocities(wheel_cmd_);
  const bool read = hardware_.read_wheel_states(wheel_vel_, wheel_pos_);

  if (read) {
    if (has_positions_) {
      const double dl = (wheel_pos_[0] - last_pos_[0]) * k.wheel_radius_m;
      const double dr = (wheel_pos_[1] - last_pos_[1]) * k.wheel_radius_m;
      odometry.pose = integrate_body_displacement(odometry.pose, 0.5 * (dl + dr), 0.0, (dr - dl) / k.wheel_separation_m);
    }
    last_pos_ = wheel_pos_;
    has_positions_ = true;
    odometry.twist = differential_forward(k.wheel_separation_m, k.wheel_radius_m, wheel_vel_[0], wheel_vel_[1]);
    odometry.stamp = now;
  }
  if (!wrote || !read) return ControlStatus::hardware_fault;
  return clipped ? ControlStatus::limited : ControlStatus::ok;
}

}  // namespace tripodal
