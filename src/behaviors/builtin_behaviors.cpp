#include "tripodal/behaviors/builtin_behaviors.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "tripodal/behaviors/behavior_registry.hpp"
#include "stale_watch.hpp"

namespace tripodal {

namespace {

double clamp_abs(double v, double limit) noexcept { return std::clamp(v, -limit, limit); }

// The odometry resource named by the "odometry" parameter, or the first one when it is empty.
const OdometryResource* find_odometry(const ParameterSet& params, const BehaviorContext& context) {
  if (context.resources == nullptr) return nullptr;
  const std::string& name = params.string("odometry");
  return name.empty() ? context.resources->first<OdometryReading>()
                      : context.resources->find<OdometryReading>(name);
}

using detail::stale_too_long;

// Body-frame translation toward a target at (dx, dy) in the body frame with speed `speed` (>= 0),
// as the base can execute it: straight on a holonomic base; on a base without sideways motion,
// forward only, scaled by cos(bearing) so the robot turns first and never drives away from the
// target. `wz_toward` receives the yaw rate that points the robot at the target (unicycle only).
Twist2D drive_toward(double dx, double dy, double speed, double k_alpha, double max_yaw_rate,
                     const BaseCapabilities& base) noexcept {
  Twist2D cmd;
  const double rho = std::hypot(dx, dy);
  if (rho <= 0.0) return cmd;
  if (base.holonomic()) {
    cmd.vx_m_s = clamp_abs(speed * dx / rho, base.max_vx_m_s);
    cmd.vy_m_s = clamp_abs(speed * dy / rho, base.max_vy_m_s);
  } else {
    const double bearing = std::atan2(dy, dx);
    cmd.vx_m_s = std::min(speed * std::max(0.0, std::cos(bearing)), base.max_vx_m_s);
    cmd.wz_rad_s = clamp_abs(k_alpha * bearing, std::min(max_yaw_rate, base.max_wz_rad_s));
  }
  return cmd;
}

}  // namespace

// --- BhStop ---------------------------------------------------------------------------------

const ModuleManifest& BhStop::static_manifest() {
  static const ModuleManifest m = behavior_manifest("BhStop", "commands zero velocity; never finishes", {}, {});
  return m;
}
void BhStop::on_activate(const ParameterSet&, const BehaviorContext&) {}
std::optional<Twist2D> BhStop::on_step(const BehaviorContext&) noexcept { return Twist2D{}; }

// --- BhRotateInPlace ------------------------------------------------------------------------

const ModuleManifest& BhRotateInPlace::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhRotateInPlace", "turns on the spot by a relative angle measured by odometry", {"odometry"},
      {parameter::number("angle_rad", 0.0, "rad", "relative turn, counter-clockwise positive", -100.0, 100.0),
       parameter::number("max_yaw_rate_rad_s", 0.8, "rad/s", "yaw rate limit", 1e-6),
       parameter::number("tolerance_rad", 0.02, "rad", "success when the remaining angle is below this", 1e-6),
       parameter::number("gain", 2.0, "1/s", "proportional gain on the remaining angle", 1e-6),
       parameter::number("stale_timeout_s", 0.5, "s", "fail when odometry stays stale longer than this", 0.0),
       parameter::text("odometry", "", "odometry resource name; empty = the first one")});
  return m;
}

void BhRotateInPlace::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  odom_ = find_odometry(params, context);
  angle_rad_ = params.number("angle_rad");
  max_rate_ = params.number("max_yaw_rate_rad_s");
  tolerance_rad_ = params.number("tolerance_rad");
  gain_ = params.number("gain");
  stale_timeout_ = from_seconds(params.number("stale_timeout_s"));
  started_ = false;
  turned_rad_ = 0.0;
  stale_ = false;
  if (odom_ == nullptr) fail("no odometry resource");
}

