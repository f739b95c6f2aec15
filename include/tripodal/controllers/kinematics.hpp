// Planar kinematics shared by the controllers and the simulator: exact integration of a constant
// body twist over a period (the SE(2) exponential), and the wheel Jacobians of differential and
// holonomic (omni, mecanum) bases. (wrap_angle lives in core/geometry.hpp.)
#pragma once

#include "tripodal/resources/readings.hpp"

namespace tripodal {

/// The pose reached from `pose` after a body-frame displacement (dx, dy, dtheta) travelled at a
/// constant twist: exact arc integration, no small-angle error for any dtheta.
[[nodiscard]] Pose2D integrate_body_displacement(const Pose2D& pose, double dx_m, double dy_m,
                                                 double dtheta_rad) noexcept;

/// Differential drive, wheels [left, right]: wheel angular velocities of a body twist (vy
/// ignored) and the body twist of wheel angular velocities.
void differential_inverse(double wheel_separation_m, double wheel_radius_m, const Twist2D& twist,
                          double& left_rad_s, double& right_rad_s) noexcept;
[[nodiscard]] Twist2D differential_forward(double wheel_separation_m, double wheel_radius_m,
                                           double left_rad_s, double right_rad_s) noexcept;

}  // namespace tripodal
