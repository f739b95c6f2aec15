#include "tripodal/navi/map_builder.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <string>

#include "tripodal/navi/map_io.hpp"

namespace tripodal::navi {

MapBuilder::MapBuilder(Point2D lower, Point2D upper, MapBuilderOptions options)
    : options_(options), closure_matcher_(options.matcher) {
  options_.matcher.global_levels = 1;  // the tracker never searches globally: no pyramid
  validate(options_.matcher);
  validate(closure_matcher_);
  Diagnostics d;
  const LoopClosureOptions& loop = options_.loop;
  if (!(loop.keyframe_m > 0.0 && loop.keyframe_rad > 0.0 && loop.every_keyframes >= 1 && loop.min_travel_m >= 0.0 &&
        loop.search_radius_m > 0.0 && loop.submap_keyframes >= 1 && loop.min_quality > 0.0 && loop.min_quality <= 1.0 &&
        loop.settled_chi2 >= 0.0 && loop.agree_keyframes >= 1 && loop.agree_m > 0.0 && loop.agree_rad > 0.0 &&
        loop.exclusion_m > 0.0 && loop.distinct_margin >= 0.0 && loop.drift_base_m >= 0.0 && loop.drift_m_per_m >= 0.0 &&
        loop.drift_base_rad >= 0.0 && loop.drift_rad_per_m >= 0.0)) {
    d.error({},
            "map builder: loop closure options out of range (keyframe_m, keyframe_rad, search_radius_m, agree_m, "
            "agree_rad, exclusion_m > 0; every_keyframes, submap_keyframes, agree_keyframes >= 1; min_quality in "
            "(0, 1]; margins, drift bounds and settled_chi2 >= 0)");
  }
  if (!(std::isfinite(options_.resolution_m) && options_.resolution_m > 0.0)) {
    d.error({}, "map builder: resolution_m must be a number > 0, got " + std::to_string(options_.resolution_m));
  }
  if (!(options_.hit_log_odds > 0.0 && options_.miss_log_odds < 0.0 && options_.clamp_log_odds > 0.0)) {
    d.error({}, "map builder: expected hit_log_odds > 0, miss_log_odds < 0 and clamp_log_odds > 0");
  }
  if (options_.refresh_every_scans < 1) d.error({}, "map builder: refresh_every_scans must be >= 1");
  if (!(options_.fallback_scans >= 1 && options_.fallback_scans <= 64 && options_.fallback_share > 0.0 &&
        options_.fallback_share <= 1.0)) {
    d.error({}, "map builder: expected fallback_scans in [1, 64] and fallback_share in (0, 1], got " +
                    std::to_string(options_.fallback_scans) + " and " + std::to_string(options_.fallback_share));
  }
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
  turns_rad_[turn_next_] = std::abs(motion.theta_rad);
  turn_next_ = (turn_next_ + 1) % turns_rad_.size();
  if (!matcher_ || since_refresh_ >= options_.refresh_every_scans) {
    const OccupancyGrid g = grid_around({pose_.x_m, pose_.y_m});
    if (g.width() >= 2 && g.height() >= 2 && g.count(Occupancy::occupied) > 0) {
      matcher_ = std::make_unique<ScanMatcher>(g, options_.matcher);
      since_refresh_ = 0;
    }
  }
  bool matched = false;
  ++health_.scans;
  if (matcher_) {
    ++since_refresh_;
    const bool fallback = fallback_on();  // judged on the matches before this one
    health_.in_fallback += fallback ? 1 : 0;
    matcher_->set_scan(scan, base_from_laser);
    ScanMatch m = matcher_->track(pose_, motion, options_.window);
    const double typical = qualities_.typical();
    const double margin = options_.recovery_margin;
    bool untrusted = false;
    if (margin > 0.0 && typical > 0.0 && m.quality < typical - margin) {
      // Far weaker than usual: the odometry may have turned (or not) beyond the window. Mapping
      // on would lay the rest of the map at the wrong angle, so search every heading around the
      // odometry's position. Not the whole map: a corridor elsewhere often looks as good.
      ++health_.weak;
      // not while falling back: the matches are not believed there, and the search costs six
      // wide matches a scan (the infinite corridor's 109 ms per scan)
      const ScanMatch g = fallback ? ScanMatch{} : rematch_all_headings();
      // a turn the odometry did not report is no odometry jump: on the infinite corridor two
      // such "recoveries" (91 and 90 degrees at scans 104 and 117, junctions that look alike)
      // laid the rest of the map backwards; seattle's jump is the odometry's own 80 degrees
      const double unexplained_rad = std::abs(wrap_angle(g.pose.theta_rad - pose_.theta_rad)) - recent_turn_rad();
      if (g.quality >= typical - margin && g.quality >= m.quality + options_.recovery_gain &&
          unexplained_rad <= options_.recovery_tolerance_rad) {
        m = g;
        ++health_.recovered;
      } else {
        ++health_.unreliable;
        untrusted = true;
        // a weak match that moves the pose far from the odometry is not taken (a corridor's
        // match slides along it): the odometry's word is kept; while most matches are
        // untrusted, not even a near one (0.3 m a scan adds up along a corridor)
        if (fallback || far_from_odometry(m.pose, motion)) m.quality = 0.0;
      }
    } else if (fallback && far_from_odometry(m.pose, motion)) {
      m.quality = 0.0;
    }
    untrusted_bits_ = (untrusted_bits_ << 1U) | (untrusted ? 1U : 0U);
    recorded_ = std::min(recorded_ + 1, options_.fallback_scans);
    last_quality_ = m.quality;
    matched = m.quality >= options_.min_quality;
    if (matched) pose_ = m.pose;
    health_.odometry_only += fallback && !matched ? 1 : 0;
    if (typical <= 0.0 || m.quality >= typical - margin) qualities_.add(m.quality);
  }
  travel_m_ += std::hypot(motion.x_m, motion.y_m);
  insert(scan, pose_, base_from_laser);
  const LoopClosureOptions& loop = options_.loop;
  if (keyframes_.empty()) {
    add_keyframe(scan, base_from_laser, true);
  } else {
    const Pose2D since = compose(inverse(graph_.poses().back()), pose_);
    if (std::hypot(since.x_m, since.y_m) >= loop.keyframe_m || std::abs(since.theta_rad) >= loop.keyframe_rad) {
      add_keyframe(scan, base_from_laser, matched);
    }
  }
  scans_.push_back({keyframes_.size() - 1, compose(inverse(graph_.poses().back()), pose_)});
  return pose_;
}

void MapBuilder::add_keyframe(const LaserScan& scan, const Pose2D& base_from_laser, bool matched) {
  const LoopClosureOptions& loop = options_.loop;
  const std::size_t node = graph_.add_node(pose_);
  if (node > 0) {
    // a poor match is the odometry's word only: a looser edge, which a closure bends first
    graph_.add_edge(node - 1, node, compose(inverse(graph_.pose(node - 1)), pose_),
                    matched ? loop.match_noise : loop.odometry_noise);
  }
  // the scan is kept only to draw the map again after a solve: without loop closure, no copy
  Keyframe k{loop.enabled ? scan : LaserScan{}, base_from_laser, travel_m_};
  k.scan.intensities.clear();
  keyframes_.push_back(std::move(k));
  ++stats_.keyframes;
  if (loop.enabled && node > 0 && node % static_cast<std::size_t>(loop.every_keyframes) == 0) try_closure();
}

void MapBuilder::try_closure() {
  const LoopClosureOptions& loop = options_.loop;
  const std::size_t c = keyframes_.size() - 1;
  const Pose2D& here = graph_.pose(c);
  const double horizon_m = keyframes_[c].travel_m - loop.min_travel_m;
  // the candidate: the nearest key scan passed long enough ago
  std::size_t j = c;
  double best_m = loop.search_radius_m;
  for (std::size_t k = 0; k < c && keyframes_[k].travel_m <= horizon_m; ++k) {
    const double d = std::hypot(graph_.pose(k).x_m - here.x_m, graph_.pose(k).y_m - here.y_m);
    if (d <= best_m) {
      best_m = d;
      j = k;
    }
  }
  if (j == c) return;
  ++stats_.attempts;
  // its local map: the key scans around it, none from the recent past
  const auto span = static_cast<std::size_t>(loop.submap_keyframes);
  const std::size_t first = j > span ? j - span : 0;
  std::size_t last = std::min(j + span, c);
  while (last > j && keyframes_[last].travel_m > horizon_m) --last;
  const double reach_m = std::min(options_.max_range_m, closure_matcher_.global_max_range_m) + 1.0;
  Point2D lo{here.x_m - reach_m, here.y_m - reach_m}, hi{here.x_m + reach_m, here.y_m + reach_m};
  for (std::size_t k = first; k <= last; ++k) {
    lo = {std::min(lo.x_m, graph_.pose(k).x_m - reach_m), std::min(lo.y_m, graph_.pose(k).y_m - reach_m)};
    hi = {std::max(hi.x_m, graph_.pose(k).x_m + reach_m), std::max(hi.y_m, graph_.pose(k).y_m + reach_m)};
  }
  MapBuilderOptions local_options = options_;
  local_options.loop.enabled = false;
  local_options.resolution_m = std::max(options_.resolution_m, loop.submap_resolution_m);
  MapBuilder local(lo, hi, local_options);
  for (std::size_t k = first; k <= last; ++k) local.insert(keyframes_[k].scan, graph_.pose(k), keyframes_[k].base_from_laser);
  const OccupancyGrid submap = local.grid();
  if (submap.count(Occupancy::occupied) == 0) return;
  ScanMatcher matcher(submap, closure_matcher_);
  if (matcher.set_scan(keyframes_[c].scan, keyframes_[c].base_from_laser) == 0) return;
  const ScanMatch m = matcher.match_global();
  if (!closure_accepted(matcher, submap, m, j)) return;
  const Pose2D j_to_c = compose(inverse(graph_.pose(j)), m.pose);
  const Pose2D off = compose(inverse(j_to_c), compose(inverse(graph_.pose(j)), here));
  graph_.add_edge(j, c, j_to_c, loop.closure_noise, true);
  ++stats_.closures;
  const double off_chi2 =
      (off.x_m * off.x_m + off.y_m * off.y_m) / (loop.closure_noise.sigma_xy_m * loop.closure_noise.sigma_xy_m) +
      off.theta_rad * off.theta_rad / (loop.closure_noise.sigma_theta_rad * loop.closure_noise.sigma_theta_rad);
  if (off_chi2 <= loop.settled_chi2) {
    ++stats_.settled;
    return;
  }
  const PoseGraphReport report = graph_.optimize();
  ++stats_.solves;
  stats_.rejected += report.rejected;
  stats_.closures -= report.rejected;
  if (report.rejected > 0 && graph_.rejected(graph_.edge_count() - 1) && report.rejected == 1) return;
  redraw();
  pose_ = graph_.pose(c);
  matcher_.reset();  // the tracker's window is refreshed from the redrawn map at the next scan
}

bool MapBuilder::closure_accepted(ScanMatcher& matcher, const OccupancyGrid& submap, const ScanMatch& best,
                                  std::size_t candidate) {
  const LoopClosureOptions& loop = options_.loop;
  const std::size_t c = keyframes_.size() - 1;
  const Pose2D& here = graph_.pose(c);
  if (best.quality < loop.min_quality || std::hypot(best.pose.x_m - here.x_m, best.pose.y_m - here.y_m) > loop.search_radius_m) {
    ++stats_.weak;
    return false;
  }
  // graph consistency first (it costs nothing): no more correction than the drift since allows
  const double travel_m = keyframes_[c].travel_m - keyframes_[candidate].travel_m;
  const Pose2D move = compose(inverse(here), best.pose);
  if (std::hypot(move.x_m, move.y_m) > loop.drift_base_m + loop.drift_m_per_m * travel_m ||
      std::abs(move.theta_rad) > loop.drift_base_rad + loop.drift_rad_per_m * travel_m) {
    ++stats_.implausible;
    return false;
  }
  // agreement: the key scans before this one, each searched on its own in the widest tracking
  // window around where the correction puts it, must find the same correction of the graph
  // (map_from_corrected = best * here^-1); a correction that fits one scan by chance moves the
  // others' best fits elsewhere
  const Pose2D correction = compose(best.pose, inverse(here));
  const auto others = static_cast<std::size_t>(std::max(loop.agree_keyframes, 1) - 1);
  for (std::size_t k = 1; k <= others && k <= c; ++k) {
    const std::size_t i = c - k;
    if (matcher.set_scan(keyframes_[i].scan, keyframes_[i].base_from_laser) == 0) continue;
    const Pose2D expected = compose(correction, graph_.pose(i));
    const ScanMatch mi = matcher.match(expected, closure_matcher_.max_search_xy_m, closure_matcher_.max_search_theta_rad);
    const Pose2D d = compose(inverse(expected), mi.pose);
    if (mi.quality < loop.min_quality || std::hypot(d.x_m, d.y_m) > loop.agree_m || std::abs(d.theta_rad) > loop.agree_rad) {
      ++stats_.disagreeing;
      return false;
    }
  }
  // distinctness: the best place away from the winner (its free cells hidden: the global search
  // places the robot on free cells only) must be clearly worse
  OccupancyGrid elsewhere = submap;
  const double r_cells = loop.exclusion_m / elsewhere.resolution_m();
  const CellIndex centre = elsewhere.cell_at({best.pose.x_m, best.pose.y_m});
  const int reach = static_cast<int>(std::ceil(r_cells));
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      const CellIndex cell{centre.x + dx, centre.y + dy};
      if (std::hypot(dx, dy) <= r_cells && elsewhere.contains(cell) && elsewhere.is_free(cell)) {
        elsewhere.set_state(cell, Occupancy::unknown);
      }
    }
  }
  ScanMatcher second_matcher(elsewhere, closure_matcher_);
  if (second_matcher.set_scan(keyframes_[c].scan, keyframes_[c].base_from_laser) > 0) {
    const ScanMatch second = second_matcher.match_global();
    if (std::hypot(second.pose.x_m - best.pose.x_m, second.pose.y_m - best.pose.y_m) > 0.5 * loop.exclusion_m &&
        second.quality > best.quality - loop.distinct_margin) {
      ++stats_.ambiguous;
      return false;
    }
  }
  return true;
}