std::optional<Twist2D> BhRotateInPlace::on_step(const BehaviorContext& context) noexcept {
  const bool fresh = odom_->is_fresh(context.now);
  if (stale_too_long(fresh, context.now, stale_timeout_, stale_, stale_since_)) {
    fail("odometry stale");
    return std::nullopt;
  }
  if (!fresh) return Twist2D{};
  const double yaw = odom_->latest().pose.theta_rad;
  if (!started_) {
    started_ = true;
    last_yaw_ = yaw;
  }
  // Accumulating wrapped increments counts full turns (angle_rad may exceed pi).
  turned_rad_ += wrap_angle(yaw - last_yaw_);
  last_yaw_ = yaw;
  const double remaining = angle_rad_ - turned_rad_;
  if (std::abs(remaining) <= tolerance_rad_) {
    succeed();
    return std::nullopt;
  }
  Twist2D cmd;
  cmd.wz_rad_s = clamp_abs(gain_ * remaining, std::min(max_rate_, context.base.max_wz_rad_s));
  return cmd;
}

// --- BhGoToPose -----------------------------------------------------------------------------

const ModuleManifest& BhGoToPose::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhGoToPose", "drives to a goal pose; holonomic and differential bases alike",
      {"odometry", "map_from_base", "goal_pose"},
      {parameter::number("goal_x_m", 0.0, "m", "goal x in the chosen frame"),
       parameter::number("goal_y_m", 0.0, "m", "goal y in the chosen frame"),
       parameter::number("goal_theta_rad", 0.0, "rad", "goal heading in the chosen frame"),
       parameter::text("frame", "odom", "\"odom\" (odometry resource) or \"map\" (localizer pose)"),
       parameter::flag("use_navigation_goal", false, "take the goal from the navigation data (map frame)"),
       parameter::number("max_speed_m_s", 0.4, "m/s", "translation speed limit", 1e-6),
       parameter::number("max_yaw_rate_rad_s", 1.0, "rad/s", "yaw rate limit", 1e-6),
       parameter::number("position_tolerance_m", 0.03, "m", "position reached within this distance", 1e-6),
       parameter::number("heading_tolerance_rad", 0.03, "rad", "heading reached within this angle", 1e-6),
       parameter::number("k_rho", 1.0, "1/s", "speed per metre of remaining distance", 1e-6),
       parameter::number("k_alpha", 2.5, "1/s", "yaw rate per radian of heading error", 1e-6),
       parameter::number("timeout_s", 0.0, "s", "fail when the goal is not reached in this time; 0 = none", 0.0),
       parameter::number("stale_timeout_s", 0.5, "s", "fail when the pose stays stale longer than this", 0.0),
       parameter::text("odometry", "", "odometry resource name; empty = the first one")});
  return m;
}

void BhGoToPose::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  const std::string& frame = params.string("frame");
  if (frame != "odom" && frame != "map") {
    throw ConfigError(SourceLocation{}, "BhGoToPose: parameter 'frame' must be \"odom\" or \"map\", got \"" + frame + "\"");
  }
  map_frame_ = frame == "map";
  use_navi_goal_ = params.boolean("use_navigation_goal");
  if (use_navi_goal_) map_frame_ = true;
  goal_ = {params.number("goal_x_m"), params.number("goal_y_m"), params.number("goal_theta_rad")};
  max_speed_ = params.number("max_speed_m_s");
  max_yaw_rate_ = params.number("max_yaw_rate_rad_s");
  pos_tol_ = params.number("position_tolerance_m");
  heading_tol_ = params.number("heading_tolerance_rad");
  k_rho_ = params.number("k_rho");
  k_alpha_ = params.number("k_alpha");
  timeout_ = from_seconds(params.number("timeout_s"));
  stale_timeout_ = from_seconds(params.number("stale_timeout_s"));
  started_ = context.now;
  position_reached_ = false;
  stale_ = false;
  odom_ = map_frame_ ? nullptr : find_odometry(params, context);
  if (!map_frame_ && odom_ == nullptr) fail("no odometry resource");
}

