#include "tripodal/sim/ray_caster.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "sim_test_util.hpp"
#include "tripodal/navi/map_io.hpp"

using namespace tripodal;
using namespace tripodal::sim;
using tripodal::sim::test::room_grid;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Reference by brute force: intersect the ray with every solid cell's square (slab method) and
// keep the nearest entry; a ray that leaves the grid first sees nothing.
double brute_force(const SolidMap& m, double gx, double gy, double dx, double dy, double max_t) {
  double best = kInf;
  auto slab = [](double o, double d, double lo, double hi, double& t0, double& t1) {
    if (d == 0.0) return o >= lo && o <= hi;
    double a = (lo - o) / d, b = (hi - o) / d;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    return t0 <= t1;
  };
  for (int y = 0; y < m.height(); ++y) {
    for (int x = 0; x < m.width(); ++x) {
      if (!m.solid(x, y)) continue;
      double t0 = 0.0, t1 = kInf;
      if (slab(gx, dx, x, x + 1.0, t0, t1) && slab(gy, dy, y, y + 1.0, t0, t1)) best = std::min(best, t0);
    }
  }
  // Leaving the grid ends the ray.
  double exit = kInf;
  if (dx > 0) exit = std::min(exit, (m.width() - gx) / dx);
  if (dx < 0) exit = std::min(exit, -gx / dx);
  if (dy > 0) exit = std::min(exit, (m.height() - gy) / dy);
  if (dy < 0) exit = std::min(exit, -gy / dy);
  if (best > exit || best > max_t) return kInf;
  return best;
}

}  // namespace

TEST_CASE("SolidMap: cell-unit coordinates follow the grid's origin and yaw", "[sim][ray]") {
  const navi::OccupancyGrid g(20, 10, 0.1, Pose2D{1.0, -2.0, 0.3}, navi::Occupancy::free);
  const SolidMap m(g);
  for (const navi::Point2D p : {navi::Point2D{1.5, -1.0}, navi::Point2D{2.2, -0.4}, navi::Point2D{0.0, 0.0}}) {
    const navi::Point2D expected = g.to_grid_frame(p);
    const navi::Point2D cells = m.to_cells(p);
    CHECK(cells.x_m == Approx(expected.x_m / 0.1).margin(1e-9));
    CHECK(cells.y_m == Approx(expected.y_m / 0.1).margin(1e-9));
  }
  CHECK(m.to_grid_angle(1.0) == Approx(0.7));
}

TEST_CASE("SolidMap: Amanatides-Woo traversal agrees with brute force on random grids", "[sim][ray]") {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int hits = 0, misses = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int w = 4 + static_cast<int>(u(rng) * 20), h = 4 + static_cast<int>(u(rng) * 20);
    navi::OccupancyGrid g(w, h, 0.1, {}, navi::Occupancy::free);
    const double density = 0.05 + 0.3 * u(rng);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (u(rng) < density) g.set_state({x, y}, navi::Occupancy::occupied);
        else if (u(rng) < 0.1) g.set_state({x, y}, navi::Occupancy::unknown);  // unknown does not stop rays
      }
    }
    const SolidMap m(g);
    for (int ray = 0; ray < 50; ++ray) {
      const double gx = u(rng) * w, gy = u(rng) * h;
      if (m.solid(static_cast<int>(gx), static_cast<int>(gy))) {
        CHECK(m.cast_cells(gx, gy, 1.0, 0.0, 100.0) == 0.0);
        continue;
      }
      const double a = u(rng) * 2.0 * kPi;
      const double dx = std::cos(a), dy = std::sin(a);
      const double max_t = 1.0 + u(rng) * 30.0;
      const double expected = brute_force(m, gx, gy, dx, dy, max_t);
      const double got = m.cast_cells(gx, gy, dx, dy, max_t);
      if (std::isinf(expected)) {
        CHECK(std::isinf(got));
        ++misses;
      } else {
        REQUIRE(got == Approx(expected).margin(1e-9));
        ++hits;
      }
      // The metric entry point gives the same answer in metres.
      const double metres = m.cast(g.from_grid_frame({gx * 0.1, gy * 0.1}), a, max_t * 0.1);
      if (std::isinf(expected)) CHECK(std::isinf(metres));
      else CHECK(metres == Approx(expected * 0.1).margin(1e-9));
    }
  }
  CHECK(hits > 1000);
  CHECK(misses > 50);
}

