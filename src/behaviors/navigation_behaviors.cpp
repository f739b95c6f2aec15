#include "tripodal/behaviors/navigation_behaviors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "tripodal/controllers/kinematics.hpp"

namespace tripodal {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kCornerRad = 0.45;  // a bend of the path the lookahead point does not cross
constexpr double kDriveWhileTurningRad = 0.5;  // differential: larger bearings turn in place
// Planning around unexpected obstacles: laser returns within this range are taken as obstacles,
// the detour keeps this much more than the robot radius from them, and a cleaning detour takes
// the coverage path up again this far beyond them (the laser sees only the near face of a box).
constexpr double kObstacleRange_m = 3.0;
constexpr double kCrawl_m_s = 0.02;  // slower than this before an obstacle counts as stopped
constexpr double kDetourMargin_m = 0.1;
constexpr double kResumeClearance_m = 0.3;

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
      text("laser", "", "Laser resource watched for obstacles (empty: the first laser)"),
  };
}

double clamp_abs(double v, double limit) noexcept { return std::clamp(v, -limit, limit); }

navi::Point2D point_of(const Pose2D& p) noexcept { return {p.x_m, p.y_m}; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// NaviWorkspace

namespace {

navi::CoverageOptions coverage_options(const NaviWorkspaceOptions& o) {
  navi::CoverageOptions c;
  c.cleaning_width_m = o.cleaning_width_m;
  c.robot_radius_m = o.robot_radius_m;
  c.overlap_m = o.overlap_m;
  return c;
}

navi::PathPlannerOptions planner_options(const NaviWorkspaceOptions& o) {
  navi::PathPlannerOptions p;
  p.robot_radius_m = o.robot_radius_m;
  return p;
}

}  // namespace

NaviWorkspace::NaviWorkspace(navi::OccupancyGrid grid, navi::RegionMap regions, NaviWorkspaceOptions options)
    : grid_(std::move(grid)),
      regions_(std::move(regions)),
      options_(options),
      sections_(navi::CSectionSplitter(options.splitter).split(grid_)),
      planner_(grid_, planner_options(options)),
      coverage_(grid_, coverage_options(options)),
      cleaned_(grid_) {}

const navi::Section* NaviWorkspace::section(std::string_view name) const noexcept {
  for (const navi::Section& s : sections_.sections) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

NaviWorkspace::RoomSections NaviWorkspace::sections_of_room(std::string_view room) const {
  RoomSections out;
  const navi::Region* r = regions_.room(room);
  if (r == nullptr) {
    out.error = "unknown room '" + std::string(room) + "' (known:";
    for (const auto& n : regions_.room_names()) out.error += " " + n;
    out.error += ")";
    return out;
  }
  for (const navi::Section& s : sections_.sections) {
    std::size_t inside = 0;
    for (const std::size_t i : s.cells) inside += r->contains(grid_.cell_center(grid_.cell(i))) ? 1 : 0;
    if (2 * inside > s.cells.size()) out.names.push_back(s.name);
  }
  if (out.names.empty()) {
    out.error = "room '" + std::string(room) + "' holds no section of the map";
    return out;
  }
  out.ok = true;
  return out;
}

std::optional<navi::Point2D> NaviWorkspace::resolve_goal(std::string_view name, navi::Point2D from) {
  constexpr std::string_view kEntry = ".entry";
  if (name.size() > kEntry.size() && name.substr(name.size() - kEntry.size()) == kEntry) {
    const std::string_view sec = name.substr(0, name.size() - kEntry.size());
    const navi::Section* s = section(sec);
    if (s == nullptr) return std::nullopt;
    auto it = entry_plans_.find(sec);
    if (it == entry_plans_.end()) it = entry_plans_.emplace(std::string(sec), plan_coverage(*s, from)).first;
    if (it->second.path.empty()) return s->centroid;
    return it->second.path.front();
  }
  if (const navi::MapNode* n = regions_.node(name)) return navi::Point2D{n->pose.x_m, n->pose.y_m};
  if (const navi::Section* s = section(name)) return s->centroid;
  if (const navi::Region* r = regions_.room(name)) {
    navi::Point2D c;
    for (const auto& p : r->polygon) {
      c.x_m += p.x_m / static_cast<double>(r->polygon.size());
      c.y_m += p.y_m / static_cast<double>(r->polygon.size());
    }
    return c;
  }
  return std::nullopt;
}

NaviWorkspace::SectionProgress& NaviWorkspace::progress(const navi::Section& section, navi::Point2D from) {
  auto it = progress_.find(section.name);
  if (it != progress_.end() && !it->second.finished) return it->second;
  SectionProgress p;
  if (auto e = entry_plans_.find(section.name); e != entry_plans_.end()) {
    p.plan = std::move(e->second);  // the entry BhAutoMove went to is this path's first point
    entry_plans_.erase(e);
  } else {
    p.plan = plan_coverage(section, from);
  }
  if (it == progress_.end()) return progress_.emplace(section.name, std::move(p)).first->second;
  it->second = std::move(p);
  return it->second;
}

navi::CoverageResult NaviWorkspace::plan_coverage(const navi::Section& section, navi::Point2D from) {
  return options_.pattern == NaviWorkspaceOptions::Pattern::balloon ? coverage_.balloon(section, from)
                                                                     : coverage_.boustrophedon(section, from);
}

bool NaviWorkspace::relocalize(Time now) const noexcept {
  if (!relocalize_) return false;
  try {
    return relocalize_(now);
  } catch (...) {
    return false;
  }
}

// ---------------------------------------------------------------------------------------------
// PathTracker

void PathTracker::reset(std::vector<navi::Point2D> path, double start_m) {
  pts_ = std::move(path);
  s_.assign(pts_.size(), 0.0);
  for (std::size_t i = 1; i < pts_.size(); ++i) {
    s_[i] = s_[i - 1] + std::hypot(pts_[i].x_m - pts_[i - 1].x_m, pts_[i].y_m - pts_[i - 1].y_m);
  }
  s_now_ = std::clamp(start_m, 0.0, length_m());
  seg_ = 0;
  while (seg_ + 1 < s_.size() && s_[seg_ + 1] <= s_now_) ++seg_;
}

void PathTracker::jump_to(double s) noexcept {
  s_now_ = std::clamp(s, 0.0, length_m());
  seg_ = 0;
  while (seg_ + 1 < s_.size() && s_[seg_ + 1] <= s_now_) ++seg_;
}

navi::Point2D PathTracker::at(double s) const noexcept {
  if (pts_.empty()) return {};
  if (s <= 0.0) return pts_.front();
  if (s >= s_.back()) return pts_.back();
  const auto it = std::upper_bound(s_.begin(), s_.end(), s);
  const std::size_t j = static_cast<std::size_t>(it - s_.begin());  // s_[j-1] <= s < s_[j]
  const double len = s_[j] - s_[j - 1];
  const double t = len > 0.0 ? (s - s_[j - 1]) / len : 0.0;
  return {pts_[j - 1].x_m + t * (pts_[j].x_m - pts_[j - 1].x_m), pts_[j - 1].y_m + t * (pts_[j].y_m - pts_[j - 1].y_m)};
}

double PathTracker::heading_at(double s) const noexcept {
  // Direction of a chord a few centimetres long: the dense cell-centre chains of the coverage
  // paths zig-zag at the cell scale, a single segment's direction would be noise.
  const navi::Point2D a = at(s - 0.05), b = at(s + 0.05);
  return std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
}

PathTracker::Target PathTracker::update(navi::Point2D position, double lookahead_m, double search_m) noexcept {
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
    const navi::Point2D a = pts_[j], b = pts_[j + 1];
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

void CPathFollowingBehavior::configure_following(const ParameterSet& params, const BehaviorContext& context) {
  speed_ = params.number("max_speed_m_s");
  lookahead_m_ = params.number("lookahead_m");
  yaw_rate_ = params.number("max_yaw_rate_rad_s");
  stop_distance_m_ = params.number("stop_distance_m");
  slow_distance_m_ = std::max(params.number("slow_distance_m"), stop_distance_m_);
  blocked_timeout_ = from_seconds(params.number("blocked_timeout_s"));
  laser_ = nullptr;
  bumpers_ = nullptr;
  if (context.resources != nullptr) {
    const std::string& name = params.string("laser");
    laser_ = name.empty() ? context.resources->first<LaserScan>() : context.resources->find<LaserScan>(name);
    bumpers_ = context.resources->first<BumperReading>();
  }
  blocked_ = false;
  has_last_ = false;
  replan_after_ = from_seconds(params.number("replan_after_s"));
  max_replans_ = static_cast<int>(params.number("max_replans"));
  replans_ = 0;
  seen_obstacles_.clear();
  if (context.navi != nullptr) hold_heading_rad_ = context.navi->map_from_base.theta_rad;
}

bool CPathFollowingBehavior::near_mapped_obstacle(navi::Point2D p) const noexcept {
  const navi::OccupancyGrid& grid = workspace_.grid();
  const navi::CellIndex cell = grid.cell_at(p);
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (grid.state(navi::CellIndex{cell.x + dx, cell.y + dy}) != navi::Occupancy::free) return true;
    }
  }
  return false;
}

Twist2D CPathFollowingBehavior::drive_toward(const Pose2D& pose, const PathTracker::Target& target,
                                             const BehaviorContext& context) noexcept {
  bool blocked = false;
  const Twist2D cmd = command_toward(pose, target, context, blocked);
  if (blocked_too_long(blocked, context.now)) {
    fail("path blocked");
    return Twist2D{};
  }
  if (replan_due(context.now)) plan_around_obstacle(pose, context.now);
  return cmd;
}

bool CPathFollowingBehavior::replan_due(Time now) const noexcept {
  if (!blocked_ || replan_after_ <= Duration{0} || replans_ >= max_replans_) return false;
  if (now - blocked_since_ < replan_after_) return false;
  return replans_ == 0 || now - last_replan_ >= replan_after_;
}

void CPathFollowingBehavior::note_unmapped_returns(const Pose2D& pose, Time now, double max_range_m) {
  ++replans_;
  last_replan_ = now;
  if (laser_ == nullptr || !laser_->is_fresh(now)) return;
  const LaserScan& scan = laser_->latest();
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < scan.range_min_m || r > std::min<double>(scan.range_max_m, max_range_m)) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double bx = r * std::cos(a), by = r * std::sin(a);
    const navi::Point2D p{pose.x_m + c * bx - s * by, pose.y_m + s * bx + c * by};
    if (!near_mapped_obstacle(p)) seen_obstacles_.push_back(p);
  }
}

