#include "tripodal/sim/ray_caster.hpp"

#include "tripodal/navi/distance_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tripodal::sim {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
// floor() for values well inside int's range, without a libm call (x86-64's baseline has no
// SSE4.1 rounding instruction).
inline int floor_int(double v) noexcept {
  const int i = static_cast<int>(v);
  return v < i ? i - 1 : i;
}
// Shorter jumps cost more (a restart of the traversal) than the cell steps they save.
constexpr float kMinJump = 2.0F;
}  // namespace

SolidMap::SolidMap(const navi::OccupancyGrid& grid)
    : width_(grid.width()),
      height_(grid.height()),
      resolution_m_(grid.resolution_m()),
      origin_(grid.origin()),
      cos_yaw_(std::cos(grid.origin().theta_rad)),
      sin_yaw_(std::sin(grid.origin().theta_rad)),
      cells_(grid.size(), 0) {
  for (std::size_t i = 0; i < grid.size(); ++i) cells_[i] = grid.state(i) == navi::Occupancy::occupied ? 1 : 0;
  refresh();
}

void SolidMap::refresh() {
  std::vector<bool> obstacle(cells_.size());
  for (std::size_t i = 0; i < cells_.size(); ++i) obstacle[i] = cells_[i] != 0;
  // Centre-to-centre distances D in cell units. Any point of this cell is within sqrt(2)/2 of its
  // centre, any point of a solid cell within sqrt(2)/2 of that one's: a jump shorter than
  // D - sqrt(2) from anywhere in the cell cannot reach a solid cell; D - 1.5 leaves a margin.
  const navi::DistanceField field(width_, height_, 1.0, obstacle, false);
  jump_.resize(cells_.size());
  for (std::size_t i = 0; i < cells_.size(); ++i) {
    const float d = field.distances_m()[i];
    jump_[i] = d > 1.5F ? d - 1.5F : 0.0F;
  }
  jumps_valid_ = true;
}

navi::Point2D SolidMap::to_cells(navi::Point2D p) const noexcept {
  const double dx = p.x_m - origin_.x_m;
  const double dy = p.y_m - origin_.y_m;
  return {(cos_yaw_ * dx + sin_yaw_ * dy) / resolution_m_, (-sin_yaw_ * dx + cos_yaw_ * dy) / resolution_m_};
}

double SolidMap::cast(navi::Point2D from, double angle_rad, double max_range_m) const noexcept {
  const navi::Point2D g = to_cells(from);
  const double a = to_grid_angle(angle_rad);
  const double t = cast_cells(g.x_m, g.y_m, std::cos(a), std::sin(a), max_range_m / resolution_m_);
  return t * resolution_m_;
}

double SolidMap::cast_cells(double gx, double gy, double dx, double dy, double max_t) const noexcept {
  // Amanatides & Woo: visit the cells the ray crosses in order, stepping across whichever cell
  // boundary (vertical or horizontal) the ray reaches first; t is the ray parameter in cells.
  const int step_x = dx > 0.0 ? 1 : -1;
  const int step_y = dy > 0.0 ? 1 : -1;
  const double t_delta_x = dx != 0.0 ? 1.0 / std::abs(dx) : kInf;
  const double t_delta_y = dy != 0.0 ? 1.0 / std::abs(dy) : kInf;
  int ix = 0, iy = 0;
  double t_max_x = kInf, t_max_y = kInf;
  // (Re)starts the traversal at ray parameter t0: the cell there and the next boundary crossings.
  auto start_at = [&](double t0) noexcept {
    const double px = gx + dx * t0, py = gy + dy * t0;
    ix = floor_int(px);
    iy = floor_int(py);
    t_max_x = dx > 0.0 ? t0 + (ix + 1.0 - px) * t_delta_x : dx < 0.0 ? t0 + (px - ix) * t_delta_x : kInf;
    t_max_y = dy > 0.0 ? t0 + (iy + 1.0 - py) * t_delta_y : dy < 0.0 ? t0 + (py - iy) * t_delta_y : kInf;
  };
  // Far outside (or not a number): outside the grid, and beyond what the integer cells can hold.
  if (!(std::abs(gx) < 1e8 && std::abs(gy) < 1e8)) return kInf;
  start_at(0.0);
  if (!contains(ix, iy)) return kInf;
  if (solid(ix, iy)) return 0.0;
  const std::size_t w = static_cast<std::size_t>(width_);
  const bool jumps = jumps_valid_;
  double t = 0.0;  // where the ray is: inside cell (ix, iy)
  for (;;) {
    const std::size_t here = static_cast<std::size_t>(iy) * w + static_cast<std::size_t>(ix);
    if (jumps && jump_[here] >= kMinJump) {
      // Open floor: no solid cell within jump_ of anywhere in this cell. The grid is convex, so a
      // ray that jumps out of it never comes back.
      t += jump_[here];
      if (!(t <= max_t) || std::isinf(t)) return kInf;
      start_at(t);
      if (!contains(ix, iy)) return kInf;
      continue;
    }
    if (t_max_x < t_max_y) {
      t = t_max_x;
      ix += step_x;
      t_max_x += t_delta_x;
      if (ix < 0 || ix >= width_) return kInf;
    } else {
      t = t_max_y;
      iy += step_y;
      t_max_y += t_delta_y;
      if (iy < 0 || iy >= height_) return kInf;
    }
    if (t > max_t) return kInf;
    if (cells_[static_cast<std::size_t>(iy) * w + static_cast<std::size_t>(ix)] != 0) return t;
  }
}

