#include "tripodal/behaviors/navigation_behaviors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>

#include "tripodal/controllers/kinematics.hpp"

namespace tripodal {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kCornerRad = 0.45;  // a bend of the path the lookahead point does not cross
constexpr double kDriveWhileTurningRad = 0.5;  // differential: larger bearings turn in place
constexpr double kCrawl_m_s = 0.02;  // slower than this before an obstacle counts as stopped
constexpr std::size_t kMaxBeams = 4096;  // beams of a scan looked at (the beam table's capacity)

using parameter::number;
using parameter::text;

std::vector<ParameterSpec> following_parameters(double speed, double lookahead) {
  return {
      number("max_speed_m_s", speed, "m/s", "Cruise speed along the path", 1e-3, 5.0),
      number("lookahead_m", lookahead, "m", "Arc length from the closest path point to the point steered at", 0.02, 5.0),
      number("max_yaw_rate_rad_s", 1.0, "rad/s", "Largest commanded yaw rate", 1e-3, 10.0),
      number("stop_distance_m", 0.05, "m", "Translation stops when an obstacle ahead is this close to the body", 0.0, 2.0),
      number("slow_distance_m", 0.4, "m", "Speed falls linearly from here to stop_distance_m", 0.0, 5.0),
      number("blocked_timeout_s", 10.0, "s", "Fail with 'path blocked' after being stopped this long", 0.1, 3600.0),
      number("replan_after_s", 2.0, "s",
             "Stopped this long by an obstacle the map does not hold, plan a way around it (0: never)", 0.0, 3600.0),
      number("max_replans", 5.0, "", "Plans around unexpected obstacles allowed per activation", 0.0, 1000.0),
      number("safety_hold_s", 1.0, "s",
             "Held still this long by a safety input (the commanded translation clamped to zero) counts as blocked, "
             "as before an obstacle on the path (0: at once)",
             0.0, 3600.0),
      text("laser", "", "Laser resource watched for obstacles (empty: the first laser)"),
  };
}

double clamp_abs(double v, double limit) noexcept { return std::clamp(v, -limit, limit); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// PathTracker

void PathTracker::reserve(std::size_t points) {
  pts_.reserve(points);
  s_.reserve(points);
}

void PathTracker::reset(std::span<const Pose2D> path, double start_m) noexcept {
  const std::size_t n = std::min(path.size(), pts_.capacity());
  pts_.assign(path.begin(), path.begin() + static_cast<std::ptrdiff_t>(n));
  s_.assign(n, 0.0);  // s_ was reserved with pts_
  for (std::size_t i = 1; i < n; ++i) {
    s_[i] = s_[i - 1] + std::hypot(pts_[i].x_m - pts_[i - 1].x_m, pts_[i].y_m - pts_[i - 1].y_m);
  }
  s_now_ = std::clamp(start_m, 0.0, length_m());
  seg_ = 0;
  memo_valid_ = false;
  while (seg_ + 1 < s_.size() && s_[seg_ + 1] <= s_now_) ++seg_;
}

Pose2D PathTracker::at(double s) const noexcept {
  if (pts_.empty()) return {};
  if (s <= 0.0) return pts_.front();
  if (s >= s_.back()) return pts_.back();
  // The first j with s < s_[j]. The points asked for lie a few centimetres around the progress
  // point (segment seg_): a short walk from there finds j before a search of the whole path would.
  const auto first_after = [&](std::size_t from, std::size_t to) {
    const auto begin = s_.begin();
    return static_cast<std::size_t>(
        std::upper_bound(begin + static_cast<std::ptrdiff_t>(from), begin + static_cast<std::ptrdiff_t>(to), s) - begin);
  };
  std::size_t j = 0;
  if (s_[seg_] <= s) {
    j = seg_ + 1;
    for (int k = 0; k < 8 && j < s_.size() && s_[j] <= s; ++k) ++j;
    if (j < s_.size() && s_[j] <= s) j = first_after(j, s_.size());
  } else {
    j = first_after(0, seg_ + 1);  // s_[seg_] > s: j <= seg_
  }
  // s_[j-1] <= s < s_[j]
  const double len = s_[j] - s_[j - 1];
  const double t = len > 0.0 ? (s - s_[j - 1]) / len : 0.0;
  return {pts_[j - 1].x_m + t * (pts_[j].x_m - pts_[j - 1].x_m), pts_[j - 1].y_m + t * (pts_[j].y_m - pts_[j - 1].y_m), 0.0};
}

double PathTracker::heading_at(double s) const noexcept {
  // Direction of a chord a few centimetres long: the dense cell-centre chains of the coverage
  // paths zig-zag at the cell scale, a single segment's direction would be noise.
  const Pose2D a = at(s - 0.05), b = at(s + 0.05);
  return std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
}

PathTracker::Target PathTracker::update(const Pose2D& position, double lookahead_m, double search_m) noexcept {
  if (memo_valid_ && position == memo_position_ && lookahead_m == memo_lookahead_m_ && search_m == memo_search_m_) {
    return memo_;
  }
  const double s_before = s_now_;
  const std::size_t seg_before = seg_;
  memo_ = search(position, lookahead_m, search_m);
  memo_position_ = position;
  memo_lookahead_m_ = lookahead_m;
  memo_search_m_ = search_m;
  // Progress unchanged: the same inputs would search the same window from the same state.
  memo_valid_ = s_now_ == s_before && seg_ == seg_before;
  return memo_;
}

PathTracker::Target PathTracker::search(const Pose2D& position, double lookahead_m, double search_m) noexcept {
  Target t;
  if (pts_.empty()) return t;
  if (pts_.size() == 1) {
    t.point = pts_.front();
    t.cross_track_m = std::hypot(position.x_m - t.point.x_m, position.y_m - t.point.y_m);
    return t;
  }
  double best_d2 = kInf, best_s = s_now_;
  std::size_t best_seg = seg_;
  for (std::size_t j = seg_; j + 1 < pts_.size() && s_[j] <= s_now_ + search_m; ++j) {
    const Pose2D& a = pts_[j];
    const Pose2D& b = pts_[j + 1];
    const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
    const double len2 = dx * dx + dy * dy;
    double u = len2 > 0.0 ? ((position.x_m - a.x_m) * dx + (position.y_m - a.y_m) * dy) / len2 : 0.0;
    u = std::clamp(u, 0.0, 1.0);
    const double s = s_[j] + u * (s_[j + 1] - s_[j]);
    if (s < s_now_) continue;
    const double px = a.x_m + u * dx - position.x_m, py = a.y_m + u * dy - position.y_m;
    const double d2 = px * px + py * py;
    if (d2 < best_d2 - 1e-12) {
      best_d2 = d2;
      best_s = s;
      best_seg = j;
    }
  }
  if (best_d2 < kInf) {
    s_now_ = best_s;
    seg_ = best_seg;
    t.cross_track_m = std::sqrt(best_d2);
  }
  // The lookahead point stops at the first sharp bend within the lookahead: a point beyond it
  // would make the robot cut the corner (and skip the short out-and-back legs of the touch-up
  // visits), leaving uncleaned cells.
  const double h0 = heading_at(s_now_ + 0.05);
  double s_carrot = s_now_ + lookahead_m;
  double corner = 0.0;
  for (double s = s_now_ + 0.1; s <= s_now_ + lookahead_m + 1e-9; s += 0.05) {
    corner = std::abs(wrap_angle(heading_at(s) - h0));
    if (corner > kCornerRad) {
      s_carrot = s - 0.05;
      break;
    }
  }
  t.point = at(std::max(s_carrot, s_now_ + 0.05));
  t.remaining_m = length_m() - s_now_;
  t.corner_rad = std::max(corner, std::abs(wrap_angle(heading_at(s_now_ + lookahead_m + 0.1) - h0)));
  return t;
}

// ---------------------------------------------------------------------------------------------
// CPathFollowingBehavior

struct CPathFollowingBehavior::NearReturns {
  // What the filtering depends on besides the scan's beam geometry (fixed by the sequence).
  bool valid = false;
  std::size_t sequence = 0;
  Pose2D pose;
  float rmin = 0.0F, near = 0.0F;
  const ObstacleMap* map = nullptr;
  std::vector<Pose2D> points;
};

namespace {

// One NearReturns per laser resource, alive while a behavior watching that laser is. Called at
// activation only (allocates); the loop's thread then uses the object without locking, as it
// reads the resource itself.
std::shared_ptr<CPathFollowingBehavior::NearReturns> near_returns_of(const LaserResource* laser) {
  static std::mutex mutex;
  static std::map<const LaserResource*, std::weak_ptr<CPathFollowingBehavior::NearReturns>> table;
  std::lock_guard lock(mutex);
  // Entries of lasers whose behaviors are all gone: a later laser at the same address starts afresh.
  std::erase_if(table, [](const auto& kv) { return kv.second.expired(); });
  std::weak_ptr<CPathFollowingBehavior::NearReturns>& entry = table[laser];
  if (auto shared = entry.lock()) return shared;
  auto shared = std::make_shared<CPathFollowingBehavior::NearReturns>();
  shared->points.reserve(kMaxBeams);
  entry = shared;
  return shared;
}

}  // namespace

void CPathFollowingBehavior::configure_following(const ParameterSet& params, const BehaviorContext& context) {
  speed_ = params.number("max_speed_m_s");
  lookahead_m_ = params.number("lookahead_m");
  yaw_rate_ = params.number("max_yaw_rate_rad_s");
  stop_distance_m_ = params.number("stop_distance_m");
  slow_distance_m_ = std::max(params.number("slow_distance_m"), stop_distance_m_);
  blocked_timeout_ = from_seconds(params.number("blocked_timeout_s"));
  safety_hold_ = from_seconds(params.number("safety_hold_s"));
  held_ = false;
  laser_ = nullptr;
  bumpers_ = nullptr;
  if (context.resources != nullptr) {
    const std::string& name = params.string("laser");
    laser_ = name.empty() ? context.resources->first<LaserScan>() : context.resources->find<LaserScan>(name);
    bumpers_ = context.resources->first<BumperReading>();
  }
  shared_ = laser_ != nullptr ? near_returns_of(laser_) : nullptr;
  if (tracker_.capacity() < kMaxPathPoints) tracker_.reserve(kMaxPathPoints);  // once per behavior
  cos_.reserve(kMaxBeams);
  sin_.reserve(kMaxBeams);
  unexpected_.reserve(kMaxBeams);
  unexpected_.clear();
  scan_seen_ = 0;
  tracker_.reset({});
  path_id_ = 0;
  waiting_since_ = context.now;
  blocked_ = false;
  if (context.navi != nullptr) hold_heading_rad_ = context.navi->map_from_base.theta_rad;
}

bool CPathFollowingBehavior::take_path(const BehaviorContext& context) noexcept {
  const NavigationData& navi = *context.navi;
  if (!navi.path_failure.empty()) {
    fail(navi.path_failure);
    return false;
  }
  if (navi.path_id != path_id_ && navi.path_id != 0) {
    tracker_.reset(navi.path, navi.path_start_m);
    path_id_ = navi.path_id;
    blocked_ = false;  // a new path (a replan around what blocked the last one): the timer restarts
  }
  if (path_id_ == 0 || tracker_.empty()) {
    if (context.now - waiting_since_ > blocked_timeout_) fail("no path");
    return false;
  }
  return true;
}

bool CPathFollowingBehavior::track(const Pose2D& pose, const BehaviorContext& context, double search_m,
                                   double tolerance_m, bool along_path, PathTracker::Target& target) noexcept {
  target = tracker_.update(pose, lookahead_m_, search_m);
  const Pose2D end = tracker_.points().back();
  // Along the path: the end counts once the progress has reached it (a spiral passes near its
  // own end before it gets there); to a goal: within the tolerance is enough.
  const bool at_end = std::hypot(end.x_m - pose.x_m, end.y_m - pose.y_m) <= tolerance_m &&
                      (!along_path || target.remaining_m < 0.05);
  if (context.feedback != nullptr) {
    context.feedback->path_id = path_id_;
    context.feedback->progress_m = tracker_.progress_m();
    context.feedback->reached_end = at_end;
    context.feedback->blocked = blocked_;
    context.feedback->blocked_since = blocked_since_;
  }
  return at_end;
}

Twist2D CPathFollowingBehavior::drive_toward(const Pose2D& pose, const PathTracker::Target& target,
                                             const BehaviorContext& context) noexcept {
  update_unexpected(pose, context);
  bool blocked = false;
  const Twist2D cmd = command_toward(pose, target, context, blocked);
  const bool too_long = blocked_too_long(blocked || held_by_safety(context), context.now);
  if (context.feedback != nullptr) {
    context.feedback->blocked = blocked_;
    context.feedback->blocked_since = blocked_since_;
  }
  if (too_long) {
    fail("path blocked");
    return Twist2D{};
  }
  return cmd;
}

void CPathFollowingBehavior::update_beam_table(const LaserScan& scan) noexcept {
  const std::size_t n = std::min(scan.ranges_m.size(), kMaxBeams);
  if (cos_.size() == n && table_angle_min_ == scan.angle_min_rad && table_increment_ == scan.angle_increment_rad) return;
  cos_.resize(n);  // within the capacity reserved at activation
  sin_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    cos_[i] = static_cast<float>(std::cos(a));
    sin_[i] = static_cast<float>(std::sin(a));
  }
  table_angle_min_ = scan.angle_min_rad;
  table_increment_ = scan.angle_increment_rad;
}

void CPathFollowingBehavior::update_unexpected(const Pose2D& pose, const BehaviorContext& context) noexcept {
  if (laser_ == nullptr || !laser_->is_fresh(context.now) || laser_->sequence() == scan_seen_) return;
  scan_seen_ = laser_->sequence();
  const LaserScan& scan = laser_->latest();
  update_beam_table(scan);
  unexpected_.clear();
  // Only returns within slow_distance_m + 2 radii can limit the speed: a return in the corridor
  // has clearance >= range - 2 * radius, and the speed is not limited beyond slow_distance_m.
  // Testing the raw range first skips most beams with one well-predicted branch.
  const double radius = context.navi->robot_radius_m;
  const auto rmin = static_cast<float>(scan.range_min_m);
  const auto near = static_cast<float>(std::min(scan.range_max_m, slow_distance_m_ + 2.0 * radius));
  // Returns from obstacles of the map are not in the way: the path was planned around them with
  // a margin; only what the map does not know (a box left in the corridor) stops the robot.
  const ObstacleMap* map = context.navi->map;
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  NearReturns* shared = shared_.get();
  if (shared != nullptr && shared->valid && shared->sequence == scan_seen_ && shared->pose == pose &&
      shared->rmin == rmin && shared->near == near && shared->map == map) {
    unexpected_.assign(shared->points.begin(), shared->points.end());  // within the reserved capacity
    return;
  }
  const std::size_t count = std::min(scan.ranges_m.size(), cos_.size());
  const float* ranges = scan.ranges_m.data();
  for (std::size_t i = 0; i < count; ++i) {
    const float r = ranges[i];
    if (!(r >= rmin && r <= near)) continue;  // also skips NaN and no-return values
    const double px = r * static_cast<double>(cos_[i]), py = r * static_cast<double>(sin_[i]);
    if (map != nullptr && map->near_obstacle(pose.x_m + c * px - s * py, pose.y_m + s * px + c * py)) continue;
    unexpected_.push_back({px, py, 0.0});  // within the capacity reserved at activation
  }
  if (shared != nullptr) {
    shared->valid = true;
    shared->sequence = scan_seen_;
    shared->pose = pose;
    shared->rmin = rmin;
    shared->near = near;
    shared->map = map;
    shared->points.assign(unexpected_.begin(), unexpected_.end());
  }
}

double CPathFollowingBehavior::clearance_along(double dx_body, double dy_body, const BehaviorContext& context) const noexcept {
  if (laser_ == nullptr || !laser_->is_fresh(context.now)) return kInf;
  const double n = std::hypot(dx_body, dy_body);
  if (n <= 0.0) return kInf;
  const double ux = dx_body / n, uy = dy_body / n;
  const double radius = context.navi->robot_radius_m;
  // Walls the path runs along are tangent to the body: a point beside it (lateral distance near
  // the radius) is not in the way, and range noise would make it look so.
  const double corridor = 0.95 * radius;
  double best = kInf;
  for (const Pose2D& p : unexpected_) {
    const double along = p.x_m * ux + p.y_m * uy;
    const double lateral = std::abs(p.x_m * uy - p.y_m * ux);
    if (along <= 0.0 || lateral >= corridor) continue;
    best = std::min(best, along - std::sqrt(radius * radius - lateral * lateral));
  }
  return best;
}

Twist2D CPathFollowingBehavior::command_toward(const Pose2D& pose, const PathTracker::Target& target,
                                               const BehaviorContext& context, bool& blocked) noexcept {
  Twist2D cmd;
  blocked = false;
  const double dx = target.point.x_m - pose.x_m, dy = target.point.y_m - pose.y_m;
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  const double bx = c * dx + s * dy, by = -s * dx + c * dy;  // body frame
  const double dist = std::hypot(bx, by);
  // Slow down for sharp corners of the path and at its end, so the footprint stays on the
  // contour (the rounds overlap by only a few centimetres).
  double speed = speed_ * std::clamp(std::cos(std::min(target.corner_rad, kPi / 2.0)), 0.35, 1.0);
  speed = std::min(speed, std::max(0.05, 1.5 * (target.remaining_m + dist)));
  // The path's own limit on this leg (a disinfection lane's speed for its dose).
  if (const NavigationData* n = context.navi;
      n != nullptr && n->path_id == path_id_ && tracker_.segment() < n->path_speed_m_s.size()) {
    speed = std::min(speed, n->path_speed_m_s[tracker_.segment()]);
  }
  if (dist < 1e-6) return cmd;
  // The speed allowed by the clearance ahead: full beyond slow_distance_m, falling linearly to
  // zero at stop_distance_m. Below a crawl the robot counts as stopped (blocked): approaching
  // the stop distance asymptotically it would otherwise creep for ever and never time out.
  auto limit_by_clearance = [&](double v, double clearance) {
    if (clearance >= slow_distance_m_ || slow_distance_m_ <= stop_distance_m_) return v;
    const double limited = clearance <= stop_distance_m_
                               ? 0.0
                               : v * (clearance - stop_distance_m_) / (slow_distance_m_ - stop_distance_m_);
    if (limited < kCrawl_m_s) {
      blocked = true;
      return 0.0;
    }
    return limited;
  };
  if (context.base.holonomic()) {
    speed = std::min(speed, context.base.max_vx_m_s);
    speed = limit_by_clearance(speed, clearance_along(bx, by, context));
    cmd.vx_m_s = speed * bx / dist;
    cmd.vy_m_s = speed * by / dist;
    cmd.wz_rad_s = clamp_abs(k_heading_ * wrap_angle(hold_heading_rad_ - pose.theta_rad), yaw_rate_);
  } else {
    const double alpha = std::atan2(by, bx);
    cmd.wz_rad_s = clamp_abs(k_heading_ * alpha, std::min(yaw_rate_, context.base.max_wz_rad_s));
    // Turn in place first when the lookahead point is well off the heading: driving while
    // turning would sweep an arc off the path, toward the obstacle the path goes around.
    if (std::abs(alpha) < kDriveWhileTurningRad) {
      speed = std::min(speed, context.base.max_vx_m_s);
      const double c_alpha = std::cos(alpha);
      cmd.vx_m_s = limit_by_clearance(speed * c_alpha * c_alpha, clearance_along(1.0, 0.0, context));
    }
  }
  return cmd;
}

bool CPathFollowingBehavior::held_by_safety(const BehaviorContext& context) noexcept {
  // Held: the last command asked to move and the safety override let it crawl at most the way it
  // asked (a reflex backing the robot off a drop holds it too: it makes no progress). Turning is
  // never held (a safety input leaves rotation free), so a turn in place toward a new path is not.
  const SafetyFeedback* safety = context.safety;
  bool holding = false;
  if (safety != nullptr && safety->limited && safety->requested_speed_m_s() >= kCrawl_m_s) {
    const Twist2D& req = safety->requested;
    const Twist2D& allowed = safety->allowed;
    const double progress_m_s = (req.vx_m_s * allowed.vx_m_s + req.vy_m_s * allowed.vy_m_s) / safety->requested_speed_m_s();
    holding = progress_m_s < kCrawl_m_s;
  }
  if (!holding) {
    held_ = false;
    return false;
  }
  if (!held_) {
    held_ = true;
    held_since_ = context.now;
  }
  return context.now - held_since_ >= safety_hold_;
}

bool CPathFollowingBehavior::blocked_too_long(bool blocked, Time now) noexcept {
  // A body in contact cannot follow the path (the laser misses what grazes the body's side).
  if (bumpers_ != nullptr && bumpers_->is_fresh(now) && bumpers_->latest().any()) blocked = true;
  if (!blocked) {
    blocked_ = false;
    return false;
  }
  if (!blocked_) {
    blocked_ = true;
    blocked_since_ = now;
  }
  return now - blocked_since_ > blocked_timeout_;
}

// ---------------------------------------------------------------------------------------------
// BhAutoMove

const ModuleManifest& BhAutoMove::static_manifest() {
  static const ModuleManifest m = [] {
    auto params = following_parameters(0.4, 0.35);
    params.insert(params.begin(), text("goal", "", "Where to go: <section>.entry, a map node, a room or a section"));
    params.push_back(number("goal_tolerance_m", 0.1, "m", "Success within this distance of the goal", 0.01, 2.0));
    return behavior_manifest("BhAutoMove",
                             "Follows the shortest collision-free path the path planner gives to a named goal; the laser "
                             "stops it before unexpected obstacles; fails when blocked for blocked_timeout_s",
                             {"map_from_base", "laser_scan", "path"}, std::move(params));
  }();
  return m;
}

void BhAutoMove::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  configure_following(params, context);
  goal_tol_m_ = params.number("goal_tolerance_m");
  if (context.navi == nullptr) fail("not localized");
}