double CPathFollowingBehavior::clearance_along(double dx_body, double dy_body, const Pose2D& pose, Time now) const noexcept {
  if (laser_ == nullptr || !laser_->is_fresh(now)) return kInf;
  const double n = std::hypot(dx_body, dy_body);
  if (n <= 0.0) return kInf;
  const double ux = dx_body / n, uy = dy_body / n;
  const double radius = workspace_.options().robot_radius_m;
  // Walls the path runs along are tangent to the body: a point beside it (lateral distance near
  // the radius) is not in the way, and range noise would make it look so.
  const double corridor = 0.95 * radius;
  // Returns from obstacles of the map are not in the way: the path was planned around them with
  // a margin; only what the map does not know (a box left in the corridor) stops the robot.
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  auto on_map = [&](double bx, double by) {
    return near_mapped_obstacle({pose.x_m + c * bx - s * by, pose.y_m + s * bx + c * by});
  };
  const LaserScan& scan = laser_->latest();
  double best = kInf;
  const std::size_t count = scan.ranges_m.size();
  for (std::size_t i = 0; i < count; ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < scan.range_min_m || r > scan.range_max_m) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double px = r * std::cos(a), py = r * std::sin(a);
    const double along = px * ux + py * uy;
    const double lateral = std::abs(px * uy - py * ux);
    if (along <= 0.0 || lateral >= corridor || on_map(px, py)) continue;
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
    speed = limit_by_clearance(speed, clearance_along(bx, by, pose, context.now));
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
      cmd.vx_m_s = limit_by_clearance(speed * c_alpha * c_alpha, clearance_along(1.0, 0.0, pose, context.now));
    }
  }
  return cmd;
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
                             "Follows the shortest collision-free path (A*) to a named goal; the laser stops it before "
                             "unexpected obstacles; fails when blocked for blocked_timeout_s",
                             {"map_from_base", "laser_scan", "grid_map"}, std::move(params));
  }();
  return m;
}

