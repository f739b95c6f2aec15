#include "tripodal/navi/trajectory_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace tripodal::navi {

namespace {

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double p95_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(v.size()))) - 1;
  return v[std::min(k, v.size() - 1)];
}

constexpr double kDeg = 180.0 / std::numbers::pi;

}  // namespace

void PoseErrors::add(const Pose2D& estimate, const Pose2D& reference) {
  m_.push_back(std::hypot(estimate.x_m - reference.x_m, estimate.y_m - reference.y_m));
  rad_.push_back(std::abs(wrap_angle(estimate.theta_rad - reference.theta_rad)));
}

double PoseErrors::mean_m() const { return mean_of(m_); }
double PoseErrors::p95_m() const { return p95_of(m_); }
double PoseErrors::mean_rad() const { return mean_of(rad_); }
double PoseErrors::p95_rad() const { return p95_of(rad_); }

std::string PoseErrors::format(const char* unit) const {
  if (empty()) return std::string("no ") + unit;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.3f m (p95 %.3f), %.2f deg (p95 %.2f), %zu %s", mean_m(), p95_m(), mean_rad() * kDeg,
                p95_rad() * kDeg, count(), unit);
  return buf;
}

StampCheck check_stamps(const std::vector<Time>& stamps) {
  const std::size_t n = stamps.size();
  if (n < 2) return {false, "fewer than two scans"};
  std::vector<double> steps;
  steps.reserve(n - 1);
  std::size_t stalled = 0;
  for (std::size_t i = 1; i < n; ++i) {
    const double d = to_seconds(stamps[i] - stamps[i - 1]);
    if (d <= 0.0) ++stalled;
    else steps.push_back(d);
  }
  char buf[200];
  if (steps.empty()) {
    std::snprintf(buf, sizeof buf, "all %zu scans stamped %.6g s", n, to_seconds(stamps[0]));
    return {false, buf};
  }
  if (static_cast<double>(stalled) > 0.05 * static_cast<double>(n - 1)) {
    std::snprintf(buf, sizeof buf, "%zu of %zu steps between scans do not advance (repeated or backwards stamps)",
                  stalled, n - 1);
    return {false, buf};
  }
  std::vector<double> sorted = steps;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  const double largest = *std::max_element(steps.begin(), steps.end());
  // A hole (fhw pauses 229 s) leaves the stamps usable: pairs across it are refused. A step of
  // more than a day between two scans is a wrap (infinite-corridor's unsigned one).
  if (largest > 100.0 * median && largest > 86400.0) {
    std::snprintf(buf, sizeof buf, "a step of %.6g s between two scans against a median of %.3g s (a wrap)", largest,
                  median);
    return {false, buf};
  }
  return {true, {}};
}

PosePairs consecutive_pairs(std::size_t n) {
  PosePairs p;
  for (std::size_t i = 0; i + 1 < n; ++i) p.emplace_back(i, i + 1);
  return p;
}

PosePairs pairs_by_time(const std::vector<Time>& stamps, double gap_s) {
  PosePairs p;
  if (!check_stamps(stamps).usable) return p;
  const Duration gap = from_seconds(gap_s), most = from_seconds(1.5 * gap_s);
  std::size_t j = 0;
  for (std::size_t i = 0; i < stamps.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < stamps.size() && stamps[j] - stamps[i] < gap) ++j;
    if (j >= stamps.size()) break;
    if (stamps[j] - stamps[i] <= most) p.emplace_back(i, j);
  }
  return p;
}

PosePairs pairs_by_travel(const std::vector<Pose2D>& reference, double gap_m) {
  PosePairs p;
  std::vector<double> path(reference.size(), 0.0);
  for (std::size_t i = 1; i < reference.size(); ++i) {
    path[i] = path[i - 1] + std::hypot(reference[i].x_m - reference[i - 1].x_m, reference[i].y_m - reference[i - 1].y_m);
  }
  std::size_t j = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < reference.size() && path[j] - path[i] < gap_m) ++j;
    if (j >= reference.size()) break;
    if (path[j] - path[i] <= 1.5 * gap_m) p.emplace_back(i, j);
  }
  return p;
}

PoseErrors relative_errors(const std::vector<Pose2D>& estimate, const std::vector<Pose2D>& reference,
                           const PosePairs& pairs) {
  PoseErrors e;
  for (const auto& [i, j] : pairs) {
    e.add(compose(inverse(estimate[i]), estimate[j]), compose(inverse(reference[i]), reference[j]));
  }
  return e;
}

PoseErrors errors_from_start(const std::vector<Pose2D>& estimate, const std::vector<Pose2D>& reference) {
  PoseErrors e;
  if (estimate.empty()) return e;
  const Pose2D e0 = inverse(estimate[0]), r0 = inverse(reference[0]);
  for (std::size_t i = 0; i < estimate.size(); ++i) e.add(compose(e0, estimate[i]), compose(r0, reference[i]));
  return e;
}

PoseErrors errors_aligned(const std::vector<Pose2D>& estimate, const std::vector<Pose2D>& reference) {
  PoseErrors e;
  const std::size_t n = std::min(estimate.size(), reference.size());
  if (n == 0) return e;
  // Closed-form 2D least squares (Horn / Umeyama without scale): centroids, then the angle of the
  // cross-covariance.
  double ex = 0, ey = 0, rx = 0, ry = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ex += estimate[i].x_m;
    ey += estimate[i].y_m;
    rx += reference[i].x_m;
    ry += reference[i].y_m;
  }
  const double k = 1.0 / static_cast<double>(n);
  ex *= k, ey *= k, rx *= k, ry *= k;
  double sc = 0, ss = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double ax = estimate[i].x_m - ex, ay = estimate[i].y_m - ey;
    const double bx = reference[i].x_m - rx, by = reference[i].y_m - ry;
    sc += ax * bx + ay * by;
    ss += ax * by - ay * bx;
  }
  const double phi = (sc == 0.0 && ss == 0.0) ? 0.0 : std::atan2(ss, sc);
  const double c = std::cos(phi), s = std::sin(phi);
  for (std::size_t i = 0; i < n; ++i) {
    const double ax = estimate[i].x_m - ex, ay = estimate[i].y_m - ey;
    const Pose2D moved{rx + c * ax - s * ay, ry + s * ax + c * ay, estimate[i].theta_rad + phi};
    e.add(moved, reference[i]);
  }
  return e;
}

}  // namespace tripodal::navi