std::optional<Twist2D> BhGoToPose::on_step(const BehaviorContext& context) noexcept {
  if (timeout_.count() > 0 && context.now - started_ > timeout_) {
    fail("timeout");
    return std::nullopt;
  }
  Pose2D pose;
  Pose2D goal = goal_;
  if (map_frame_) {
    const bool ok = context.navi != nullptr && context.navi->localized;
    if (stale_too_long(ok, context.now, stale_timeout_, stale_, stale_since_)) {
      fail("not localized");
      return std::nullopt;
    }
    if (!ok) return Twist2D{};
    pose = context.navi->map_from_base;
    if (use_navi_goal_) {
      if (!context.navi->has_goal) return Twist2D{};
      goal = context.navi->goal;
    }
  } else {
    const bool fresh = odom_->is_fresh(context.now);
    if (stale_too_long(fresh, context.now, stale_timeout_, stale_, stale_since_)) {
      fail("odometry stale");
      return std::nullopt;
    }
    if (!fresh) return Twist2D{};
    pose = odom_->latest().pose;
  }

  // Goal in the body frame.
  const double ex = goal.x_m - pose.x_m;
  const double ey = goal.y_m - pose.y_m;
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  const double dx = c * ex + s * ey;
  const double dy = -s * ex + c * ey;
  const double rho = std::hypot(dx, dy);
  const double heading_error = wrap_angle(goal.theta_rad - pose.theta_rad);
  const double yaw_limit = std::min(max_yaw_rate_, context.base.max_wz_rad_s);

  // Hysteresis: once the position is reached, only a clear drift resumes the approach, so the
  // final turn of a differential base does not chase a bearing that is pure noise.
  if (position_reached_ && rho > 2.0 * pos_tol_) position_reached_ = false;
  if (!position_reached_ && rho <= pos_tol_) position_reached_ = true;

  if (position_reached_) {
    if (std::abs(heading_error) <= heading_tol_) {
      succeed();
      return std::nullopt;
    }
    Twist2D cmd;
    cmd.wz_rad_s = clamp_abs(k_alpha_ * heading_error, yaw_limit);
    return cmd;
  }
  const double speed = std::min(max_speed_, k_rho_ * rho);
  Twist2D cmd = drive_toward(dx, dy, speed, k_alpha_, yaw_limit, context.base);
  // A holonomic base turns to the final heading on the way.
  if (context.base.holonomic()) cmd.wz_rad_s = clamp_abs(k_alpha_ * heading_error, yaw_limit);
  return cmd;
}

// --- BhBackOff ------------------------------------------------------------------------------

const ModuleManifest& BhBackOff::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhBackOff", "backs straight off after a bump, then optionally turns", {"odometry"},
      {parameter::number("distance_m", 0.2, "m", "distance to back off", 0.0, 10.0),
       parameter::number("speed_m_s", 0.1, "m/s", "backing speed", 1e-6),
       parameter::number("turn_rad", 0.0, "rad", "turn after backing off, counter-clockwise positive", -10.0, 10.0),
       parameter::number("yaw_rate_rad_s", 0.5, "rad/s", "yaw rate of the turn", 1e-6),
       parameter::number("stale_timeout_s", 0.5, "s", "fail when odometry stays stale longer than this", 0.0),
       parameter::text("odometry", "", "odometry resource name; empty = the first one")});
  return m;
}

void BhBackOff::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  odom_ = find_odometry(params, context);
  distance_m_ = params.number("distance_m");
  speed_ = params.number("speed_m_s");
  turn_rad_ = params.number("turn_rad");
  yaw_rate_ = params.number("yaw_rate_rad_s");
  stale_timeout_ = from_seconds(params.number("stale_timeout_s"));
  started_ = false;
  turning_ = false;
  turned_rad_ = 0.0;
  stale_ = false;
  if (odom_ == nullptr) fail("no odometry resource");
}