TEST_CASE("SolidMap: jumps over open floor give the same ranges as the plain traversal", "[sim][ray]") {
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 30 + static_cast<int>(u(rng) * 60), h = 30 + static_cast<int>(u(rng) * 60);
    navi::OccupancyGrid g(w, h, 0.05, {}, navi::Occupancy::free);
    const double density = 0.002 + 0.02 * u(rng);  // sparse: long jumps
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (u(rng) < density) g.set_state({x, y}, navi::Occupancy::occupied);
      }
    }
    SolidMap m(g);
    REQUIRE(m.jumps_valid());
    // Change a few cells: until refresh() rays go cell by cell, after it they jump again.
    for (int k = 0; k < 5; ++k) {
      m.set_solid(static_cast<int>(u(rng) * w), static_cast<int>(u(rng) * h), true);
    }
    for (int phase = 0; phase < 2; ++phase) {
      CHECK(m.jumps_valid() == (phase == 1));
      for (int ray = 0; ray < 40; ++ray) {
        const double gx = u(rng) * w, gy = u(rng) * h;
        if (m.solid(static_cast<int>(gx), static_cast<int>(gy))) continue;
        const double a = u(rng) * 2.0 * kPi;
        const double max_t = 200.0 * u(rng);
        const double expected = brute_force(m, gx, gy, std::cos(a), std::sin(a), max_t);
        const double got = m.cast_cells(gx, gy, std::cos(a), std::sin(a), max_t);
        if (std::isinf(expected)) REQUIRE(std::isinf(got));
        else REQUIRE(got == Approx(expected).margin(1e-9));
        ++checked;
      }
      m.refresh();
    }
  }
  CHECK(checked > 3000);
  // A grid without any solid cell: nothing is ever hit.
  const SolidMap empty(navi::OccupancyGrid(50, 50, 0.05, {}, navi::Occupancy::free));
  CHECK(std::isinf(empty.cast_cells(25.5, 25.5, 0.6, 0.8, 1000.0)));
}

TEST_CASE("SolidMap: axis-aligned rays along cell boundaries and from outside the grid", "[sim][ray]") {
  const SolidMap m(room_grid(10, 10, 0.1));
  // From the middle of cell (5, 5) straight at each wall: the walls' inner faces are at 1 and 9.
  CHECK(m.cast_cells(5.5, 5.5, 1.0, 0.0, 100.0) == Approx(3.5));
  CHECK(m.cast_cells(5.5, 5.5, -1.0, 0.0, 100.0) == Approx(4.5));
  CHECK(m.cast_cells(5.5, 5.5, 0.0, 1.0, 100.0) == Approx(3.5));
  CHECK(m.cast_cells(5.5, 5.5, 0.0, -1.0, 100.0) == Approx(4.5));
  // Exactly on a cell boundary.
  CHECK(m.cast_cells(5.0, 5.0, 1.0, 0.0, 100.0) == Approx(4.0));
  // Beyond the maximum range: nothing.
  CHECK(std::isinf(m.cast_cells(5.5, 5.5, 1.0, 0.0, 3.0)));
  // From outside the grid: nothing; from inside a wall: 0.
  CHECK(std::isinf(m.cast_cells(-1.0, 5.5, 1.0, 0.0, 100.0)));
  CHECK(m.cast_cells(0.5, 5.5, 1.0, 0.0, 100.0) == 0.0);
}

