// The dose planner (navi/dose_planner.hpp): the closed-form dose of a straight lane against the
// irradiance integrated numerically, plans that reach the target and no faster one, a second
// pass only where one pass at the minimum speed falls short, the refusal, and per-lane speeds.
#include "tripodal/navi/dose_planner.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>
#include <vector>

using namespace tripodal;
using namespace tripodal::navi;
using Catch::Matchers::Contains;

namespace {
// The dose at lateral y of a lane at speed v by the midpoint rule over the lit chord.
double numeric_lane_dose(const UvLamp& lamp, double y, double v) {
  const int n = 200000;
  const double x0 = -lamp.radius_m, dx = 2.0 * lamp.radius_m / n;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double x = x0 + (i + 0.5) * dx;
    sum += uv_irradiance_w_m2(lamp, std::hypot(x, y)) * dx / v;
  }
  return sum;
}
}  // namespace

TEST_CASE("the dose of a straight lane at speed v is the irradiance integrated along the chord", "[navi][dose]") {
  const UvLamp lamp{1.0, 0.05, 0.3};
  for (const double y : {0.0, 0.03, 0.1, 0.2, 0.29}) {
    for (const double v : {0.05, 0.3}) {
      CHECK(lane_dose_j_m2(lamp, y, v) == Approx(numeric_lane_dose(lamp, y, v)).epsilon(1e-3));
    }
  }
  // Under the lane: P R / (2 pi h v sqrt(R^2 + h^2)), within 2 % of an unshielded lamp's P / (2 pi h v).
  const double under = 1.0 * 0.3 / (2.0 * 3.141592653589793 * 0.05 * 0.1 * std::sqrt(0.09 + 0.0025));
  CHECK(lane_dose_j_m2(lamp, 0.0, 0.1) == Approx(under).epsilon(1e-9));
  CHECK(lane_dose_j_m2(lamp, 0.0, 0.1) == Approx(1.0 / (2.0 * 3.141592653589793 * 0.05 * 0.1)).epsilon(0.02));
  CHECK(lane_dose_j_m2(lamp, -0.1, 0.2) == lane_dose_j_m2(lamp, 0.1, 0.2));
  CHECK(lane_dose_j_m2(lamp, 0.3, 0.1) == 0.0);  // the shield's edge
  CHECK(lane_dose_j_m2(lamp, 0.1, 0.0) == 0.0);  // not moving: no lane dose
  CHECK(lane_dose_j_m2(lamp, 0.1, 0.2) == Approx(lane_dose_j_m2(lamp, 0.1, 0.1) / 2.0));
}

TEST_CASE("between lanes the least dose is at the middle for two lanes and counts every lit lane", "[navi][dose]") {
  const UvLamp lamp;
  const double two = lane_dose_j_m2(lamp, 0.1, 0.1) * 2.0;
  // 0.2 m apart: the middle point sees lanes 0.1 m away on both sides and 0.3 m away (dark).
  CHECK(lanes_min_dose_j_m2(lamp, 0.2, 0.1) == Approx(two));
  CHECK(lanes_min_dose_j_m2(lamp, 0.2, 0.1, 2) == Approx(2.0 * two));
  // 0.1 m apart: the lanes 0.15 m and 0.25 m away add to the middle's dose.
  CHECK(lanes_min_dose_j_m2(lamp, 0.1, 0.1) > 2.0 * lane_dose_j_m2(lamp, 0.05, 0.1));
  CHECK(lanes_min_dose_j_m2(lamp, 0.7, 0.1) == 0.0);  // the middle is beyond both lit discs
}