std::optional<Twist2D> BhBackOff::on_step(const BehaviorContext& context) noexcept {
  const bool fresh = odom_->is_fresh(context.now);
  if (stale_too_long(fresh, context.now, stale_timeout_, stale_, stale_since_)) {
    fail("odometry stale");
    return std::nullopt;
  }
  if (!fresh) return Twist2D{};
  const Pose2D& pose = odom_->latest().pose;
  if (!started_) {
    started_ = true;
    start_ = pose;
    last_yaw_ = pose.theta_rad;
  }
  Twist2D cmd;
  if (!turning_) {
    const double travelled = std::hypot(pose.x_m - start_.x_m, pose.y_m - start_.y_m);
    const double remaining = distance_m_ - travelled;
    if (remaining > 0.005) {
      // Slow down over the last few centimetres so the base does not overshoot by much.
      cmd.vx_m_s = -std::min(speed_, std::max(0.02, 2.0 * remaining));
      return cmd;
    }
    turning_ = true;
    last_yaw_ = pose.theta_rad;
  }
  turned_rad_ += wrap_angle(pose.theta_rad - last_yaw_);
  last_yaw_ = pose.theta_rad;
  const double remaining = turn_rad_ - turned_rad_;
  if (std::abs(remaining) <= 0.02) {
    succeed();
    return std::nullopt;
  }
  cmd.wz_rad_s = clamp_abs(2.0 * remaining, std::min(yaw_rate_, context.base.max_wz_rad_s));
  return cmd;
}

// --- BhAvoidObstacle ------------------------------------------------------------------------

namespace {
constexpr std::size_t kMaxTableBeams = 4096;
}

const ModuleManifest& BhAvoidObstacle::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhAvoidObstacle", "laser safety override: slows and stops translation toward obstacles", {"laser_scan"},
      {parameter::number("stop_distance_m", 0.15, "m", "no motion toward an obstacle this close to the footprint", 0.0),
       parameter::number("slow_distance_m", 0.8, "m", "full speed allowed beyond this clearance", 0.0),
       parameter::number("max_speed_m_s", 1.0, "m/s", "speed allowed at slow_distance_m and beyond", 0.0),
       parameter::number("robot_radius_m", 0.25, "m", "radius of the circular footprint", 0.0),
       parameter::number("laser_x_m", 0.0, "m", "laser position in the body frame"),
       parameter::number("laser_y_m", 0.0, "m", "laser position in the body frame"),
       parameter::number("laser_yaw_rad", 0.0, "rad", "laser orientation in the body frame"),
       parameter::text("laser", "", "laser resource name; empty = the first one")});
  return m;
}

void BhAvoidObstacle::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  stop_m_ = params.number("stop_distance_m");
  slow_m_ = params.number("slow_distance_m");
  if (slow_m_ <= stop_m_) {
    throw ConfigError(SourceLocation{}, "BhAvoidObstacle: slow_distance_m must be greater than stop_distance_m");
  }
  max_speed_ = params.number("max_speed_m_s");
  radius_m_ = params.number("robot_radius_m");
  laser_x_m_ = params.number("laser_x_m");
  laser_y_m_ = params.number("laser_y_m");
  laser_yaw_rad_ = params.number("laser_yaw_rad");
  const std::string& name = params.string("laser");
  laser_ = context.resources == nullptr ? nullptr
           : name.empty()               ? context.resources->first<LaserScan>()
                                        : context.resources->find<LaserScan>(name);
  // Capacity reserved here so that step() never allocates, whatever the beam count.
  cos_.resize(0);
  sin_.resize(0);
  scan_seen_ = 0;
  if (laser_ == nullptr) fail("no laser resource");
}