std::optional<Twist2D> BhAutoMove::on_step(const BehaviorContext& context) noexcept {
  if (context.navi == nullptr || !context.navi->localized) return Twist2D{};  // pause: the net decides
  if (!take_path(context)) return Twist2D{};
  const Pose2D pose = context.navi->map_from_base;
  PathTracker::Target t;
  if (track(pose, context, 1.0, goal_tol_m_, false, t)) {
    if (context.navi->path_final) succeed();
    return Twist2D{};
  }
  return drive_toward(pose, t, context);
}

// ---------------------------------------------------------------------------------------------
// Cleaning

namespace {

std::vector<ParameterSpec> cleaning_parameters() {
  auto params = following_parameters(0.3, 0.1);
  params.insert(params.begin(), text("section", "", "The section to cover, as named by the section splitter"));
  return params;
}

}  // namespace

const ModuleManifest& BhCleaning::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhCleaning",
      "Wall-following full coverage of a section on an omni-directional base: follows the balloon path "
      "(offset growing each round) the coverage planner gives, succeeds at its end",
      {"map_from_base", "laser_scan", "coverage_path"}, cleaning_parameters());
  return m;
}

const ModuleManifest& BhCleaningTwoWheel::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhCleaningTwoWheel",
      "Wall-following full coverage of a section on a two-wheel differential base: turns toward the "
      "balloon path the coverage planner gives and drives forward, succeeds at its end",
      {"map_from_base", "laser_scan", "coverage_path"}, cleaning_parameters());
  return m;
}

