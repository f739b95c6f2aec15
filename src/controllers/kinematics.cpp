#include "tripodal/controllers/kinematics.hpp"

#include <cmath>

namespace tripodal {

Pose2D integrate_body_displacement(const Pose2D& pose, double dx_m, double dy_m, double dtheta_rad) noexcept {
  // Constant twist over the period: the displacement in the start frame is V(dtheta) * (dx, dy)
  // with V = [[sin t / t, -(1 - cos t) / t], [(1 - cos t) / t, sin t / t]].
  double a = 1.0, b = 0.0;
  const double t = dtheta_rad;
  if (std::abs(t) > 1e-6) {
    a = std::sin(t) / t;
    b = (1.0 - std::cos(t)) / t;
  } else {
    // Taylor series: exact to double precision for |t| <= 1e-6.
    a = 1.0 - t * t / 6.0;
    b = t / 2.0 - t * t * t / 24.0;
  }
  const double lx = a * dx_m - b * dy_m;
  const double ly = b * dx_m + a * dy_m;
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  return {pose.x_m + c * lx - s * ly, pose.y_m + s * lx + c * ly, wrap_angle(pose.theta_rad + t)};
}

void differential_inverse(double wheel_separation_m, double wheel_radius_m, const Twist2D& twist,
                          double& left_rad_s, double& right_rad_s) noexcept {
  const double half = 0.5 * wheel_separation_m * twist.wz_rad_s;
  left_rad_s = (twist.vx_m_s - half) / wheel_radius_m;
  right_rad_s = (twist.vx_m_s + half) / wheel_radius_m;
}

Twist2D differential_forward(double wheel_separation_m, double wheel_radius_m, double left_rad_s,
                             double right_rad_s) noexcept {
  return {0.5 * wheel_radius_m * (left_rad_s + right_rad_s), 0.0,
          wheel_radius_m * (right_rad_s - left_rad_s) / wheel_separation_m};
}

}  // namespace tripodal