TEST_CASE("the plan reaches the target between lanes and no spacing or speed is faster", "[navi][dose]") {
  const UvLamp lamp;
  const DoseLimits limits;
  const DosePlan p = plan_dose(lamp, 10.0, limits);
  REQUIRE(p.passes == 1);
  CHECK(p.min_dose_j_m2 >= 10.0 * (1.0 - 1e-9));
  CHECK(lanes_min_dose_j_m2(lamp, p.spacing_m + limits.tracking_error_m, p.speed_m_s) == Approx(p.min_dose_j_m2));
  CHECK(p.speed_m_s >= limits.min_speed_m_s);
  CHECK(p.speed_m_s <= limits.max_speed_m_s);
  CHECK(p.area_rate_m2_s == Approx(p.spacing_m * p.speed_m_s));
  // Faster at this spacing falls short, unless capped by the maximum speed.
  if (p.speed_m_s < limits.max_speed_m_s) {
    CHECK(lanes_min_dose_j_m2(lamp, p.spacing_m + limits.tracking_error_m, p.speed_m_s * 1.01) < 10.0);
  }
  // No other spacing reaches the target faster.
  for (double s = 0.05; s <= 0.6 + 1e-9; s += 0.05) {
    const double v = std::min(limits.max_speed_m_s, lanes_min_dose_j_m2(lamp, s + limits.tracking_error_m, 1.0) / 10.0);
    if (v >= limits.min_speed_m_s) CHECK(s * v <= p.area_rate_m2_s * (1.0 + 1e-9));
  }
  // The wall round's lit reach at the minimum speed gives the target, and a centimetre more does not.
  // (with the tracking error to spare).
  CHECK(lane_dose_j_m2(lamp, p.reach_m + limits.tracking_error_m, limits.min_speed_m_s) == Approx(10.0).epsilon(1e-6));
  CHECK(lane_dose_j_m2(lamp, p.reach_m + limits.tracking_error_m + 0.01, limits.min_speed_m_s) < 10.0);
}

TEST_CASE("a higher target slows the lanes or brings them closer", "[navi][dose]") {
  const UvLamp lamp;
  const DosePlan low = plan_dose(lamp, 5.0, {});
  const DosePlan high = plan_dose(lamp, 20.0, {});
  CHECK(high.area_rate_m2_s < low.area_rate_m2_s);
  CHECK(high.min_dose_j_m2 >= 20.0 * (1.0 - 1e-9));
}

TEST_CASE("a second pass where one pass at the minimum speed cannot reach the target", "[navi][dose]") {
  const UvLamp weak{0.05, 0.05, 0.3};
  DoseLimits limits;
  limits.min_spacing_m = limits.max_spacing_m = 0.1;  // one spacing allowed
  const double one_pass = lanes_min_dose_j_m2(weak, 0.1 + limits.tracking_error_m, limits.min_speed_m_s);
  REQUIRE(one_pass < 4.0);
  REQUIRE(2.0 * one_pass >= 4.0);
  const DosePlan p = plan_dose(weak, 4.0, limits);
  CHECK(p.passes == 2);
  CHECK(p.min_dose_j_m2 >= 4.0 * (1.0 - 1e-9));
  CHECK(p.area_rate_m2_s == Approx(0.1 * p.speed_m_s / 2.0));
}

TEST_CASE("a target the lamp cannot reach is refused with the best dose the limits allow", "[navi][dose]") {
  const UvLamp weak{0.001, 0.05, 0.3};
  DoseLimits limits;
  limits.max_passes = 2;
  REQUIRE_THROWS_WITH(plan_dose(weak, 10.0, limits), Contains("target dose 10 J/m^2 cannot be reached") &&
                                                         Contains("2 passes at the minimum speed 0.05 m/s give at most"));
  REQUIRE_THROWS_WITH(plan_dose(UvLamp{}, 0.0, limits), Contains("target dose must be finite and > 0"));
  REQUIRE_THROWS_WITH(plan_dose(UvLamp{0.0, 0.05, 0.3}, 10.0, limits), Contains("uvc_power_w must be finite and > 0"));
  limits.min_speed_m_s = 0.5;
  REQUIRE_THROWS_WITH(plan_dose(UvLamp{}, 10.0, limits), Contains("min_speed_m_s 0.5 is above max_speed_m_s 0.3"));
}

