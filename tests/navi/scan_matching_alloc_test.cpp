// Proves that the scan-matching localizer allocates nothing per scan once started: it runs in the
// sequencing loop on every scan, next to the real-time reactive loop.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <vector>

#include "../support/counting_new.hpp"
#include "tripodal/navi/scan_matching_localizer.hpp"
#include "tripodal/sim/ray_caster.hpp"

using namespace tripodal;
using namespace tripodal::navi;

TEST_CASE("ScanMatchingLocalizer: steady-state scans allocate nothing", "[navi][scan_matching][alloc]") {
  OccupancyGrid g(160, 120, 0.05, {}, Occupancy::free);
  for (int x = 0; x < 160; ++x) {
    g.set_state({x, 0}, Occupancy::occupied);
    g.set_state({x, 119}, Occupancy::occupied);
  }
  for (int y = 0; y < 120; ++y) {
    g.set_state({0, y}, Occupancy::occupied);
    g.set_state({159, y}, Occupancy::occupied);
    if (y > 40) g.set_state({90, y}, Occupancy::occupied);
  }
  const sim::SolidMap solid(g);
  // the simulator's 1,450-beam scanner, along a straight drive with odometry 3 % short
  std::vector<LaserScan> scans;
  std::vector<Pose2D> truth, odom;
  for (int k = 0; k < 60; ++k) {
    const Pose2D p{1.5 + 0.05 * k, 1.5 + 0.02 * k, 0.01 * k};
    LaserScan s;
    s.angle_min_rad = -std::numbers::pi;
    s.angle_increment_rad = 2 * std::numbers::pi / 1450;
    s.angle_max_rad = s.angle_min_rad + 1449 * s.angle_increment_rad;
    s.range_min_m = 0.15;
    s.range_max_m = 12.0;
    s.ranges_m.resize(1450);
    for (std::size_t i = 0; i < s.ranges_m.size(); ++i) {
      const double r = solid.cast({p.x_m, p.y_m}, p.theta_rad + s.angle_min_rad + static_cast<double>(i) * s.angle_increment_rad, 12.0);
      s.ranges_m[i] = static_cast<float>(std::isfinite(r) ? r : 12.0);
    }
    if (k >= 30 && k < 33) {
      for (float& r : s.ranges_m) r = 0.01f;  // blinded for fewer scans than make it lost
    }
    scans.push_back(s);
    truth.push_back(p);
    odom.push_back({0.97 * p.x_m, 0.97 * p.y_m, p.theta_rad});
  }
  ScanMatchingLocalizerOptions o;
  o.initial_pose = truth[0];
  CScanMatchingLocalizer loc(o);
  loc.set_map(g);
  std::vector<ModuleEvent> events;
  events.reserve(8);
  loc.step(scans[0], odom[0], Time{}, events);  // the first scan posts localizer.ok
  REQUIRE(events.size() == 1);
  const std::size_t before = tripodal::test::allocations();
  for (std::size_t k = 1; k < scans.size(); ++k) loc.step(scans[k], odom[k], Time{}, events);
  CHECK(tripodal::test::allocations() == before);
  CHECK(events.size() == 1);
  CHECK(std::hypot(loc.estimate().x_m - truth.back().x_m, loc.estimate().y_m - truth.back().y_m) < 0.05);
}
