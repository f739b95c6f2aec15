// Behaviors written for the test-kit tests: one that drives blind (the helpers must catch it) and
// one that approaches the nearest obstacle ahead and stops short of it (the helpers must pass it).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "tripodal/behaviors/behavior.hpp"

namespace tripodal::testing::test {

/// Commands speed_m_s forward every period, whatever the laser sees. Never finishes.
class BhBlindCruise final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m{"BhBlindCruise", Layer::reactive, ModuleKind::behavior, "drives forward blind", {}, {"cmd_vel"},
                                  {ParameterSpec{"speed_m_s", ValueType::number, Value{0.6}, "m/s", "forward speed", 0.0, {}}}};
    return m;
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext&) override { speed_ = params.number("speed_m_s"); }
  std::optional<Twist2D> on_step(const BehaviorContext&) noexcept override { return Twist2D{speed_, 0.0, 0.0}; }

 private:
  double speed_ = 0.0;
};

/// Drives forward at speed_m_s until the free distance ahead of a footprint of robot_radius_m is
/// below stop_distance_m, then succeeds. Fails "no laser resource" when the named laser is absent.
class BhStopAtWall final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m{
        "BhStopAtWall", Layer::reactive, ModuleKind::behavior, "approaches the obstacle ahead", {"laser_scan"}, {"cmd_vel"},
        {ParameterSpec{"speed_m_s", ValueType::number, Value{0.3}, "m/s", "forward speed", 0.0, {}},
         ParameterSpec{"stop_distance_m", ValueType::number, Value{1.0}, "m", "succeed below this clearance", 0.0, {}},
         ParameterSpec{"robot_radius_m", ValueType::number, Value{0.25}, "m", "footprint radius", 0.0, {}},
         ParameterSpec{"laser", ValueType::string, Value{std::string{}}, "", "laser resource; empty = the first", {}, {}}}};
    return m;
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& ctx) override {
    speed_ = params.number("speed_m_s");
    stop_ = params.number("stop_distance_m");
    radius_ = params.number("robot_radius_m");
    const std::string& name = params.string("laser");
    laser_ = name.empty() ? ctx.resources->first<LaserScan>() : ctx.resources->find<LaserScan>(name);
    if (laser_ == nullptr) fail("no laser resource");
  }
  std::optional<Twist2D> on_step(const BehaviorContext&) noexcept override {
    if (!laser_->has_reading()) return Twist2D{};
    const LaserScan& s = laser_->latest();
    double ahead = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < s.ranges_m.size(); ++i) {
      const double r = s.ranges_m[i];
      if (!(r >= s.range_min_m && r < s.range_max_m)) continue;
      const double a = s.angle_min_rad + static_cast<double>(i) * s.angle_increment_rad;
      const double x = r * std::cos(a), y = r * std::sin(a);
      if (x > 0.0 && std::abs(y) <= radius_) ahead = std::min(ahead, x - radius_);
    }
    if (ahead < stop_) {
      succeed();
      return Twist2D{};
    }
    return Twist2D{speed_, 0.0, 0.0};
  }

 private:
  const LaserResource* laser_ = nullptr;
  double speed_ = 0.0, stop_ = 0.0, radius_ = 0.0;
};

}  // namespace tripodal::testing::test
