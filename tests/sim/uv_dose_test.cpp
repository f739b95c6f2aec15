// The UV lamp's dose model (sim/uv_dose.hpp) against the closed forms of its physics: the
// inverse-square irradiance with the floor's cosine, and the dose of a straight pass.
#include "tripodal/sim/uv_dose.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>

using namespace tripodal;
using namespace tripodal::sim;
using namespace std::chrono_literals;
using Catch::Matchers::Contains;

namespace {
navi::OccupancyGrid floor_grid() { return navi::OccupancyGrid(200, 100, 0.01, Pose2D{-1.0, -0.5, 0.0}); }  // 2 m x 1 m
}  // namespace

TEST_CASE("irradiance falls with the cube of the distance to the lamp and stops at the lit disc", "[sim][uv]") {
  const UvLamp lamp{2.0, 0.05, 0.3};
  // Under the lamp: P / (4 pi h^2).
  CHECK(uv_irradiance_w_m2(lamp, 0.0) == Approx(2.0 / (4.0 * std::numbers::pi * 0.05 * 0.05)));
  // At r = h: d = h sqrt(2), cos = 1/sqrt(2): E(0) / (2 sqrt(2)).
  CHECK(uv_irradiance_w_m2(lamp, 0.05) == Approx(uv_irradiance_w_m2(lamp, 0.0) / (2.0 * std::sqrt(2.0))));
  CHECK(uv_irradiance_w_m2(lamp, 0.3) > 0.0);
  CHECK(uv_irradiance_w_m2(lamp, 0.3001) == 0.0);
  CHECK(uv_irradiance_w_m2(lamp, std::nan("")) == 0.0);
}

TEST_CASE("a straight pass doses the floor under its centre line as the line integral says", "[sim][uv]") {
  const UvLamp lamp{1.0, 0.05, 0.3};
  UvDoseMap dose(floor_grid(), lamp);
  // The lamp crosses the grid along y = 0.005 (a row of cell centres) at 0.3 m/s, 1 ms steps.
  const double v = 0.3;
  for (int i = 0; i <= 6000; ++i) dose.expose({-0.9 + v * 0.001 * i, 0.005}, 1ms);
  CHECK(to_seconds(dose.lamp_on()) == Approx(6.001));
  // Under the centre line: the integral of E along x over the disc, divided by the speed:
  // P R / (2 pi h v sqrt(R^2 + h^2)).
  const double R = lamp.radius_m, h = lamp.height_m;
  const double centre = lamp.uvc_power_w * R / (2.0 * std::numbers::pi * h * v * std::sqrt(R * R + h * h));
  CHECK(dose.dose_at_j_m2({0.0, 0.005}) == Approx(centre).epsilon(0.01));
  // 0.1 m aside, a chord of the disc: the same integral with h^2 + y^2 under the root.
  const double y = 0.1, c = std::sqrt(R * R - y * y);
  const double aside = lamp.uvc_power_w * h * c / (2.0 * std::numbers::pi * v * (y * y + h * h) * std::sqrt(c * c + y * y + h * h));
  CHECK(dose.dose_at_j_m2({0.0, 0.105}) == Approx(aside).epsilon(0.01));
  // The dose planner's closed form (navi/dose_planner.hpp) is what the simulator counts.
  CHECK(dose.dose_at_j_m2({0.0, 0.105}) == Approx(navi::lane_dose_j_m2(lamp, y, v)).epsilon(0.01));
  CHECK(dose.dose_at_j_m2({0.0, 0.005}) == Approx(navi::lane_dose_j_m2(lamp, 0.0, v)).epsilon(0.01));
  // Outside the lit band and outside the grid: nothing.
  CHECK(dose.dose_at_j_m2({0.0, -0.4}) == 0.0);
  CHECK(dose.dose_at_j_m2({5.0, 0.0}) == 0.0);
}

TEST_CASE("no dose without time, and a lamp without power or height is refused by name", "[sim][uv]") {
  UvDoseMap dose(floor_grid(), UvLamp{});
  dose.expose({0.0, 0.0}, 0ms);
  dose.expose({0.0, 0.0}, -5ms);
  dose.expose({std::nan(""), 0.0}, 5ms);
  CHECK(dose.dose_at_j_m2({0.0, 0.0}) == 0.0);
  CHECK(dose.lamp_on() == 0ms);
  CHECK_THROWS_WITH(UvDoseMap(floor_grid(), UvLamp{0.0, 0.05, 0.3}), Contains("uvc_power_w must be finite and > 0"));
  CHECK_THROWS_WITH(UvDoseMap(floor_grid(), UvLamp{1.0, -0.05, 0.3}), Contains("height_m must be finite and > 0"));
  CHECK_THROWS_WITH(UvDoseMap(floor_grid(), UvLamp{1.0, 0.05, std::nan("")}), Contains("radius_m must be finite and > 0"));
}