void BhAutoMove::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  configure_following(params, context);
  goal_tol_m_ = params.number("goal_tolerance_m");
  tracker_.reset({});
  if (context.navi == nullptr) {
    fail("not localized");
    return;
  }
  const navi::Point2D from = point_of(context.navi->map_from_base);
  const std::optional<navi::Point2D> goal = workspace_.resolve_goal(params.string("goal"), from);
  if (!goal) {
    fail("unknown goal");
    return;
  }
  navi::PlannedPath plan = workspace_.planner().plan(from, *goal);
  if (!plan.ok()) {
    fail("no path to the goal");
    return;
  }
  goal_ = *goal;
  tracker_.reset(std::move(plan.waypoints));
}

void BhAutoMove::plan_around_obstacle(const Pose2D& pose, Time now) noexcept {
  try {
    const std::size_t before = seen_obstacles_.size();
    note_unmapped_returns(pose, now, kObstacleRange_m);
    if (seen_obstacles_.size() == before) return;  // nothing new seen (a bumper): the same plan again
    navi::PlannedPath plan = workspace_.planner().plan_around(point_of(pose), goal_, seen_obstacles_, kDetourMargin_m);
    if (!plan.ok()) return;  // no way around (yet): wait, the obstacle may go, until blocked_timeout_s
    tracker_.reset(std::move(plan.waypoints));
    blocked_ = false;  // a new path: the blocked timer starts again
  } catch (...) {
    // Out of memory while planning: keep the current path; the blocked timeout decides.
  }
}

