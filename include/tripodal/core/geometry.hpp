// Planar geometry, the shared vocabulary of every layer: poses and twists (resources, behaviors,
// controllers, simulator), points of the map frame (navigation modules), and the few operations
// on them that several components need (angle wrapping, SE(2) composition, polyline simplification).
#pragma once

#include <span>
#include <vector>

namespace tripodal {

/// A planar pose: frame-to-frame transform, e.g. map_from_base or odom_from_base.
struct Pose2D {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
  friend bool operator==(const Pose2D&, const Pose2D&) = default;
};

/// A planar velocity in the body frame: forward, leftward, counter-clockwise yaw rate.
/// It is also the motion command behaviors produce and controllers execute.
struct Twist2D {
  double vx_m_s = 0.0;
  double vy_m_s = 0.0;
  double wz_rad_s = 0.0;
  friend bool operator==(const Twist2D&, const Twist2D&) = default;
};

/// A point in a plane frame (the map frame unless said otherwise), metres.
struct Point2D {
  double x_m = 0.0;
  double y_m = 0.0;
  friend bool operator==(const Point2D&, const Point2D&) = default;
};

/// Angle wrapped to [-pi, pi). Any finite input; NaN stays NaN.
[[nodiscard]] double wrap_angle(double angle_rad) noexcept;

/// a_from_c = a_from_b * b_from_c (SE(2) composition); the heading is wrapped to [-pi, pi).
[[nodiscard]] Pose2D compose(const Pose2D& a_from_b, const Pose2D& b_from_c) noexcept;

/// b_from_a of a_from_b, so that compose(p, inverse(p)) is the identity (up to rounding).
[[nodiscard]] Pose2D inverse(const Pose2D& a_from_b) noexcept;

/// The point p of frame b expressed in frame a.
[[nodiscard]] Point2D transform(const Pose2D& a_from_b, Point2D p) noexcept;

/// Douglas-Peucker simplification of an open polyline: the subsequence of its points (first and
/// last always kept) such that no dropped point lies farther than tolerance_m from the simplified
/// chain. Iterative, so a long trajectory cannot overflow the stack. A polyline of fewer than
/// three points is returned as it is.
[[nodiscard]] std::vector<Point2D> douglas_peucker(std::span<const Point2D> polyline, double tolerance_m);

}  // namespace tripodal
