// The shared planar geometry: angle wrapping, SE(2) composition and inversion, Douglas-Peucker.
#include "tripodal/core/geometry.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "tripodal/navi/occupancy_grid.hpp"

using namespace tripodal;

namespace {
constexpr double kPi = std::numbers::pi;

bool near(const Pose2D& a, const Pose2D& b, double eps = 1e-12) {
  return std::abs(a.x_m - b.x_m) < eps && std::abs(a.y_m - b.y_m) < eps &&
         std::abs(wrap_angle(a.theta_rad - b.theta_rad)) < eps;
}
}  // namespace

TEST_CASE("wrap_angle maps every angle into -pi (included) to pi (excluded)") {
  CHECK(wrap_angle(0.0) == 0.0);
  CHECK(wrap_angle(kPi) == Approx(-kPi));
  CHECK(wrap_angle(-kPi) == Approx(-kPi));
  CHECK(wrap_angle(3.0 * kPi / 2.0) == Approx(-kPi / 2.0));
  CHECK(wrap_angle(-3.0 * kPi / 2.0) == Approx(kPi / 2.0));
  CHECK(wrap_angle(1e6) == Approx(std::remainder(1e6, 2.0 * kPi)).margin(1e-9));
  CHECK(std::isnan(wrap_angle(std::nan(""))));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> any(-100.0, 100.0);
  for (int i = 0; i < 1000; ++i) {
    const double a = any(rng);
    const double w = wrap_angle(a);
    REQUIRE(w >= -kPi);
    REQUIRE(w < kPi);
    // the same direction
    REQUIRE(std::cos(w) == Approx(std::cos(a)).margin(1e-9));
    REQUIRE(std::sin(w) == Approx(std::sin(a)).margin(1e-9));
  }
}

TEST_CASE("compose chains frames: map_from_odom * odom_from_base = map_from_base") {
  const Pose2D map_from_odom{1.0, 2.0, kPi / 2.0};
  const Pose2D odom_from_base{3.0, 0.0, kPi / 2.0};
  // 3 m along odom's x, which is map's y; headings add.
  CHECK(near(compose(map_from_odom, odom_from_base), Pose2D{1.0, 5.0, -kPi}));
  CHECK(near(compose(Pose2D{}, odom_from_base), odom_from_base));
  CHECK(near(compose(odom_from_base, Pose2D{}), odom_from_base));
  const Point2D p = transform(map_from_odom, {1.0, 0.0});
  CHECK(p.x_m == Approx(1.0).margin(1e-12));
  CHECK(p.y_m == Approx(3.0));
}

TEST_CASE("inverse undoes compose and is associative with it") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> xy(-10.0, 10.0);
  std::uniform_real_distribution<double> th(-4.0, 4.0);
  for (int i = 0; i < 200; ++i) {
    const Pose2D a{xy(rng), xy(rng), th(rng)};
    const Pose2D b{xy(rng), xy(rng), th(rng)};
    const Pose2D c{xy(rng), xy(rng), th(rng)};
    REQUIRE(near(compose(a, inverse(a)), Pose2D{}, 1e-9));
    REQUIRE(near(compose(inverse(a), a), Pose2D{}, 1e-9));
    REQUIRE(near(compose(compose(a, b), c), compose(a, compose(b, c)), 1e-9));
    REQUIRE(near(inverse(compose(a, b)), compose(inverse(b), inverse(a)), 1e-9));
  }
}

TEST_CASE("douglas_peucker keeps the ends and the corner of an L") {
  // An L with points along both legs: only the ends and the corner stay.
  std::vector<Point2D> l;
  for (int i = 0; i <= 10; ++i) l.push_back({0.1 * i, 0.0});
  for (int i = 1; i <= 10; ++i) l.push_back({1.0, 0.1 * i});
  const auto s = douglas_peucker(l, 0.01);
  REQUIRE(s.size() == 3);
  CHECK(s[0] == Point2D{0.0, 0.0});
  CHECK(s[1] == l[10]);
  CHECK(s[2] == l.back());
}

TEST_CASE("douglas_peucker drops deviations within the tolerance and keeps larger ones") {
  const std::vector<Point2D> zig{{0.0, 0.0}, {1.0, 0.04}, {2.0, -0.04}, {3.0, 0.0}};
  CHECK(douglas_peucker(zig, 0.05).size() == 2);
  CHECK(douglas_peucker(zig, 0.03).size() == 4);
  // Fewer than three points come back as they are.
  CHECK(douglas_peucker(std::vector<Point2D>{}, 0.1).empty());
  CHECK(douglas_peucker(std::vector<Point2D>{{1.0, 2.0}}, 0.1).size() == 1);
  // A closed loop (first == last) measures distances to the start point and keeps the far side.
  const std::vector<Point2D> loop{{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}, {0.0, 0.0}};
  const auto s = douglas_peucker(loop, 0.1);
  CHECK(s.front() == loop.front());
  CHECK(s.back() == loop.back());
  CHECK(std::find(s.begin(), s.end(), Point2D{1.0, 1.0}) != s.end());
}

TEST_CASE("douglas_peucker handles a long trajectory without recursion") {
  std::vector<Point2D> spiral;
  for (int i = 0; i < 200000; ++i) {
    const double t = 0.001 * i;
    spiral.push_back({t * std::cos(t), t * std::sin(t)});
  }
  const auto s = douglas_peucker(spiral, 0.001);
  CHECK(s.size() > 2);
  CHECK(s.size() < spiral.size());
}

TEST_CASE("navi::Point2D is the shared Point2D") {
  const navi::Point2D p{1.0, 2.0};
  const Point2D& q = p;
  CHECK(q == Point2D{1.0, 2.0});
}
