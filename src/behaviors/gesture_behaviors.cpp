#include "tripodal/behaviors/gesture_behaviors.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "stale_watch.hpp"

namespace tripodal {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// Returns within this much of the nearest one belong to the same person (a body is ~0.5 m deep).
constexpr double kSameBodyM = 0.3;

}  // namespace

// --- BhFaceVisitor ----------------------------------------------------------------------------

const ModuleManifest& BhFaceVisitor::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhFaceVisitor", "turns the base on the spot to face the nearest person the laser sees (a gesture)", {"laser_scan"},
      {parameter::number("max_range_m", 2.5, "m", "a person farther than this is not the one talking to the robot", 0.2, 20.0),
       parameter::number("tolerance_rad", 0.08, "rad", "success when the person is this close to straight ahead", 1e-3, 1.0),
       parameter::number("max_yaw_rate_rad_s", 0.8, "rad/s", "yaw rate limit", 1e-3),
       parameter::number("gain", 1.5, "1/s", "proportional gain on the bearing", 1e-3),
       parameter::number("stale_timeout_s", 1.0, "s", "fail when the laser stays stale longer than this", 0.0),
       parameter::text("laser", "", "laser resource; empty = the first one")});
  return m;
}

void BhFaceVisitor::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  max_range_m_ = params.number("max_range_m");
  tolerance_rad_ = params.number("tolerance_rad");
  max_yaw_rate_ = params.number("max_yaw_rate_rad_s");
  gain_ = params.number("gain");
  stale_timeout_ = from_seconds(params.number("stale_timeout_s"));
  laser_ = nullptr;
  odom_ = nullptr;
  if (context.resources != nullptr) {
    const std::string& name = params.string("laser");
    laser_ = name.empty() ? context.resources->first<LaserScan>() : context.resources->find<LaserScan>(name);
    odom_ = context.resources->first<OdometryReading>();
  }
  if (laser_ == nullptr) fail("no laser");
  scan_seen_ = laser_ != nullptr ? laser_->sequence() : 0;  // a scan taken before the activation may be old
  bearing_rad_.reset();
  stale_ = false;
}

std::optional<Twist2D> BhFaceVisitor::on_step(const BehaviorContext& context) noexcept {
  const bool fresh = laser_->is_fresh(context.now);
  if (detail::stale_too_long(fresh, context.now, stale_timeout_, stale_, stale_since_)) {
    fail("no laser");
    return Twist2D{};
  }
  const double yaw = odom_ != nullptr && odom_->has_reading() ? odom_->latest().pose.theta_rad : 0.0;
  if (fresh && laser_->sequence() != scan_seen_) {
    scan_seen_ = laser_->sequence();
    const LaserScan& scan = laser_->latest();
    const NavigationData* navi = context.navi;
    const bool use_map = navi != nullptr && navi->map != nullptr && navi->localized;
    const double c = use_map ? std::cos(navi->map_from_base.theta_rad) : 1.0;
    const double s = use_map ? std::sin(navi->map_from_base.theta_rad) : 0.0;
    const std::size_t n = scan.ranges_m.size();
    std::size_t nearest = n;
    double nearest_m = max_range_m_;
    for (std::size_t i = 0; i < n; ++i) {
      const double r = scan.ranges_m[i];
      if (!(r >= scan.range_min_m && r <= nearest_m)) continue;
      if (use_map) {
        const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
        const double bx = r * std::cos(a), by = r * std::sin(a);
        if (navi->map->near_obstacle(navi->map_from_base.x_m + c * bx - s * by, navi->map_from_base.y_m + s * bx + c * by)) continue;
      }
      nearest = i;
      nearest_m = r;
    }
    if (nearest == n) {
      bearing_rad_.reset();
      succeed();  // nobody near: nobody to face
      return Twist2D{};
    }
    // The middle of the body: the beams next to the nearest that return from the same person.
    long lo = 0, hi = 0;
    const auto at = [&](long k) { return scan.ranges_m[static_cast<std::size_t>((static_cast<long>(nearest) + k + static_cast<long>(n)) % static_cast<long>(n))]; };
    while (hi + 1 < static_cast<long>(n) / 2 && std::abs(at(hi + 1) - nearest_m) < kSameBodyM) ++hi;
    while (-lo + 1 < static_cast<long>(n) / 2 && std::abs(at(lo - 1) - nearest_m) < kSameBodyM) --lo;
    const double a = scan.angle_min_rad + (static_cast<double>(nearest) + 0.5 * static_cast<double>(lo + hi)) * scan.angle_increment_rad;
    bearing_rad_ = wrap_angle(a);
    yaw_at_scan_ = yaw;
  }
  if (!bearing_rad_) return Twist2D{};
  // Between scans the odometry tells how far the base has turned since the bearing was measured.
  const double remaining = wrap_angle(*bearing_rad_ - (yaw - yaw_at_scan_));
  if (std::abs(remaining) < tolerance_rad_) {
    succeed();
    return Twist2D{};
  }
  Twist2D cmd;
  cmd.wz_rad_s = std::clamp(gain_ * remaining, -std::min(max_yaw_rate_, context.base.max_wz_rad_s),
                            std::min(max_yaw_rate_, context.base.max_wz_rad_s));
  return cmd;
}

// --- BhNeckGesture ----------------------------------------------------------------------------

const ModuleManifest& BhNeckGesture::static_manifest() {
  static const ModuleManifest m = [] {
    ModuleManifest r = behavior_manifest(
        "BhNeckGesture", "moves a neck or arm joint to a position (a gesture: look at the visitor, at an exhibit)",
        {"joint_state"},
        {parameter::number("angle_deg", 0.0, "deg", "the joint's target position", -360.0, 360.0),
         parameter::number("tolerance_deg", 1.0, "deg", "success within this of the target, the joint stopped", 1e-3, 45.0),
         parameter::number("timeout_s", 10.0, "s", "fail when the joint has not arrived by then", 0.1),
         parameter::text("joint", "neck", "the joint: its state resource and its position channel")});
    r.writes.push_back(ChannelWrite{{}, "joint", ChannelType::joint_position, "the target position while active"});
    return r;
  }();
  return m;
}

void BhNeckGesture::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  target_rad_ = params.number("angle_deg") * kDegToRad;
  tolerance_rad_ = params.number("tolerance_deg") * kDegToRad;
  timeout_ = from_seconds(params.number("timeout_s"));
  started_ = context.now;
  commanded_ = false;
  joint_ = context.resources != nullptr ? context.resources->find<JointReading>(params.string("joint")) : nullptr;
  if (joint_ == nullptr) fail("no joint");
}

std::optional<Twist2D> BhNeckGesture::on_step(const BehaviorContext& context) noexcept {
  write_channel(0, ChannelValue::of(target_rad_));  // the joint's channel holds it after the gesture
  if (!commanded_) {
    commanded_ = true;  // the state tells of the command from the next period on
    return std::nullopt;
  }
  const JointReading& j = joint_->latest();
  if (target_rad_ < j.min_rad || target_rad_ > j.max_rad) {
    fail("joint limit");
    return std::nullopt;
  }
  if (joint_->stamp() > started_ && std::abs(j.position_rad - target_rad_) <= tolerance_rad_ && j.velocity_rad_s == 0.0) {
    succeed();
  } else if (context.now - started_ > timeout_) {
    fail("timeout");
  }
  return std::nullopt;
}

void register_gesture_behaviors(BehaviorRegistry& registry) {
  registry.add<BhFaceVisitor>();
  registry.add<BhNeckGesture>();
}

}  // namespace tripodal
