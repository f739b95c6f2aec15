// The built-in behaviors of the reactive layer, registered by name in the behavior registry:
// BhStop, BhRotateInPlace, BhGoToPose, BhBackOff and BhAvoidObstacle. Each drives holonomic and
// differential bases alike: it reads BehaviorContext::base and steers by heading when the base
// cannot move sideways.
#pragma once

#include <Eigen/Core>
#include <cstddef>

#include "tripodal/behaviors/behavior.hpp"

namespace tripodal {

/// Commands zero velocity every period; never finishes. Used as the lowest-priority fallback and
/// by the supervisor to hold the robot.
class BhStop final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;
};

/// Turns on the spot by angle_rad (relative, counter-clockwise positive) measured by odometry;
/// succeeds within tolerance_rad. Fails with "odometry stale" when odometry stays stale longer
/// than stale_timeout_s, "no odometry resource" when there is none.
class BhRotateInPlace final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const OdometryResource* odom_ = nullptr;
  double angle_rad_ = 0.0, tolerance_rad_ = 0.0, max_rate_ = 0.0, gain_ = 0.0;
  Duration stale_timeout_{0};
  bool started_ = false;
  double last_yaw_ = 0.0, turned_rad_ = 0.0;
  Time stale_since_{};
  bool stale_ = false;
};

/// Drives to a goal pose (goal_x_m, goal_y_m, goal_theta_rad) in the odom frame (odometry
/// resource) or the map frame (NavigationData::map_from_base; or the navigation goal when
/// use_navigation_goal). Holonomic base: translates straight at the goal while turning to the
/// goal heading. Base without sideways motion (max_vy_m_s == 0): turns toward the goal, drives
/// forward with speed scaled by cos(bearing), then turns to the goal heading. Succeeds within
/// position_tolerance_m and heading_tolerance_rad. Fails: "not localized", "odometry stale",
/// "no odometry resource", "timeout".
class BhGoToPose final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const OdometryResource* odom_ = nullptr;
  bool map_frame_ = false, use_navi_goal_ = false;
  Pose2D goal_;
  double max_speed_ = 0.0, max_yaw_rate_ = 0.0, pos_tol_ = 0.0, heading_tol_ = 0.0;
  double k_rho_ = 0.0, k_alpha_ = 0.0;
  Duration timeout_{0}, stale_timeout_{0};
  Time started_{};
  bool position_reached_ = false;
  bool stale_ = false;
  Time stale_since_{};
};

/// Backs straight off by distance_m at speed_m_s (after a bump), then optionally turns by
/// turn_rad; measured by odometry. Fails like BhRotateInPlace.
class BhBackOff final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const OdometryResource* odom_ = nullptr;
  double distance_m_ = 0.0, speed_ = 0.0, turn_rad_ = 0.0, yaw_rate_ = 0.0;
  Duration stale_timeout_{0};
  bool started_ = false, turning_ = false;
  Pose2D start_;
  double last_yaw_ = 0.0, turned_rad_ = 0.0;
  bool stale_ = false;
  Time stale_since_{};
};

/// Laser-based safety override (configure its coordinator input with role safety). Every period
/// it finds the clearance ahead, behind, left and right of a circular footprint of
/// robot_radius_m and imposes a velocity envelope: speed toward an obstacle falls linearly from
/// max_speed_m_s at slow_distance_m to 0 at stop_distance_m (clearances from the footprint);
/// beyond slow_distance_m and in directions without returns nothing is restricted; rotation is
/// never restricted. A return outside the straight corridors counts too, its clearance along an
/// axis being its gap to the footprint divided by the cosine of its bearing from that axis (a base
/// turning on a curve sweeps beyond the corridor, a person steps into it from the side); returns
/// nearly abeam (within about 6 degrees) leave the axis free. With a stale or missing scan it blocks all translation. Never
/// finishes; commands nothing itself (step returns nothing, envelope() carries the limits).
class BhAvoidObstacle final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  void rebuild_table(const LaserScan& scan) noexcept;
  const LaserResource* laser_ = nullptr;
  double stop_m_ = 0.0, slow_m_ = 0.0, max_speed_ = 0.0, radius_m_ = 0.0;
  double laser_x_m_ = 0.0, laser_y_m_ = 0.0, laser_yaw_rad_ = 0.0;
  static constexpr int kMaxBeams = 4096;  ///< beams beyond this are ignored
  using BeamArray = Eigen::Array<float, Eigen::Dynamic, 1, 0, kMaxBeams, 1>;
  // Beam directions in the body frame, rebuilt only when the scan geometry changes. Fixed maximum
  // size: never allocated.
  BeamArray cos_, sin_;
  double table_angle_min_ = 0.0, table_increment_ = 0.0;
  std::size_t scan_seen_ = 0;    ///< sequence of the scan envelope_ was computed from
  VelocityEnvelope envelope_;
};

}  // namespace tripodal