TEST_CASE("LaserModel: known distances in a box room, with the mounting offset and heading", "[sim][ray][laser]") {
  // 81 x 61 cells of 5 cm: inner faces at x = 0.05 and 4.0, y = 0.05 and 3.0.
  const SolidMap m(room_grid(81, 61, 0.05));
  LaserConfig c = LaserConfig::rplidar_a1();
  c.noise_stddev_m = 0.0;
  c.beams = 1440;  // a beam every 0.25 degrees: 0, 90, 180, 270 degrees are beams
  LaserModel laser(c, 1);
  LaserScan scan;
  laser.scan(m, {2.0, 1.5, 0.0}, time_from_ns(5), scan);
  REQUIRE(scan.ranges_m.size() == 1440);
  CHECK(scan.stamp == time_from_ns(5));
  // Beam i is at -pi + i * 0.25 deg: 720 -> 0, 1080 -> +90, 0 -> 180, 360 -> -90.
  CHECK(scan.ranges_m[720] == Approx(2.0).margin(1e-5));
  CHECK(scan.ranges_m[1080] == Approx(1.5).margin(1e-5));
  CHECK(scan.ranges_m[0] == Approx(1.95).margin(1e-5));
  CHECK(scan.ranges_m[360] == Approx(1.45).margin(1e-5));
  // 45 degrees: the top wall (1.5 m up) comes before the right one (2 m across).
  CHECK(scan.ranges_m[900] == Approx(1.5 * std::sqrt(2.0)).margin(1e-5));

  // Facing +y, and a scanner mounted 0.1 m ahead of the base centre.
  c.mount = {0.1, 0.0, 0.0};
  LaserModel mounted(c, 1);
  mounted.scan(m, {2.0, 1.5, kPi / 2.0}, Time{}, scan);
  CHECK(scan.ranges_m[720] == Approx(1.4).margin(1e-5));   // ahead: +y, from y = 1.6
  CHECK(scan.ranges_m[1080] == Approx(1.95).margin(1e-5)); // left: -x
  CHECK(scan.ranges_m[360] == Approx(2.0).margin(1e-5));   // right: +x
}

TEST_CASE("LaserModel: scan fields match the configured sensor", "[sim][laser]") {
  const SolidMap m(room_grid(81, 61, 0.05));
  LaserScan scan;
  SECTION("RPLIDAR A1") {
    const LaserConfig c = LaserConfig::rplidar_a1();
    LaserModel laser(c, 3);
    laser.scan(m, {2.0, 1.5, 0.3}, Time{}, scan);
    CHECK(scan.ranges_m.size() == 1450);
    CHECK(scan.angle_min_rad == Approx(-kPi));
    CHECK(scan.angle_increment_rad == Approx(2.0 * kPi / 1450.0));
    CHECK(scan.angle_max_rad == Approx(-kPi + 1449.0 * 2.0 * kPi / 1450.0));
    CHECK(scan.angle_max_rad < kPi);
    CHECK(scan.range_min_m == 0.15);
    CHECK(scan.range_max_m == 12.0);
    CHECK(scan.scan_time_s == Approx(1.0 / 5.5));
    CHECK(scan.time_increment_s == Approx(1.0 / 5.5 / 1450.0));
    CHECK(scan.intensities.empty());
    for (float r : scan.ranges_m) {
      REQUIRE(std::isfinite(r));  // a closed room: every beam returns
      REQUIRE(r >= 0.15f);
      REQUIRE(r <= 12.0f);
    }
  }
  SECTION("SICK 180") {
    const LaserConfig c = LaserConfig::sick_180();
    LaserModel laser(c, 3);
    laser.scan(m, {2.0, 1.5, 0.0}, Time{}, scan);
    CHECK(scan.ranges_m.size() == 361);
    CHECK(scan.angle_min_rad == Approx(-kPi / 2));
    CHECK(scan.angle_max_rad == Approx(kPi / 2));
    CHECK(scan.angle_increment_rad == Approx(kPi / 360.0));
    CHECK(scan.range_max_m == 30.0);
    CHECK(scan.scan_time_s == Approx(1.0 / 37.5));
    CHECK(scan.ranges_m[180] == Approx(2.0).margin(0.05));  // straight ahead, 1 cm noise
  }
}

