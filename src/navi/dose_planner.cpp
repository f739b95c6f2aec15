#include "tripodal/navi/dose_planner.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace tripodal::navi {

void validate(const UvLamp& lamp) {
  const auto check = [](double v, const char* name) {
    if (!std::isfinite(v) || v <= 0.0) {
      throw std::invalid_argument(std::string("UV lamp: ") + name + " must be finite and > 0, got " + std::to_string(v));
    }
  };
  check(lamp.uvc_power_w, "uvc_power_w");
  check(lamp.height_m, "height_m");
  check(lamp.radius_m, "radius_m");
}

double uv_irradiance_w_m2(const UvLamp& lamp, double r_m) noexcept {
  if (!(r_m <= lamp.radius_m)) return 0.0;
  const double d2 = r_m * r_m + lamp.height_m * lamp.height_m;
  return lamp.uvc_power_w * lamp.height_m / (4.0 * std::numbers::pi * d2 * std::sqrt(d2));
}

double lane_dose_j_m2(const UvLamp& lamp, double lateral_m, double speed_m_s) noexcept {
  const double y = std::abs(lateral_m);
  if (!(y < lamp.radius_m) || !(speed_m_s > 0.0)) return 0.0;
  const double a2 = y * y + lamp.height_m * lamp.height_m;
  const double half_chord = std::sqrt(lamp.radius_m * lamp.radius_m - y * y);
  // The integral of h / (x^2 + a^2)^(3/2) over the chord: [x / (a^2 sqrt(x^2 + a^2))] from -L to L.
  const double along = 2.0 * half_chord / (a2 * std::sqrt(half_chord * half_chord + a2));
  return lamp.uvc_power_w * lamp.height_m / (4.0 * std::numbers::pi) * along / speed_m_s;
}

namespace {

// Points across a gap at which the least dose is looked for (the dose is smooth: 1/64 of a gap
// of at most a lit disc's diameter is under a centimetre).
constexpr int kSamples = 64;

// The least dose over one gap `gap_m` wide between two lanes, each at `speed_m_s`, `passes`
// times, counting only these two lanes.
double two_lane_min_dose(const UvLamp& lamp, double gap_m, double speed_m_s, int passes) noexcept {
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kSamples / 2; ++i) {  // symmetric about the middle
    const double y = gap_m * i / kSamples;
    least = std::min(least, lane_dose_j_m2(lamp, y, speed_m_s) + lane_dose_j_m2(lamp, gap_m - y, speed_m_s));
  }
  return passes * least;
}

