#include "tripodal/navi/map_builder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "tripodal/navi/map_io.hpp"

namespace tripodal::navi {

MapBuilder::MapBuilder(Point2D lower, Point2D upper, MapBuilderOptions options) : options_(options) {
  options_.matcher.global_levels = 1;  // the builder never searches globally: no pyramid
  validate(options_.matcher);
  Diagnostics d;
  if (!(std::isfinite(options_.resolution_m) && options_.resolution_m > 0.0)) {
    d.error({}, "map builder: resolution_m must be a number > 0, got " + std::to_string(options_.resolution_m));
  }
  if (!(options_.hit_log_odds > 0.0 && options_.miss_log_odds < 0.0 && options_.clamp_log_odds > 0.0)) {
    d.error({}, "map builder: expected hit_log_odds > 0, miss_log_odds < 0 and clamp_log_odds > 0");
  }
  if (options_.refresh_every_scans < 1) d.error({}, "map builder: refresh_every_scans must be >= 1");
  if (!(std::isfinite(options_.window_m) && options_.window_m > 0.0)) {
    d.error({}, "map builder: window_m must be a number > 0, got " + std::to_string(options_.window_m));
  }
  const double w = (upper.x_m - lower.x_m) / options_.resolution_m;
  const double h = (upper.y_m - lower.y_m) / options_.resolution_m;
  if (!(std::isfinite(w) && std::isfinite(h) && w >= 1.0 && h >= 1.0 && w * h <= static_cast<double>(kMaxPgmPixels))) {
    d.error({}, "map builder: the extent [" + std::to_string(lower.x_m) + ", " + std::to_string(upper.x_m) + "] x [" +
                    std::to_string(lower.y_m) + ", " + std::to_string(upper.y_m) +
                    "] m is empty or larger than a map image may be");
  }
  if (d.has_errors()) throw ConfigError(d);
  width_ = static_cast<int>(std::ceil(w));
  height_ = static_cast<int>(std::ceil(h));
  origin_ = {lower.x_m, lower.y_m, 0.0};
  log_odds_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0.0f);
}

MapBuilder::~MapBuilder() = default;

void MapBuilder::insert(const LaserScan& scan, const Pose2D& map_from_base, const Pose2D& base_from_laser) {
  const Pose2D laser = compose(map_from_base, base_from_laser);
  const double res = options_.resolution_m;
  const double ox = (laser.x_m - origin_.x_m) / res, oy = (laser.y_m - origin_.y_m) / res;
  const int x0 = static_cast<int>(std::floor(ox)), y0 = static_cast<int>(std::floor(oy));
  const double hi = std::min(scan.range_max_m > 0.0 ? scan.range_max_m : options_.max_range_m, options_.max_range_m);
  const auto miss = static_cast<float>(options_.miss_log_odds), hit = static_cast<float>(options_.hit_log_odds);
  const auto lim = static_cast<float>(options_.clamp_log_odds);
  auto add = [&](int x, int y, float v) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    float& c = log_odds_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
    c = std::clamp(c + v, -lim, lim);
  };
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < std::max(scan.range_min_m, 1e-3) || r >= hi) continue;
    const double a = laser.theta_rad + scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double ex = ox + r * std::cos(a) / res, ey = oy + r * std::sin(a) / res;
    const int x1 = static_cast<int>(std::floor(ex)), y1 = static_cast<int>(std::floor(ey));
    // Bresenham from the scanner's cell to the end point's, the end point excluded
    int x = x0, y = y0;
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    while (x != x1 || y != y1) {
      add(x, y, miss);
      const int e2 = 2 * err;
      if (e2 >= dy) {
        err += dy;
        x += sx;
      }
      if (e2 <= dx) {
        err += dx;
        y += sy;
      }
    }
    add(x1, y1, hit);
  }
}

Pose2D MapBuilder::add(const LaserScan& scan, const Pose2D& odom_from_base, const Pose2D& start,
                       const Pose2D& base_from_laser) {
  Pose2D motion;
  if (!started_) {
    started_ = true;
    pose_ = start;
  } else {
    motion = compose(inverse(last_odom_), odom_from_base);
    pose_ = compose(pose_, motion);
  }
  last_odom_ = odom_from_base;
  if (!matcher_ || since_refresh_ >= options_.refresh_every_scans) {
    const OccupancyGrid g = grid_around({pose_.x_m, pose_.y_m});
    if (g.width() >= 2 && g.height() >= 2 && g.count(Occupancy::occupied) > 0) {
      matcher_ = std::make_unique<ScanMatcher>(g, options_.matcher);
      since_refresh_ = 0;
    }
  }
  if (matcher_) {
    ++since_refresh_;
    matcher_->set_scan(scan, base_from_laser);
    const ScanMatch m = matcher_->track(pose_, motion, options_.window);
    last_quality_ = m.quality;
    if (m.quality >= options_.min_quality) pose_ = m.pose;
  }
  insert(scan, pose_, base_from_laser);
  return pose_;
}

OccupancyGrid MapBuilder::grid() const { return grid_of(0, 0, width_, height_); }

OccupancyGrid MapBuilder::grid_around(Point2D center) const {
  const double res = options_.resolution_m;
  const double cx = (center.x_m - origin_.x_m) / res, cy = (center.y_m - origin_.y_m) / res, r = options_.window_m / res;
  auto clip = [](double v, int hi) { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(hi))); };
  return grid_of(clip(std::floor(cx - r), width_), clip(std::floor(cy - r), height_), clip(std::ceil(cx + r), width_),
                 clip(std::ceil(cy + r), height_));
}

OccupancyGrid MapBuilder::grid_within(Point2D lower, Point2D upper) const {
  const double res = options_.resolution_m;
  auto clip = [](double v, int hi) { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(hi))); };
  return grid_of(clip(std::floor((lower.x_m - origin_.x_m) / res), width_), clip(std::floor((lower.y_m - origin_.y_m) / res), height_),
                 clip(std::ceil((upper.x_m - origin_.x_m) / res), width_), clip(std::ceil((upper.y_m - origin_.y_m) / res), height_));
}

OccupancyGrid MapBuilder::grid_of(int x0, int y0, int x1, int y1) const {
  const double res = options_.resolution_m;
  OccupancyGrid g(x1 - x0, y1 - y0, res, Pose2D{origin_.x_m + x0 * res, origin_.y_m + y0 * res, 0.0}, Occupancy::unknown);
  // map_server's trinary thresholds as log odds: p > 0.65 occupied, p < 0.196 free
  const float occupied = std::log(0.65f / 0.35f), free = std::log(0.196f / 0.804f);
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      const float v = log_odds_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
      if (v > occupied) g.set_state({x - x0, y - y0}, Occupancy::occupied);
      else if (v < free) g.set_state({x - x0, y - y0}, Occupancy::free);
    }
  }
  return g;
}

}  // namespace tripodal::navi