TEST_CASE("LaserModel: seeded Gaussian range noise, range limits", "[sim][laser]") {
  const SolidMap m(room_grid(81, 61, 0.05));
  LaserConfig c = LaserConfig::rplidar_a1();
  c.noise_stddev_m = 0.02;
  LaserScan exact, a, b, other;
  LaserModel(c, 1).scan_exact(m, {2.0, 1.5, 0.0}, Time{}, exact);
  LaserModel la(c, 9), lb(c, 9), lo(c, 10);
  la.scan(m, {2.0, 1.5, 0.0}, Time{}, a);
  lb.scan(m, {2.0, 1.5, 0.0}, Time{}, b);
  lo.scan(m, {2.0, 1.5, 0.0}, Time{}, other);
  CHECK(a == b);
  CHECK_FALSE(a == other);
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < a.ranges_m.size(); ++i) {
    const double e = static_cast<double>(a.ranges_m[i]) - exact.ranges_m[i];
    sum += e;
    sum2 += e * e;
  }
  const double n = static_cast<double>(a.ranges_m.size());
  CHECK(sum / n == Approx(0.0).margin(0.003));
  CHECK(std::sqrt(sum2 / n) == Approx(0.02).margin(0.003));

  // Nearer than range_min: no return; farther than range_max: no return.
  LaserConfig near = c;
  near.noise_stddev_m = 0.0;
  near.range_min_m = 1.6;
  near.range_max_m = 1.9;
  LaserModel ln(near, 1);
  ln.scan(m, {2.0, 1.5, 0.0}, Time{}, a);
  const std::size_t ahead = 725, left = 1087;  // 0 and ~90 degrees of 1450 beams
  CHECK(std::isinf(a.ranges_m[ahead]));  // 2.0 > range_max
  LaserScan s2;
  ln.scan(m, {2.0, 1.2, 0.0}, Time{}, s2);
  CHECK(s2.ranges_m[left] == Approx(1.8).margin(2e-3));   // within [1.6, 1.9]
  ln.scan(m, {2.0, 1.5, 0.0}, Time{}, s2);
  CHECK(std::isinf(s2.ranges_m[left]));  // about 1.5 < range_min
}

TEST_CASE("LaserModel: on the demo workspace, jumping rays see what cell-by-cell rays see", "[sim][ray][laser]") {
  const navi::OccupancyGrid grid =
      navi::load_map(std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace_map.yaml").grid;
  const SolidMap jumping(grid);
  SolidMap plain(grid);
  plain.set_solid(0, 0, plain.solid(0, 0));  // invalidates the jumps: every cell is visited
  REQUIRE(jumping.jumps_valid());
  REQUIRE_FALSE(plain.jumps_valid());
  LaserConfig c = LaserConfig::rplidar_a1();
  c.noise_stddev_m = 0.0;
  LaserModel laser(c, 1);
  LaserScan a, b;
  int poses = 0;
  for (double y = 1.0; y < 31.5; y += 2.3) {
    for (double x = 0.7; x < 9.8; x += 1.3) {
      if (jumping.disc_overlaps({x, y}, 0.2)) continue;
      const Pose2D p{x, y, 0.1 * poses};
      laser.scan_exact(jumping, p, Time{}, a);
      laser.scan_exact(plain, p, Time{}, b);
      for (std::size_t i = 0; i < a.ranges_m.size(); ++i) {
        if (std::isinf(b.ranges_m[i])) REQUIRE(std::isinf(a.ranges_m[i]));
        else REQUIRE(a.ranges_m[i] == Approx(b.ranges_m[i]).margin(1e-5));
      }
      ++poses;
    }
  }
  CHECK(poses > 60);
}
