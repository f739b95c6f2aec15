#include "bh_approach.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

using namespace tripodal;

namespace example {

const ModuleManifest& BhApproach::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("BhApproach", ModuleKind::behavior, Layer::reactive)
                                      .description("approaches the obstacle ahead and stops short of it")
                                      .input("laser_scan")
                                      .output("behavior_command")
                                      .number("speed_m_s", 0.4, "m/s", "cruise speed", 0.0)
                                      .number("slow_distance_m", 1.5, "m", "slow down below this clearance", 0.0)
                                      .number("stop_distance_m", 0.8, "m", "succeed at this clearance", 0.0)
                                      .number("robot_radius_m", 0.25, "m", "footprint radius", 0.0)
                                      .build();
  return m;
}

void BhApproach::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  speed_m_s_ = params.number("speed_m_s");
  slow_m_ = params.number("slow_distance_m");
  stop_m_ = params.number("stop_distance_m");
  radius_m_ = params.number("robot_radius_m");
  if (slow_m_ <= stop_m_) throw ConfigError(SourceLocation{}, "BhApproach: slow_distance_m must exceed stop_distance_m");
  laser_ = context.resources == nullptr ? nullptr : context.resources->first<LaserScan>();
  if (laser_ == nullptr) fail("no laser resource");
}

std::optional<Twist2D> BhApproach::on_step(const BehaviorContext& context) noexcept {
  // Without a fresh scan the behavior does not know what is ahead: it stands still.
  if (!laser_->is_fresh(context.now)) return Twist2D{};
  const LaserScan& scan = laser_->latest();
  // Free distance ahead: returns inside the corridor the footprint sweeps when driving forward.
  double ahead = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!(r >= scan.range_min_m && r < scan.range_max_m)) continue;  // no return
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double x = r * std::cos(a), y = r * std::sin(a);
    if (x > 0.0 && std::abs(y) <= radius_m_) ahead = std::min(ahead, x - radius_m_);
  }
  if (ahead <= stop_m_) {
    succeed();
    return Twist2D{};
  }
  const double scale = std::clamp((ahead - stop_m_) / (slow_m_ - stop_m_), 0.0, 1.0);
  return Twist2D{speed_m_s_ * scale, 0.0, 0.0};
}

}  // namespace example