TEST_CASE("a lane between closer neighbours may drive faster, never slower than the plan", "[navi][dose]") {
  const UvLamp lamp;
  const DoseLimits limits;
  const DosePlan p = plan_dose(lamp, 10.0, limits);
  const double inf = std::numeric_limits<double>::infinity();
  CHECK(lane_speed_m_s(lamp, p, limits, p.spacing_m, p.spacing_m) == p.speed_m_s);
  CHECK(lane_speed_m_s(lamp, p, limits, inf, inf) == p.speed_m_s);
  const double close = lane_speed_m_s(lamp, p, limits, 0.05, 0.05);
  CHECK(close >= p.speed_m_s);
  // Both gaps 0.05 m apart: the two lanes bounding each still give the target at that speed.
  if (close < limits.max_speed_m_s) {
    CHECK(2.0 * lane_dose_j_m2(lamp, (0.05 + limits.tracking_error_m) / 2.0, close) == Approx(10.0).epsilon(0.02));
  }
  // The wider gap rules.
  CHECK(lane_speed_m_s(lamp, p, limits, 0.05, p.spacing_m) == p.speed_m_s);
}

TEST_CASE("lane speeds of a path: lanes from their parallel neighbours, short legs at the minimum speed", "[navi][dose]") {
  const UvLamp lamp;
  DoseLimits limits;
  DosePlan p = plan_dose(lamp, 10.0, limits);
  // Four lanes along x, 0.05, 0.05 and the plan's spacing apart, joined by short links.
  const double s = p.spacing_m;
  const std::vector<Point2D> path{{0.0, 0.0}, {2.0, 0.0}, {2.0, 0.05},    {0.0, 0.05},
                                  {0.0, 0.1}, {2.0, 0.1}, {2.0, 0.1 + s}, {0.0, 0.1 + s}};
  const std::vector<double> v = lane_speeds(path, lamp, p, limits);
  REQUIRE(v.size() == path.size());
  const double inf = std::numeric_limits<double>::infinity();
  CHECK(v[0] == p.speed_m_s);                                          // 0.05 one side, nothing the other: the wider gap rules
  CHECK(v[1] == limits.min_speed_m_s);                                 // a short link: the floor beside it has no lane
  CHECK(v[2] == Approx(lane_speed_m_s(lamp, p, limits, 0.05, 0.05)));  // between two close lanes
  CHECK(v[2] > p.speed_m_s);
  CHECK(v[4] == p.speed_m_s);  // 0.05 one side, the spacing the other
  CHECK(v[6] == Approx(lane_speed_m_s(lamp, p, limits, s, inf)));
  CHECK(v[7] == v[6]);
  CHECK(path_time_s(path, v) == Approx(2.0 / v[0] + 0.05 / v[1] + 2.0 / v[2] + 0.05 / v[3] + 2.0 / v[4] + s / v[5] + 2.0 / v[6]));
}

TEST_CASE("a lane's ends are driven at half speed, so its end point gets the middle's dose", "[navi][dose]") {
  const UvLamp lamp;
  const DoseLimits limits;
  const DosePlan p = plan_dose(lamp, 10.0, limits);
  const std::vector<Point2D> lane{{0.0, 0.0}, {2.0, 0.0}};
  const DosePath d = dose_path(lane, lamp, p, limits);
  REQUIRE(d.path.size() == 4);
  CHECK(d.path[1].x_m == Approx(lamp.radius_m));
  CHECK(d.path[2].x_m == Approx(2.0 - lamp.radius_m));
  CHECK(d.speed_m_s[0] == Approx(p.speed_m_s / 2.0));
  CHECK(d.speed_m_s[1] == Approx(p.speed_m_s));
  CHECK(d.speed_m_s[2] == Approx(p.speed_m_s / 2.0));
  // The lamp driven along it, 0.5 mm steps: the dose at the end point and in the middle.
  const auto dose_at = [&](double x) {
    double sum = 0.0;
    for (std::size_t i = 0; i + 1 < d.path.size(); ++i) {
      const double a = d.path[i].x_m, b = d.path[i + 1].x_m;
      for (double s = a + 0.00025; s < b; s += 0.0005) sum += uv_irradiance_w_m2(lamp, std::abs(s - x)) * 0.0005 / d.speed_m_s[i];
    }
    return sum;
  };
  CHECK(dose_at(2.0) == Approx(dose_at(1.0)).epsilon(0.01));
  CHECK(dose_at(1.0) == Approx(lane_dose_j_m2(lamp, 0.0, p.speed_m_s)).epsilon(0.01));
  // Without the slow ends, the end point gets half.
  CHECK(lane_dose_j_m2(lamp, 0.0, p.speed_m_s) / 2.0 < 0.6 * dose_at(2.0));
}