std::optional<Twist2D> BhAutoMove::on_step(const BehaviorContext& context) noexcept {
  if (context.navi == nullptr || !context.navi->localized) return Twist2D{};  // pause: the net decides
  const Pose2D pose = context.navi->map_from_base;
  const PathTracker::Target t = tracker_.update(point_of(pose), lookahead_m_, 1.0);
  const navi::Point2D end = tracker_.points().empty() ? point_of(pose) : tracker_.points().back();
  if (std::hypot(end.x_m - pose.x_m, end.y_m - pose.y_m) <= goal_tol_m_) {
    succeed();
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
      "(offset growing each round), marks cleaned cells, succeeds when the section is covered",
      {"map_from_base", "laser_scan", "grid_map"}, cleaning_parameters());
  return m;
}

const ModuleManifest& BhCleaningTwoWheel::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhCleaningTwoWheel",
      "Wall-following full coverage of a section on a two-wheel differential base: turns toward the "
      "balloon path and drives forward, marks cleaned cells, succeeds when the section is covered",
      {"map_from_base", "laser_scan", "grid_map"}, cleaning_parameters());
  return m;
}

void CCleaningBehavior::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  configure_following(params, context);
  section_ = nullptr;
  progress_ = nullptr;
  if (needs_holonomic_ && !context.base.holonomic()) {
    fail("BhCleaning needs an omni-directional base");
    return;
  }
  section_ = workspace_.section(params.string("section"));
  if (section_ == nullptr) {
    fail("unknown section");
    return;
  }
  if (context.navi == nullptr) {
    fail("not localized");
    return;
  }
  progress_ = &workspace_.progress(*section_, point_of(context.navi->map_from_base));
  tracker_.reset(progress_->plan.path, progress_->done_m);
  detouring_ = false;
  // The reachable cells of the section, for section_coverage(): those the plan can clean.
  navi::CleanedCells reach(workspace_.grid());
  reach.mark_path(progress_->plan.path, workspace_.options().cleaning_width_m / 2.0);
  reachable_.clear();
  for (const std::size_t i : section_->cells) {
    if (reach.cleaned(i)) reachable_.push_back(i);
  }
}

double CCleaningBehavior::section_coverage() const noexcept { return workspace_.cleaned().coverage(reachable_); }

std::optional<Twist2D> CCleaningBehavior::on_step(const BehaviorContext& context) noexcept {
  if (context.navi == nullptr || !context.navi->localized) {
    has_last_ = false;  // the estimate is not trusted: mark nothing
    return Twist2D{};
  }
  const Pose2D pose = context.navi->map_from_base;
  const double half = workspace_.options().cleaning_width_m / 2.0;
  if (has_last_) workspace_.cleaned().mark_segment(point_of(last_pose_), point_of(pose), half);
  else workspace_.cleaned().mark_disc(point_of(pose), half);
  last_pose_ = pose;
  has_last_ = true;
  if (detouring_) {
    const PathTracker::Target d = detour_.update(point_of(pose), lookahead_m_, 1.0);
    const navi::Point2D end = detour_.points().back();
    if (d.remaining_m < 0.05 && std::hypot(end.x_m - pose.x_m, end.y_m - pose.y_m) < 0.1) {
      detouring_ = false;  // back on the coverage path, beyond the obstacle
      tracker_.jump_to(resume_m_);
    } else {
      return drive_toward(pose, d, context);
    }
  }
  const PathTracker::Target t = tracker_.update(point_of(pose), lookahead_m_, 0.6);
  progress_->done_m = tracker_.progress_m();
  const navi::Point2D end = tracker_.points().empty() ? point_of(pose) : tracker_.points().back();
  if (t.remaining_m < 0.05 && std::hypot(end.x_m - pose.x_m, end.y_m - pose.y_m) < 0.1) {
    progress_->finished = true;
    succeed();
    return Twist2D{};
  }
  return drive_toward(pose, t, context);
}