// The largest lateral distance at which one lane, `passes` times at `speed_m_s`, gives `target`.
double lateral_reach_m(const UvLamp& lamp, double target_j_m2, double speed_m_s, int passes) noexcept {
  if (passes * lane_dose_j_m2(lamp, 0.0, speed_m_s) < target_j_m2) return 0.0;
  double lo = 0.0, hi = lamp.radius_m;  // the dose falls monotonically with the lateral distance
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (lo + hi);
    (passes * lane_dose_j_m2(lamp, mid, speed_m_s) >= target_j_m2 ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

double lanes_min_dose_j_m2(const UvLamp& lamp, double spacing_m, double speed_m_s, int passes) noexcept {
  if (!(spacing_m > 0.0) || !(speed_m_s > 0.0) || passes < 1) return 0.0;
  const int far = static_cast<int>(std::ceil(lamp.radius_m / spacing_m)) + 1;
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kSamples / 2; ++i) {  // between lane 0 and lane 1; symmetric about the middle
    const double y = spacing_m * i / kSamples;
    double sum = 0.0;
    for (int k = -far; k <= far; ++k) sum += lane_dose_j_m2(lamp, y - k * spacing_m, speed_m_s);
    least = std::min(least, sum);
  }
  return passes * least;
}

void validate(const DoseLimits& l) {
  const auto positive = [](double v, const char* name) {
    if (!std::isfinite(v) || v <= 0.0) {
      throw std::invalid_argument(fmt::format("dose limits: {} must be finite and > 0, got {}", name, v));
    }
  };
  positive(l.min_speed_m_s, "min_speed_m_s");
  positive(l.max_speed_m_s, "max_speed_m_s");
  positive(l.min_spacing_m, "min_spacing_m");
  positive(l.max_spacing_m, "max_spacing_m");
  positive(l.spacing_step_m, "spacing_step_m");
  if (l.min_speed_m_s > l.max_speed_m_s) {
    throw std::invalid_argument(
        fmt::format("dose limits: min_speed_m_s {} is above max_speed_m_s {}", l.min_speed_m_s, l.max_speed_m_s));
  }
  if (l.min_spacing_m > l.max_spacing_m) {
    throw std::invalid_argument(
        fmt::format("dose limits: min_spacing_m {} is above max_spacing_m {}", l.min_spacing_m, l.max_spacing_m));
  }
  if (l.max_passes < 1) throw std::invalid_argument(fmt::format("dose limits: max_passes must be >= 1, got {}", l.max_passes));
  if (!std::isfinite(l.tracking_error_m) || l.tracking_error_m < 0.0) {
    throw std::invalid_argument(fmt::format("dose limits: tracking_error_m must be finite and >= 0, got {}", l.tracking_error_m));
  }
}

DosePlan plan_dose(const UvLamp& lamp, double target_j_m2, const DoseLimits& limits) {
  validate(lamp);
  validate(limits);
  if (!std::isfinite(target_j_m2) || target_j_m2 <= 0.0) {
    throw std::invalid_argument(fmt::format("target dose must be finite and > 0 J/m^2, got {}", target_j_m2));
  }
  DosePlan best;
  best.target_j_m2 = target_j_m2;
  const int k0 = std::max(1, static_cast<int>(std::ceil(limits.min_spacing_m / limits.spacing_step_m - 1e-9)));
  const int k1 = static_cast<int>(std::floor(limits.max_spacing_m / limits.spacing_step_m + 1e-9));
  for (int k = k0; k <= k1; ++k) {
    const double s = k * limits.spacing_step_m;
    for (int n = 1; n <= limits.max_passes; ++n) {
      // The dose is inversely proportional to the speed: the fastest speed reaching the target.
      const double at_unit_speed = lanes_min_dose_j_m2(lamp, s + limits.tracking_error_m, 1.0, n);
      const double v = std::min(limits.max_speed_m_s, at_unit_speed / target_j_m2);
      if (v < limits.min_speed_m_s) continue;  // one more pass, then
      const double rate = s * v / n;
      if (rate > best.area_rate_m2_s) {
        best.spacing_m = s;
        best.speed_m_s = v;
        best.passes = n;
        best.area_rate_m2_s = rate;
        best.min_dose_j_m2 = at_unit_speed / v;
      }
      break;  // more passes at this spacing are never faster
    }
  }
  if (best.area_rate_m2_s <= 0.0) {
    const double s = std::max(limits.min_spacing_m, limits.spacing_step_m);
    const double most = lanes_min_dose_j_m2(lamp, s + limits.tracking_error_m, limits.min_speed_m_s, limits.max_passes);
    throw std::invalid_argument(
        fmt::format("target dose {} J/m^2 cannot be reached by the lamp ({} W UVC, {} m above the floor): lanes {} m apart, {} "
                    "passes at the minimum speed {} m/s give at most {:.3g} J/m^2",
                    target_j_m2, lamp.uvc_power_w, lamp.height_m, s, limits.max_passes, limits.min_speed_m_s, most));
  }
  // The wall round may run the tracking error farther out than planned, as the lanes may.
  best.reach_m = std::max(0.0, lateral_reach_m(lamp, target_j_m2, limits.min_speed_m_s, best.passes) - limits.tracking_error_m);
  return best;
}

double lane_speed_m_s(const UvLamp& lamp, const DosePlan& plan, const DoseLimits& limits, double gap_left_m,
                      double gap_right_m) noexcept {
  const auto for_gap = [&](double gap_m) {
    if (!(gap_m < plan.spacing_m)) return plan.speed_m_s;
    // The two lanes bounding the gap alone (a lower bound of the dose), at the speed giving the target.
    const double at_unit_speed = two_lane_min_dose(lamp, gap_m + limits.tracking_error_m, 1.0, plan.passes);
    return std::max(plan.speed_m_s, std::min(limits.max_speed_m_s, at_unit_speed / plan.target_j_m2));
  };
  return std::min(for_gap(gap_left_m), for_gap(gap_right_m));
}

std::vector<double> lane_speeds(const std::vector<Point2D>& path, const UvLamp& lamp, const DosePlan& plan,
                                const DoseLimits& limits, double min_lane_m) {
  // Legs that are not lanes (the wall round's cell chains, short links, touch-ups) have floor on
  // their outer side that no lane doses: the minimum speed, which gives the target out to reach_m.
  std::vector<double> speeds(path.size(), limits.min_speed_m_s);
  struct Lane {
    std::size_t leg;
    Point2D a;
    double ux, uy, length_m;
  };
  std::vector<Lane> lanes;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const double dx = path[i + 1].x_m - path[i].x_m, dy = path[i + 1].y_m - path[i].y_m;
    const double len = std::hypot(dx, dy);
    if (len >= min_lane_m) lanes.push_back({i, path[i], dx / len, dy / len, len});
  }
  for (const Lane& l : lanes) {
    double left = std::numeric_limits<double>::infinity(), right = left;
    for (const Lane& o : lanes) {
      if (std::abs(l.ux * o.uy - l.uy * o.ux) > 1e-3) continue;  // not parallel
      const double ox = o.a.x_m - l.a.x_m, oy = o.a.y_m - l.a.y_m;
      const double lateral = l.ux * oy - l.uy * ox;  // > 0: on the left
      if (std::abs(lateral) < 1e-6) continue;        // the same line (another pass)
      // Overlap along the lane: o's ends projected on l's axis against [0, length].
      const double p0 = l.ux * ox + l.uy * oy;
      const double p1 = p0 + (l.ux * o.ux + l.uy * o.uy) * o.length_m;
      if (std::min(std::max(p0, p1), l.length_m) - std::max(std::min(p0, p1), 0.0) <= 0.0) continue;
      (lateral > 0.0 ? left : right) = std::min(lateral > 0.0 ? left : right, std::abs(lateral));
    }
    speeds[l.leg] = lane_speed_m_s(lamp, plan, limits, left, right);
  }
  if (speeds.size() >= 2) speeds.back() = speeds[speeds.size() - 2];
  return speeds;
}

