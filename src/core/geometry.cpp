#include "tripodal/core/geometry.hpp"

#include <cmath>
#include <numbers>
#include <utility>

namespace tripodal {

double wrap_angle(double angle_rad) noexcept {
  constexpr double kPi = std::numbers::pi;
  // fmod keeps the cost constant for large angles (a loop of +-2 pi steps would not). Most
  // angles are already within one turn, where fmod returns its argument exactly: skipping the
  // call there gives the same result for a fraction of the cost (every behavior wraps angles).
  double a = angle_rad + kPi;
  if (a >= 0.0 && a < 2.0 * kPi) return a - kPi;
  a = std::fmod(a, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  return a - kPi;
}

Pose2D compose(const Pose2D& a_from_b, const Pose2D& b_from_c) noexcept {
  const Point2D p = transform(a_from_b, {b_from_c.x_m, b_from_c.y_m});
  return {p.x_m, p.y_m, wrap_angle(a_from_b.theta_rad + b_from_c.theta_rad)};
}

Pose2D inverse(const Pose2D& a_from_b) noexcept {
  const double c = std::cos(a_from_b.theta_rad);
  const double s = std::sin(a_from_b.theta_rad);
  return {-c * a_from_b.x_m - s * a_from_b.y_m, s * a_from_b.x_m - c * a_from_b.y_m, wrap_angle(-a_from_b.theta_rad)};
}

Point2D transform(const Pose2D& a_from_b, Point2D p) noexcept {
  const double c = std::cos(a_from_b.theta_rad);
  const double s = std::sin(a_from_b.theta_rad);
  return {a_from_b.x_m + c * p.x_m - s * p.y_m, a_from_b.y_m + s * p.x_m + c * p.y_m};
}

std::vector<Point2D> douglas_peucker(std::span<const Point2D> polyline, double tolerance_m) {
  if (polyline.size() < 3) return {polyline.begin(), polyline.end()};
  std::vector<char> keep(polyline.size(), 0);
  keep.front() = keep.back() = 1;
  std::vector<std::pair<std::size_t, std::size_t>> pending{{0, polyline.size() - 1}};
  while (!pending.empty()) {
    const auto [i, j] = pending.back();
    pending.pop_back();
    if (j <= i + 1) continue;
    const Point2D& a = polyline[i];
    const double dx = polyline[j].x_m - a.x_m;
    const double dy = polyline[j].y_m - a.y_m;
    const double len = std::hypot(dx, dy);
    double worst = -1.0;
    std::size_t at = i;
    for (std::size_t k = i + 1; k < j; ++k) {
      const double ex = polyline[k].x_m - a.x_m;
      const double ey = polyline[k].y_m - a.y_m;
      // Distance to the chord's line; to its start when the chord closes on itself.
      const double d = len > 0.0 ? std::abs(ex * dy - ey * dx) / len : std::hypot(ex, ey);
      if (d > worst) {
        worst = d;
        at = k;
      }
    }
    if (worst > tolerance_m) {
      keep[at] = 1;
      pending.emplace_back(i, at);
      pending.emplace_back(at, j);
    }
  }
  std::vector<Point2D> out;
  for (std::size_t k = 0; k < polyline.size(); ++k) {
    if (keep[k] != 0) out.push_back(polyline[k]);
  }
  return out;
}

}  // namespace tripodal