void CCleaningBehavior::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  configure_following(params, context);
  if (needs_holonomic_ && !context.base.holonomic()) {
    fail("BhCleaning needs an omni-directional base");
    return;
  }
  if (context.navi == nullptr) fail("not localized");
}

std::optional<Twist2D> CCleaningBehavior::on_step(const BehaviorContext& context) noexcept {
  if (context.navi == nullptr || !context.navi->localized) return Twist2D{};  // pause: the net decides
  if (!take_path(context)) return Twist2D{};
  const Pose2D pose = context.navi->map_from_base;
  PathTracker::Target t;
  if (track(pose, context, context.navi->path_final ? 0.6 : 1.0, 0.1, true, t)) {
    if (context.navi->path_final) succeed();
    return Twist2D{};  // the end of a detour: the coverage planner gives the way on
  }
  return drive_toward(pose, t, context);
}

// ---------------------------------------------------------------------------------------------
// BhGlobalLocalization

const ModuleManifest& BhGlobalLocalization::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhGlobalLocalization",
      "Turns in place while the localizer attempts global position fixes, until one is accepted",
      {"laser_scan", "position_fix"},
      {number("yaw_rate_rad_s", 0.5, "rad/s", "Turning rate while searching", 0.0, 5.0),
       number("attempt_period_s", 2.0, "s", "Time between two position fixes the localizer attempts", 0.01, 60.0),
       number("timeout_s", 50.0, "s", "Fail with 'no position found' after this long", 0.1, 3600.0)});
  return m;
}

void BhGlobalLocalization::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  yaw_rate_ = params.number("yaw_rate_rad_s");
  timeout_ = from_seconds(params.number("timeout_s"));
  started_ = context.now;
  fixes_at_start_ = context.navi != nullptr ? context.navi->fixes : 0;
}

std::optional<Twist2D> BhGlobalLocalization::on_step(const BehaviorContext& context) noexcept {
  if (context.navi != nullptr && context.navi->fixes != fixes_at_start_) {
    succeed();
    return Twist2D{};
  }
  if (context.now - started_ > timeout_) {
    fail("no position found");
    return Twist2D{};
  }
  return Twist2D{0.0, 0.0, yaw_rate_};
}

void register_navigation_behaviors(BehaviorRegistry& registry) {
  registry.add<BhAutoMove>();
  registry.add<BhCleaning>();
  registry.add<BhCleaningTwoWheel>();
  registry.add<BhGlobalLocalization>();
}

}  // namespace tripodal