DosePath dose_path(const std::vector<Point2D>& path, const UvLamp& lamp, const DosePlan& plan, const DoseLimits& limits,
                   double min_lane_m) {
  const std::vector<double> speeds = lane_speeds(path, lamp, plan, limits, min_lane_m);
  DosePath out;
  out.path.reserve(path.size());
  out.speed_m_s.reserve(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    out.path.push_back(path[i]);
    out.speed_m_s.push_back(speeds[i]);
    if (i + 1 == path.size()) break;
    const double dx = path[i + 1].x_m - path[i].x_m, dy = path[i + 1].y_m - path[i].y_m;
    const double len = std::hypot(dx, dy);
    if (len < min_lane_m) continue;
    const double end = std::min(lamp.radius_m, len / 2.0);
    const double slow = std::max(limits.min_speed_m_s, speeds[i] / 2.0);
    out.speed_m_s.back() = slow;
    out.path.push_back({path[i].x_m + dx * end / len, path[i].y_m + dy * end / len});
    out.speed_m_s.push_back(speeds[i]);
    out.path.push_back({path[i + 1].x_m - dx * end / len, path[i + 1].y_m - dy * end / len});
    out.speed_m_s.push_back(slow);
  }
  return out;
}

double path_time_s(const std::vector<Point2D>& path, const std::vector<double>& speeds) noexcept {
  double t = 0.0;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const double v = i < speeds.size() && speeds[i] > 0.0 ? speeds[i] : 0.0;
    const double len = std::hypot(path[i + 1].x_m - path[i].x_m, path[i + 1].y_m - path[i].y_m);
    if (len <= 0.0) continue;
    if (v <= 0.0) return std::numeric_limits<double>::infinity();  // a leg it never covers
    t += len / v;
  }
  return t;
}

}  // namespace tripodal::navi