ScanMatch MapBuilder::rematch_all_headings() noexcept {
  const ScanMatcherOptions& mo = options_.matcher;
  const double half = mo.max_search_theta_rad;
  // windows centred 2 x half apart, out to recovery_max_turn_rad (not the half turn: a corridor
  // matches itself backwards, and CSAIL's map flipped there)
  const int turns = std::max(1, static_cast<int>(std::floor((options_.recovery_max_turn_rad - half) / (2.0 * half) + 1e-9)));
  ScanMatch best;
  for (int k = -turns; k <= turns; ++k) {
    if (k == 0) continue;  // the tracker searched there
    const Pose2D around{pose_.x_m, pose_.y_m, wrap_angle(pose_.theta_rad + 2.0 * half * k)};
    const ScanMatch m = matcher_->match(around, mo.max_search_xy_m, half);
    if (m.quality > best.quality) best = m;
  }
  return best;
}

bool MapBuilder::far_from_odometry(const Pose2D& match, const Pose2D& motion) const noexcept {
  const Pose2D c = compose(inverse(pose_), match);
  const double moved = std::hypot(motion.x_m, motion.y_m);
  return std::hypot(c.x_m, c.y_m) > options_.recovery_tolerance_m + 0.3 * moved ||
         std::abs(c.theta_rad) > options_.recovery_tolerance_rad + 0.3 * std::abs(motion.theta_rad);
}

double MapBuilder::recent_turn_rad() const noexcept {
  double sum = 0.0;
  for (double t : turns_rad_) sum += t;
  return sum;
}

bool MapBuilder::fallback_on() const noexcept {
  if (recorded_ < options_.fallback_scans) return false;
  const std::uint64_t mask = options_.fallback_scans >= 64
                                 ? ~std::uint64_t{0}
                                 : (std::uint64_t{1} << static_cast<unsigned>(options_.fallback_scans)) - 1U;
  const auto untrusted = static_cast<double>(std::popcount(untrusted_bits_ & mask));
  return untrusted > options_.fallback_share * static_cast<double>(options_.fallback_scans);
}

void MapBuilder::redraw() {
  std::fill(log_odds_.begin(), log_odds_.end(), 0.0f);
  for (std::size_t k = 0; k < keyframes_.size(); ++k) insert(keyframes_[k].scan, graph_.pose(k), keyframes_[k].base_from_laser);
}

std::vector<Pose2D> MapBuilder::trajectory() const {
  std::vector<Pose2D> out;
  out.reserve(scans_.size());
  for (const ScanRef& s : scans_) out.push_back(compose(graph_.pose(s.keyframe), s.keyframe_from_base));
  return out;
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