void BhAvoidObstacle::rebuild_table(const LaserScan& scan) noexcept {
  const auto n = static_cast<Eigen::Index>(std::min(scan.ranges_m.size(), kMaxTableBeams));
  // Fixed maximum size: resizing never allocates.
  cos_.resize(n);
  sin_.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double a = laser_yaw_rad_ + scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    cos_[i] = static_cast<float>(std::cos(a));
    sin_[i] = static_cast<float>(std::sin(a));
  }
  table_angle_min_ = scan.angle_min_rad;
  table_increment_ = scan.angle_increment_rad;
}

std::optional<Twist2D> BhAvoidObstacle::on_step(const BehaviorContext& context) noexcept {
  VelocityEnvelope env;
  if (!laser_->is_fresh(context.now)) {
    // Blind: no translation at all, rotation in place stays allowed.
    env.vx_lo_m_s = env.vx_hi_m_s = env.vy_lo_m_s = env.vy_hi_m_s = 0.0;
    set_envelope(env);
    return std::nullopt;
  }
  // The envelope depends on the scan alone: computed once per scan (a laser publishes far less
  // often than the loop runs).
  if (laser_->sequence() == scan_seen_) {
    set_envelope(envelope_);
    return std::nullopt;
  }
  scan_seen_ = laser_->sequence();
  const LaserScan& scan = laser_->latest();
  if (static_cast<std::size_t>(cos_.size()) != std::min(scan.ranges_m.size(), kMaxTableBeams) || table_angle_min_ != scan.angle_min_rad ||
      table_increment_ != scan.angle_increment_rad) {
    rebuild_table(scan);
  }
  // Clearance from the footprint along each body axis direction, over the beams whose return
  // lies in the corridor the footprint sweeps when moving along that axis.
  constexpr double kInf = VelocityEnvelope::kInf;
  // Clearance along +x (front), -x (back), +y (left), -y (right).
  enum Axis : std::size_t { kFront, kBack, kLeft, kRight };
  double along[4] = {kInf, kInf, kInf, kInf};
  const double r = radius_m_;
  const auto n = static_cast<std::size_t>(cos_.size());
  const float* ranges = scan.ranges_m.data();
  // Only returns closer than the slow-down zone can restrict anything; testing the raw range
  // first skips the far majority of beams.
  const auto rmin = static_cast<float>(scan.range_min_m);
  const auto near = static_cast<float>(std::min(scan.range_max_m, r + slow_m_ + std::hypot(laser_x_m_, laser_y_m_)));
  const double reach2 = (r + slow_m_) * (r + slow_m_);  // a return closer than r + slow_m_ counts
  // A return off the corridors limits an axis by (d - r) * d / |coordinate| >= d - r (below).
  // That costs a square root and a division, so it is skipped where it cannot change the
  // envelope: when d - r exceeds the axis's clearance so far (it would not lower the minimum) or
  // slow_m_ (any clearance beyond slow_m_ allows full speed). Compared as squared distances,
  // with a relative margin far above the few roundings of the candidate, so that what is skipped
  // is strictly above the bound and the envelope is bit for bit the one every return computes.
  constexpr double kMargin = 1.0 + 1e-6;
  auto skip_beyond2 = [&](double clearance) noexcept {
    const double bound = std::min(clearance, slow_m_);
    if (bound < 0.0) return -1.0;  // a point inside the footprint: no candidate (>= 0) is lower
    const double d = (bound + r) * kMargin;
    return d * d;
  };
  double beyond2[4];
  for (double& b : beyond2) b = skip_beyond2(kInf);
  auto lower = [&](std::size_t axis, double clearance) noexcept {
    if (clearance < along[axis]) {
      along[axis] = clearance;
      beyond2[axis] = skip_beyond2(clearance);
    }
  };
  // One return within [rmin, near].
  auto visit_near = [&](std::size_t i) noexcept {
    const float range = ranges[i];
    const auto k = static_cast<Eigen::Index>(i);
    const double x = laser_x_m_ + range * static_cast<double>(cos_[k]);
    const double y = laser_y_m_ + range * static_cast<double>(sin_[k]);
    const std::size_t x_axis = x > 0.0 ? kFront : kBack;
    const std::size_t y_axis = y > 0.0 ? kLeft : kRight;
    const double ax = std::abs(x), ay = std::abs(y);
    // Clearance from the footprint along each axis direction, over the points in the corridor
    // the footprint sweeps when moving along that axis.
    if (ay <= r) lower(x_axis, ax - r);
    if (ax <= r) lower(y_axis, ay - r);
    // Outside those corridors too: a base that turns while it moves (a differential drive on a
    // curve) sweeps beyond the straight corridor, and a person walks into it from the side. A
    // return at bearing a from an axis closes on the footprint at cos(a) of the speed along that
    // axis: its clearance along the axis counts as gap / cos(a). Returns nearly abeam (cos(a) <=
    // 0.1, within about 6 degrees of the axis's normal) leave that axis free.
    // The sign of x picks front or back, that of y left or right; d = sqrt(x^2 + y^2) and
    // gap / cos(a) = gap * d / |x|. Per return this was std::hypot and four divisions, which
    // doubled the reactive cycle's instructions (issue 42).
    const double d2 = x * x + y * y;
    const bool on_x = d2 <= beyond2[x_axis], on_y = d2 <= beyond2[y_axis];
    if ((on_x || on_y) && d2 < reach2 && d2 > 0.0) {
      constexpr double kAbeam = 0.1;
      const double d = std::sqrt(d2);
      const double gap_d = std::max(d - r, 0.0) * d;
      const double abeam = kAbeam * d;
      if (on_x && ax > abeam) lower(x_axis, gap_d / ax);
      if (on_y && ay > abeam) lower(y_axis, gap_d / ay);
    }
  };
  std::size_t i = 0;
#if defined(__SSE2__)
  // Blocks of 16 beams are tested with SIMD compares, their lanes' results packed into a 16-bit
  // mask (movmskps); a block without a near return costs one test, and in the others only the
  // near returns are visited, by their set bits (the far ones of a block took a scalar test each,
  // and the block loop was a third of this behavior's instructions at 8 beams per block).
  constexpr std::size_t kBlock = 16;
  const __m128 lo = _mm_set1_ps(rmin), hi = _mm_set1_ps(near);
  auto lanes_near = [&](const float* p) noexcept {
    const __m128 v = _mm_loadu_ps(p);  // NaN compares false: skipped like a far return
    return static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(v, lo), _mm_cmple_ps(v, hi))));
  };
  for (; i + kBlock <= n; i += kBlock) {
    unsigned mask = lanes_near(ranges + i) | (lanes_near(ranges + i + 4) << 4U) | (lanes_near(ranges + i + 8) << 8U) |
                    (lanes_near(ranges + i + 12) << 12U);
    for (; mask != 0; mask &= mask - 1) visit_near(i + static_cast<std::size_t>(std::countr_zero(mask)));
  }
#endif
  for (; i < n; ++i) {
    const float range = ranges[i];
    if (range >= rmin && range <= near) visit_near(i);  // also skips NaN and no-return values
  }
  const double span = slow_m_ - stop_m_;
  auto allowed = [&](double clearance) noexcept {
    if (clearance > slow_m_) return kInf;
    return max_speed_ * std::clamp((clearance - stop_m_) / span, 0.0, 1.0);
  };
  env.vx_hi_m_s = allowed(along[kFront]);
  env.vx_lo_m_s = -allowed(along[kBack]);
  env.vy_hi_m_s = allowed(along[kLeft]);
  env.vy_lo_m_s = -allowed(along[kRight]);
  envelope_ = env;
  set_envelope(env);
  return std::nullopt;
}

// --- registration ---------------------------------------------------------------------------

void register_builtin_behaviors(BehaviorRegistry& registry) {
  registry.add<BhStop>();
  registry.add<BhRotateInPlace>();
  registry.add<BhGoToPose>();
  registry.add<BhBackOff>();
  registry.add<BhAvoidObstacle>();
}

}  // namespace tripodal