bool SolidMap::disc_overlaps(navi::Point2D center, double radius_m) const noexcept {
  const navi::Point2D g = to_cells(center);
  const double r = radius_m / resolution_m_;
  const int x0 = static_cast<int>(std::floor(g.x_m - r));
  const int x1 = static_cast<int>(std::floor(g.x_m + r));
  const int y0 = static_cast<int>(std::floor(g.y_m - r));
  const int y1 = static_cast<int>(std::floor(g.y_m + r));
  if (x0 < 0 || y0 < 0 || x1 >= width_ || y1 >= height_) return true;
  const double r2 = r * r;
  for (int y = y0; y <= y1; ++y) {
    const double ny = std::clamp(g.y_m, static_cast<double>(y), y + 1.0) - g.y_m;
    const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_);
    for (int x = x0; x <= x1; ++x) {
      if (cells_[row + static_cast<std::size_t>(x)] == 0) continue;
      const double nx = std::clamp(g.x_m, static_cast<double>(x), x + 1.0) - g.x_m;
      if (nx * nx + ny * ny < r2) return true;
    }
  }
  return false;
}

LaserModel::LaserModel(const LaserConfig& config, std::uint64_t seed)
    : config_(config), rng_(seed), noise_(0.0, config.noise_stddev_m > 0.0 ? config.noise_stddev_m : 1.0) {
  const double inc = config_.angle_increment();
  cos_.resize(config_.beams);
  sin_.resize(config_.beams);
  for (std::uint32_t i = 0; i < config_.beams; ++i) {
    const double a = config_.angle_min_rad + inc * i;
    cos_[i] = std::cos(a);
    sin_[i] = std::sin(a);
  }
}

void LaserModel::fill(const SolidMap& world, const Pose2D& map_from_base, Time stamp, LaserScan& scan) const noexcept {
  const std::uint32_t n = config_.beams;
  scan.stamp = stamp;
  scan.angle_min_rad = config_.angle_min_rad;
  scan.angle_increment_rad = config_.angle_increment();
  scan.angle_max_rad = config_.last_beam_angle();
  scan.scan_time_s = config_.rate_hz > 0.0 ? 1.0 / config_.rate_hz : 0.0;
  scan.time_increment_s = n > 0 ? scan.scan_time_s / n : 0.0;
  scan.range_min_m = config_.range_min_m;
  scan.range_max_m = config_.range_max_m;
  scan.ranges_m.resize(n);
  scan.intensities.clear();

  // The scanner's pose in the map, then in the grid frame in cell units.
  const double cb = std::cos(map_from_base.theta_rad), sb = std::sin(map_from_base.theta_rad);
  const navi::Point2D origin{map_from_base.x_m + cb * config_.mount.x_m - sb * config_.mount.y_m,
                             map_from_base.y_m + sb * config_.mount.x_m + cb * config_.mount.y_m};
  const navi::Point2D g = world.to_cells(origin);
  const double heading = world.to_grid_angle(map_from_base.theta_rad + config_.mount.theta_rad);
  const double ch = std::cos(heading), sh = std::sin(heading);
  const double max_t = config_.range_max_m / world.resolution_m();
  // Rotating the tabulated beam directions by the heading: cos(a + h), sin(a + h) by the sum
  // formulas, with no trigonometric call per beam.
  for (std::uint32_t i = 0; i < n; ++i) {
    const double dx = cos_[i] * ch - sin_[i] * sh;
    const double dy = sin_[i] * ch + cos_[i] * sh;
    const double t = world.cast_cells(g.x_m, g.y_m, dx, dy, max_t);
    scan.ranges_m[i] = static_cast<float>(t * world.resolution_m());
  }
}

void LaserModel::scan_exact(const SolidMap& world, const Pose2D& map_from_base, Time stamp, LaserScan& scan) const noexcept {
  fill(world, map_from_base, stamp, scan);
  for (float& r : scan.ranges_m) {
    if (r < config_.range_min_m) r = std::numeric_limits<float>::infinity();
  }
}

void LaserModel::scan(const SolidMap& world, const Pose2D& map_from_base, Time stamp, LaserScan& scan) noexcept {
  fill(world, map_from_base, stamp, scan);
  const bool noisy = config_.noise_stddev_m > 0.0;
  for (float& r : scan.ranges_m) {
    if (!std::isfinite(r)) continue;
    double v = r;
    // Every returned beam draws its noise, so the stream stays aligned whatever the ranges.
    if (noisy) v += noise_(rng_);
    v = std::min(v, config_.range_max_m);
    r = v < config_.range_min_m ? std::numeric_limits<float>::infinity() : static_cast<float>(v);
  }
}

double LaserConfig::angle_increment() const noexcept {
  if (beams == 0) return 0.0;
  const double span = angle_max_rad - angle_min_rad;
  if (span >= 2.0 * std::numbers::pi - 1e-9) return 2.0 * std::numbers::pi / beams;
  return beams > 1 ? span / (beams - 1.0) : 0.0;
}

LaserConfig LaserConfig::rplidar_a1() {
  LaserConfig c;
  c.angle_min_rad = -std::numbers::pi;
  c.angle_max_rad = std::numbers::pi;
  c.beams = 1450;
  c.range_min_m = 0.15;
  c.range_max_m = 12.0;
  c.rate_hz = 5.5;
  c.noise_stddev_m = 0.01;
  return c;
}

LaserConfig LaserConfig::sick_180() {
  LaserConfig c;
  c.angle_min_rad = -0.5 * std::numbers::pi;
  c.angle_max_rad = 0.5 * std::numbers::pi;
  c.beams = 361;
  c.range_min_m = 0.05;
  c.range_max_m = 30.0;
  c.rate_hz = 37.5;
  c.noise_stddev_m = 0.01;
  return c;
}

}  // namespace tripodal::sim