void CCleaningBehavior::plan_around_obstacle(const Pose2D& pose, Time now) noexcept {
  try {
    const std::size_t before = seen_obstacles_.size();
    note_unmapped_returns(pose, now, kObstacleRange_m);
    if (seen_obstacles_.size() == before) return;
    // The first point of the coverage path beyond the progress that is clear of everything
    // seen, by the robot radius, the detour margin and the depth the laser could not see.
    const double keep = workspace_.options().robot_radius_m + kDetourMargin_m + kResumeClearance_m;
    const double keep2 = keep * keep;
    double resume = -1.0;
    for (double s = tracker_.progress_m() + 0.1; s <= tracker_.length_m(); s += 0.05) {
      const navi::Point2D p = tracker_.at(s);
      const bool clear = std::none_of(seen_obstacles_.begin(), seen_obstacles_.end(), [&](const navi::Point2D& o) {
        return (o.x_m - p.x_m) * (o.x_m - p.x_m) + (o.y_m - p.y_m) * (o.y_m - p.y_m) < keep2;
      });
      if (clear) {
        resume = s;
        break;
      }
    }
    if (resume < 0.0) resume = tracker_.length_m();  // the rest of the path is behind the obstacle
    navi::PlannedPath plan =
        workspace_.planner().plan_around(point_of(pose), tracker_.at(resume), seen_obstacles_, kDetourMargin_m);
    if (!plan.ok()) return;  // no way around yet: wait; the obstacle may go before blocked_timeout_s
    detour_.reset(std::move(plan.waypoints));
    detouring_ = true;
    resume_m_ = resume;
    blocked_ = false;
  } catch (...) {
    // Out of memory while planning: keep going as before; the blocked timeout decides.
  }
}

void CCleaningBehavior::on_deactivate() noexcept {
  has_last_ = false;
  detouring_ = false;
}

// ---------------------------------------------------------------------------------------------
// BhGlobalLocalization

const ModuleManifest& BhGlobalLocalization::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhGlobalLocalization",
      "Turns in place and asks the localizer for a global position fix until one is accepted",
      {"laser_scan"},
      {number("yaw_rate_rad_s", 0.5, "rad/s", "Turning rate while searching", 0.0, 5.0),
       number("attempt_period_s", 2.0, "s", "Time between two position fixes asked of the localizer", 0.01, 60.0),
       number("timeout_s", 50.0, "s", "Fail with 'no position found' after this long", 0.1, 3600.0)});
  return m;
}

void BhGlobalLocalization::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  yaw_rate_ = params.number("yaw_rate_rad_s");
  attempt_ = from_seconds(params.number("attempt_period_s"));
  timeout_ = from_seconds(params.number("timeout_s"));
  started_ = context.now;
  last_attempt_ = context.now;
}

std::optional<Twist2D> BhGlobalLocalization::on_step(const BehaviorContext& context) noexcept {
  if (context.now - last_attempt_ >= attempt_) {
    last_attempt_ = context.now;
    if (workspace_.relocalize(context.now)) {
      succeed();
      return Twist2D{};
    }
  }
  if (context.now - started_ > timeout_) {
    fail("no position found");
    return Twist2D{};
  }
  return Twist2D{0.0, 0.0, yaw_rate_};
}

void register_navigation_behaviors(BehaviorRegistry& registry, NaviWorkspace& workspace) {
  registry.add(BhAutoMove::static_manifest(), [&workspace] { return std::unique_ptr<CBehavior>(std::make_unique<BhAutoMove>(workspace)); });
  registry.add(BhCleaning::static_manifest(), [&workspace] { return std::unique_ptr<CBehavior>(std::make_unique<BhCleaning>(workspace)); });
  registry.add(BhCleaningTwoWheel::static_manifest(),
               [&workspace] { return std::unique_ptr<CBehavior>(std::make_unique<BhCleaningTwoWheel>(workspace)); });
  registry.add(BhGlobalLocalization::static_manifest(),
               [&workspace] { return std::unique_ptr<CBehavior>(std::make_unique<BhGlobalLocalization>(workspace)); });
}

}  // namespace tripodal
