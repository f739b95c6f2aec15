#include "tripodal/navi/planning_modules.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tripodal::navi {

namespace {

// Planning around unexpected obstacles: laser returns within this range are taken as obstacles,
// the detour keeps this much more than the robot radius from them, and a cleaning detour takes
// the coverage path up again this far beyond them (the laser sees only the near face of a box).
constexpr double kObstacleRange_m = 3.0;
constexpr double kHazardSame_m = 0.02;  // hazard points closer than this to a known one add nothing
constexpr double kDetourMargin_m = 0.1;
constexpr double kResumeClearance_m = 0.3;

std::vector<std::string> split_names(const std::string& text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    std::string name = text.substr(at, comma - at);
    name.erase(0, name.find_first_not_of(' '));
    name.erase(name.find_last_not_of(' ') + 1);
    if (!name.empty()) out.push_back(std::move(name));
    at = comma + 1;
  }
  return out;
}

bool serves(const std::vector<std::string>& names, std::string_view behavior) {
  return std::find(names.begin(), names.end(), behavior) != names.end();
}

Point2D point_of(const Pose2D& p) noexcept { return {p.x_m, p.y_m}; }

}  // namespace

// ---------------------------------------------------------------------------------------------
// ObstacleReplanner, PublishedPath

void ObstacleReplanner::reset(const ParameterSet& behavior_params) {
  after_ = behavior_params.contains("replan_after_s") ? from_seconds(behavior_params.number("replan_after_s")) : Duration{0};
  max_ = behavior_params.contains("max_replans") ? static_cast<int>(behavior_params.number("max_replans")) : 0;
  attempts_ = 0;
  last_ = Time{};
  seen_.clear();
}

bool ObstacleReplanner::due(const NavigationFeedback& feedback, Time now) const noexcept {
  if (!feedback.blocked || after_ <= Duration{0} || attempts_ >= max_) return false;
  if (now - feedback.blocked_since < after_) return false;
  return attempts_ == 0 || now - last_ >= after_;
}

bool ObstacleReplanner::observe(const CGridMaps& maps, const ModuleContext& context) {
  ++attempts_;
  last_ = context.now;
  const std::size_t before = seen_.size();
  const LaserResource* laser = context.resources != nullptr ? context.resources->first<LaserScan>() : nullptr;
  if (laser != nullptr && laser->is_fresh(context.now)) {
    maps.unmapped_returns(laser->latest(), context.navigation->map_from_base, kObstacleRange_m, seen_);
  }
  // What the safety behaviors found (a drop, glass): obstacles the laser cannot see. A point
  // already known is not news.
  const NavigationFeedback& fb = context.feedback;
  for (std::size_t i = 0; i < fb.hazard_count; ++i) {
    const Point2D h{fb.hazards[i].x_m, fb.hazards[i].y_m};
    const bool known = std::any_of(seen_.begin(), seen_.end(), [&](const Point2D& o) {
      return (o.x_m - h.x_m) * (o.x_m - h.x_m) + (o.y_m - h.y_m) * (o.y_m - h.y_m) < kHazardSame_m * kHazardSame_m;
    });
    if (!known) seen_.push_back(h);
  }
  return seen_.size() != before;
}

void PublishedPath::publish(const std::vector<Point2D>& points, double start_m, bool final, ModuleContext& context,
                            const std::vector<double>& speeds_m_s) {
  points_.clear();
  s_.clear();
  speeds_ = speeds_m_s;
  for (const Point2D& p : points) {
    s_.push_back(points_.empty() ? 0.0 : s_.back() + std::hypot(p.x_m - points_.back().x_m, p.y_m - points_.back().y_m));
    points_.push_back({p.x_m, p.y_m, 0.0});
  }
  id_ = context.new_path_id();
  NavigationData& n = *context.navigation;
  n.path = points_;
  n.path_speed_m_s = speeds_;
  n.path_id = id_;
  n.path_start_m = start_m;
  n.path_final = final;
  n.path_failure = {};
  n.has_goal = !points_.empty();
  if (n.has_goal) n.goal = points_.back();
}

void PublishedPath::fail(std::string_view reason, ModuleContext& context) {
  points_.clear();
  s_.clear();
  id_ = context.new_path_id();
  NavigationData& n = *context.navigation;
  n.path = {};
  n.path_speed_m_s = {};
  n.path_id = id_;
  n.path_failure = reason;
  n.has_goal = false;
}

void PublishedPath::withdraw(ModuleContext& context) {
  NavigationData& n = *context.navigation;
  if (n.path_id != id_ || id_ == 0) return;  // another module's path is being followed now
  n.path = {};
  n.path_speed_m_s = {};
  n.path_id = 0;
  n.path_failure = {};
  n.has_goal = false;
  id_ = 0;
}

Point2D PublishedPath::at(double s) const noexcept {
  if (points_.empty()) return {};
  if (s <= 0.0) return point_of(points_.front());
  if (s >= s_.back()) return point_of(points_.back());
  const auto it = std::upper_bound(s_.begin(), s_.end(), s);
  const std::size_t j = static_cast<std::size_t>(it - s_.begin());
  const double len = s_[j] - s_[j - 1];
  const double t = len > 0.0 ? (s - s_[j - 1]) / len : 0.0;
  return {points_[j - 1].x_m + t * (points_[j].x_m - points_[j - 1].x_m), points_[j - 1].y_m + t * (points_[j].y_m - points_[j - 1].y_m)};
}

// ---------------------------------------------------------------------------------------------
// CPathPlanner

const ModuleManifest& CPathPlanner::static_manifest() {
  static const ModuleManifest m = navi_manifest(
      "PathPlanner",
      "plans the shortest collision-free path (A*) to a path-following behavior's goal and replans around "
      "obstacles the map does not hold",
      {"grid_map", "map_from_base", "laser_scan"}, {"path"},
      {ParameterSpec{"serves", ValueType::string, Value{std::string("BhAutoMove")}, "",
                     "the behaviors it plans for, comma separated (their parameter `goal` names the goal)", {}, {}}});
  return m;
}

void CPathPlanner::on_configure(const ParameterSet& params) {
  serves_ = split_names(params.string("serves"));
}

void CPathPlanner::on_start(ModuleContext& context) {
  maps_ = context.modules != nullptr ? context.modules->find<CGridMaps>() : nullptr;
  if (maps_ == nullptr) throw ConfigError(where(), "PathPlanner needs the robot's map: add a GridMaps module");
  splitter_ = context.modules->find<CSectionSplitter>();
  coverage_ = context.modules->find<CCoveragePlanner>();
}

std::optional<Point2D> CPathPlanner::resolve_goal(std::string_view name, Point2D from) {
  constexpr std::string_view kEntry = ".entry";
  if (name.size() > kEntry.size() && name.substr(name.size() - kEntry.size()) == kEntry) {
    const Section* s = splitter_ != nullptr ? splitter_->section(name.substr(0, name.size() - kEntry.size())) : nullptr;
    if (s == nullptr) return std::nullopt;
    if (coverage_ == nullptr) return s->centroid;
    const CoverageResult& plan = coverage_->entry_plan(*s, from);
    return plan.path.empty() ? s->centroid : plan.path.front();
  }
  const RegionMap& regions = maps_->regions();
  if (const MapNode* n = regions.node(name)) return Point2D{n->pose.x_m, n->pose.y_m};
  if (splitter_ != nullptr) {
    if (const Section* s = splitter_->section(name)) return s->centroid;
  }
  if (const Region* r = regions.room(name)) {
    Point2D c;
    for (const auto& p : r->polygon) {
      c.x_m += p.x_m / static_cast<double>(r->polygon.size());
      c.y_m += p.y_m / static_cast<double>(r->polygon.size());
    }
    return c;
  }
  return std::nullopt;
}

void CPathPlanner::on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) {
  if (!serves(serves_, activation.behavior)) return;
  active_ = true;
  const ParameterSet params = activation.resolved();
  replanner_.reset(params);
  const Point2D from = point_of(context.navigation->map_from_base);
  const std::optional<Point2D> goal = resolve_goal(params.string("goal"), from);
  if (!goal) {
    path_.fail("unknown goal", context);
    return;
  }
  PlannedPath plan = maps_->planner().plan(from, *goal);
  if (!plan.ok()) {
    // The behavior's reason is static text (NavigationData::path_failure); where the robot stood
    // and why the planner refused go to the log.
    spdlog::warn("PathPlanner: no path to '{}' from ({:.3f}, {:.3f}): {}", params.string("goal"), from.x_m, from.y_m,
                 plan.message);
    path_.fail("no path to the goal", context);
    return;
  }
  goal_ = *goal;
  path_.publish(plan.waypoints, 0.0, true, context);
}

void CPathPlanner::on_update(ModuleContext& context) {
  if (!active_ || context.feedback.path_id != path_.id() || !replanner_.due(context.feedback, context.now)) return;
  if (!replanner_.observe(*maps_, context)) return;  // nothing new seen: the same plan again
  PlannedPath plan = maps_->planner().plan_around(point_of(context.navigation->map_from_base), goal_, replanner_.obstacles(),
                                                  kDetourMargin_m);
  // No way around (yet): the behavior waits, the obstacle may go, until its blocked timeout.
  if (plan.ok()) path_.publish(plan.waypoints, 0.0, true, context);
}

void CPathPlanner::on_behavior_deactivated(std::string_view behavior, ModuleContext& context) {
  if (!serves(serves_, behavior)) return;
  active_ = false;
  path_.withdraw(context);
}

// ---------------------------------------------------------------------------------------------
// CCoveragePlanner

const ModuleManifest& CCoveragePlanner::static_manifest() {
  static const ModuleManifest m = navi_manifest(
      "CoveragePlanner",
      "gives the cleaning behaviors their section's coverage path (hybrid: a balloon round along walls and "
      "obstacles, lanes inside; or the paper's balloon, or the boustrophedon), resumes where a section stopped, plans detours, "
      "records the cleaned cells",
      {"grid_map", "sections", "map_from_base", "laser_scan"}, {"coverage_path", "cleaned_cells"},
      {ParameterSpec{"cleaning_width_m", ValueType::number, Value{0.4}, "m", "diameter of the cleaning footprint", 0.01, 5.0},
       ParameterSpec{"overlap_m", ValueType::number, Value{0.05}, "m", "overlap of neighbouring coverage rounds", 0.0, 1.0},
       ParameterSpec{"lane_overlap_m", ValueType::number, Value{CoverageOptions{}.lane_overlap_m}, "m",
                     "hybrid: overlap of neighbouring lanes (absorbs the robot's tracking and localization error)", 0.0, 1.0},
       ParameterSpec{"lane_inset_m", ValueType::number, Value{CoverageOptions{}.lane_inset_m}, "m",
                     "hybrid: how far inside the wall round's centre line the lanes end (0: one cell)", 0.0, 5.0},
       ParameterSpec{"turn_cost_m", ValueType::number, Value{CoverageOptions{}.turn_cost_m}, "m",
                     "hybrid: the travel a turn weighs when the lane direction is chosen", 0.0, 100.0},
       ParameterSpec{"link_margin_m", ValueType::number, Value{CoverageOptions{}.link_margin_m}, "m",
                     "links between passes keep this much more than the robot radius from obstacles where the way "
                     "allows (0: the robot radius)",
                     0.0, 1.0},
       ParameterSpec{"pattern",
                     ValueType::string,
                     Value{std::string("hybrid")},
                     "",
                     "hybrid (a wall-following round, then lanes), balloon (the paper's wall-following rounds) or "
                     "boustrophedon (plough lanes)",
                     {},
                     {}},
       ParameterSpec{"serves",
                     ValueType::string,
                     Value{std::string("BhCleaning, BhCleaningTwoWheel")},
                     "",
                     "the behaviors it gives coverage paths to, comma separated (their parameter `section`)",
                     {},
                     {}},
       ParameterSpec{"dose_target_j_m2", ValueType::number, Value{0.0}, "J/m^2",
                     "UV disinfection: the dose every point between the lanes must get; lanes spaced and speeds "
                     "limited for it from the lamp (docs/coverage.md, \"A dose that is reached\"). 0: off",
                     0.0, 1e6},
       ParameterSpec{"uv_power_w", ValueType::number, Value{UvLamp{}.uvc_power_w}, "W", "the UV lamp's UVC output", 0.0, 1000.0,
                     true},
       ParameterSpec{"uv_height_m", ValueType::number, Value{UvLamp{}.height_m}, "m", "the UV lamp above the floor", 0.0, 1.0,
                     true},
       ParameterSpec{"uv_radius_m", ValueType::number, Value{UvLamp{}.radius_m}, "m", "the UV lamp's lit disc on the floor", 0.0,
                     5.0, true},
       ParameterSpec{"dose_min_speed_m_s", ValueType::number, Value{DoseLimits{}.min_speed_m_s}, "m/s",
                     "the slowest lane speed the plan may ask for", 0.0, 5.0, true},
       ParameterSpec{"dose_max_speed_m_s", ValueType::number, Value{DoseLimits{}.max_speed_m_s}, "m/s",
                     "the fastest lane speed (the cleaning behavior's cruise speed)", 0.0, 5.0, true},
       ParameterSpec{"dose_max_passes", ValueType::number, Value{static_cast<double>(DoseLimits{}.max_passes)}, "",
                     "passes over the same lanes the plan may ask for", 1.0, 10.0},
       ParameterSpec{"dose_tracking_error_m", ValueType::number, Value{DoseLimits{}.tracking_error_m}, "m",
                     "lanes may lie this much farther apart than planned (tracking error, cells)", 0.0, 0.5}});
  return m;
}

void CCoveragePlanner::on_configure(const ParameterSet& params) {
  options_.cleaning_width_m = params.number("cleaning_width_m");
  options_.overlap_m = params.number("overlap_m");
  options_.lane_overlap_m = params.number("lane_overlap_m");
  options_.turn_cost_m = params.number("turn_cost_m");
  options_.lane_inset_m = params.number("lane_inset_m");
  options_.link_margin_m = params.number("link_margin_m");
  const std::string& pattern = params.string("pattern");
  if (pattern != "hybrid" && pattern != "balloon" && pattern != "boustrophedon") {
    throw ConfigError(where(), "CoveragePlanner: pattern must be hybrid, balloon or boustrophedon, not '" + pattern + "'");
  }
  pattern_ = pattern;
  serves_ = split_names(params.string("serves"));
  footprint_width_m_ = options_.cleaning_width_m;
  lamp_ = UvLamp{params.number("uv_power_w"), params.number("uv_height_m"), params.number("uv_radius_m")};
  dose_limits_.min_speed_m_s = params.number("dose_min_speed_m_s");
  dose_limits_.max_speed_m_s = params.number("dose_max_speed_m_s");
  dose_limits_.max_passes = static_cast<int>(params.number("dose_max_passes"));
  dose_limits_.tracking_error_m = params.number("dose_tracking_error_m");
  dose_plan_.reset();
  if (const double target = params.number("dose_target_j_m2"); target > 0.0) {
    if (pattern_ != "hybrid")
      throw ConfigError(where(), "CoveragePlanner: dose_target_j_m2 plans lanes: it needs pattern hybrid");
    // Lanes on grid rows, at most the lit disc's diameter apart.
    dose_limits_.max_spacing_m = std::max(dose_limits_.min_spacing_m, 2.0 * lamp_.radius_m);
    try {
      dose_plan_ = plan_dose(lamp_, target, dose_limits_);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(where(), std::string("CoveragePlanner: ") + e.what());
    }
    // The hybrid planner spaces lanes cleaning_width - lane_overlap apart.
    options_.cleaning_width_m = dose_plan_->spacing_m + options_.lane_overlap_m;
  }
  planner_.reset();
}

void CCoveragePlanner::on_start(ModuleContext& context) {
  maps_ = context.modules != nullptr ? context.modules->find<CGridMaps>() : nullptr;
  if (maps_ == nullptr) throw ConfigError(where(), "CoveragePlanner needs the robot's map: add a GridMaps module");
  splitter_ = context.modules->find<CSectionSplitter>();
  if (splitter_ == nullptr) throw ConfigError(where(), "CoveragePlanner needs the sections: add a SectionSplitter module");
  cleaned_ = CleanedCells(maps_->grid());
  (void)planner();  // built now, not in the first period that needs it
}

CoveragePlanner& CCoveragePlanner::planner() {
  if (!planner_) {
    CoverageOptions o = options_;
    o.robot_radius_m = maps_->robot_radius_m();
    planner_.emplace(maps_->grid(), o);
  }
  return *planner_;
}

CoverageResult CCoveragePlanner::plan(const Section& section, Point2D from) {
  if (pattern_ == "boustrophedon") return planner().boustrophedon(section, from);
  if (pattern_ == "balloon") return planner().balloon(section, from);
  CoverageResult r = planner().hybrid(section, from, next_section_centroid(section));
  if (dose_plan_) {
    // The grid quantises lanes to cells: the planner's real spacing is one cell finer than the
    // plan's at most, never wider (hybrid spreads lanes at most one spacing apart).
    DosePath driven = dose_path(r.path, lamp_, *dose_plan_, dose_limits_, 2.0 * dose_plan_->spacing_m);
    r.path = std::move(driven.path);
    r.speed_m_s = std::move(driven.speed_m_s);
    // Further passes go back over the same path, reversed (no walk back to the start).
    const std::vector<Point2D> one = r.path;
    const std::vector<double> speeds = r.speed_m_s;
    for (int k = 1; k < dose_plan_->passes; ++k) {
      const bool back = k % 2 == 1;
      for (std::size_t i = 1; i < one.size(); ++i) {
        const std::size_t j = back ? one.size() - 1 - i : i;
        r.path.push_back(one[j]);
        // The leg arriving at one[j] backwards is the leg leaving it forwards (j to j + 1).
        r.speed_m_s.back() = back ? speeds[j] : speeds[j - 1];
        r.speed_m_s.push_back(speeds[j]);
      }
    }
  }
  return r;
}

std::optional<Point2D> CCoveragePlanner::next_section_centroid(const Section& section) const {
  // The planner visits a room's sections nearest first (CSectionSplitter::on_answer), so the
  // next one is most likely the nearest section not cleaned yet; a path that ends on its side
  // saves the walk across this one.
  std::optional<Point2D> next;
  double best = std::numeric_limits<double>::infinity();
  for (const Section& s : splitter_->sections().sections) {
    if (s.name == section.name) continue;
    if (const auto p = progress_.find(s.name); p != progress_.end() && p->second.finished) continue;
    const double d = std::hypot(s.centroid.x_m - section.centroid.x_m, s.centroid.y_m - section.centroid.y_m);
    if (d < best) {
      best = d;
      next = s.centroid;
    }
  }
  return next;
}

const CoverageResult& CCoveragePlanner::entry_plan(const Section& section, Point2D from) {
  if (auto p = progress_.find(section.name); p != progress_.end() && !p->second.finished) return p->second.plan;
  auto it = entry_plans_.find(section.name);
  if (it == entry_plans_.end()) it = entry_plans_.emplace(section.name, plan(section, from)).first;
  return it->second;
}

double CCoveragePlanner::section_coverage(const Section& section) const {
  const auto it = progress_.find(section.name);
  if (it == progress_.end() || !maps_) return 0.0;
  CleanedCells reach(maps_->grid());
  reach.mark_path(it->second.plan.path, options_.cleaning_width_m / 2.0);
  std::vector<std::size_t> cells;
  for (const std::size_t i : section.cells) {
    if (reach.cleaned(i)) cells.push_back(i);
  }
  return cleaned_.coverage(cells);
}

void CCoveragePlanner::on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) {
  if (!serves(serves_, activation.behavior)) return;
  const ParameterSet params = activation.resolved();
  replanner_.reset(params);
  detouring_ = false;
  has_last_ = false;
  const Section* section = splitter_->section(params.string("section"));
  if (section == nullptr) {
    active_ = nullptr;
    coverage_path_.fail("unknown section", context);
    return;
  }
  const Point2D from = point_of(context.navigation->map_from_base);
  auto it = progress_.find(section->name);
  if (it == progress_.end() || it->second.finished) {
    SectionProgress p;
    if (auto e = entry_plans_.find(section->name); e != entry_plans_.end()) {
      p.plan = std::move(e->second);  // the entry BhAutoMove went to is this path's first point
      entry_plans_.erase(e);
    } else {
      p.plan = plan(*section, from);
    }
    it = progress_.insert_or_assign(section->name, std::move(p)).first;
  }
  active_ = &it->second;
  coverage_path_.publish(active_->plan.path, active_->done_m, true, context, active_->plan.speed_m_s);
  rejoin(from, context);
}

void CCoveragePlanner::rejoin(Point2D from, ModuleContext& context) {
  // The follower steers straight at the path's next point: from where a kidnapping (or a
  // recovery that moved the robot) left it, that line may pass an obstacle of the map at any
  // distance, and the laser watch ignores what the map holds. The way back goes round it.
  const Point2D back = coverage_path_.at(active_->done_m);
  PathPlanner& pp = planner().planner();
  const auto a = pp.grid().world_to_cell(from);
  const auto b = pp.grid().world_to_cell(back);
  if (!a || !b || (*a == *b)) return;
  const double keep = pp.leg_clearance_m(*a, *b);
  if (pp.line_of_sight(*a, *b, keep)) return;
  PlannedPath plan = pp.plan(*a, *b, keep);
  if (plan.ok()) {
    plan.waypoints.front() = from;
    plan.waypoints.back() = back;
  }
  if (!plan.ok()) return;  // the follower's straight line, as before
  detour_.publish(plan.waypoints, 0.0, false, context);
  detouring_ = true;
  resume_m_ = active_->done_m;
}

void CCoveragePlanner::on_update(ModuleContext& context) {
  if (active_ == nullptr) return;
  const NavigationData& navi = *context.navigation;
  // The cleaned cells: under the footprint, from the pose the robot trusts.
  if (navi.localized) {
    const double half = options_.cleaning_width_m / 2.0;
    if (has_last_) cleaned_.mark_segment(point_of(last_pose_), point_of(navi.map_from_base), half);
    else cleaned_.mark_disc(point_of(navi.map_from_base), half);
    last_pose_ = navi.map_from_base;
    has_last_ = true;
  } else {
    has_last_ = false;
  }
  const NavigationFeedback& fb = context.feedback;
  if (fb.path_id == coverage_path_.id() && fb.path_id != 0) {
    active_->done_m = fb.progress_m;
    if (fb.reached_end) active_->finished = true;
  } else if (detouring_ && fb.path_id == detour_.id() && fb.reached_end) {
    detouring_ = false;  // back on the coverage path, beyond the obstacle
    active_->done_m = std::max(active_->done_m, resume_m_);
    coverage_path_.publish(active_->plan.path, active_->done_m, true, context, active_->plan.speed_m_s);
    return;
  }
  const bool following = fb.path_id != 0 && (fb.path_id == coverage_path_.id() || fb.path_id == detour_.id());
  if (following && replanner_.due(fb, context.now)) plan_detour(navi.map_from_base, context);
}

void CCoveragePlanner::plan_detour(const Pose2D& pose, ModuleContext& context) {
  if (!replanner_.observe(*maps_, context)) return;
  // The first point of the coverage path beyond the progress that is clear of everything seen,
  // by the robot radius, the detour margin and the depth the laser could not see.
  const double keep = maps_->robot_radius_m() + kDetourMargin_m + kResumeClearance_m;
  const double keep2 = keep * keep;
  const auto& seen = replanner_.obstacles();
  double resume = -1.0;
  for (double s = active_->done_m + 0.1; s <= coverage_path_.length_m(); s += 0.05) {
    const Point2D p = coverage_path_.at(s);
    const bool clear = std::none_of(seen.begin(), seen.end(), [&](const Point2D& o) {
      return (o.x_m - p.x_m) * (o.x_m - p.x_m) + (o.y_m - p.y_m) * (o.y_m - p.y_m) < keep2;
    });
    if (clear) {
      resume = s;
      break;
    }
  }
  if (resume < 0.0) resume = coverage_path_.length_m();  // the rest of the path is behind the obstacle
  PlannedPath plan = maps_->planner().plan_around(point_of(pose), coverage_path_.at(resume), seen, kDetourMargin_m);
  if (!plan.ok()) return;  // no way around yet: the behavior waits; the obstacle may go before its timeout
  detour_.publish(plan.waypoints, 0.0, false, context);
  detouring_ = true;
  resume_m_ = resume;
}

void CCoveragePlanner::on_behavior_deactivated(std::string_view behavior, ModuleContext& context) {
  if (!serves(serves_, behavior)) return;
  active_ = nullptr;
  detouring_ = false;
  has_last_ = false;
  coverage_path_.withdraw(context);
  detour_.withdraw(context);
}

}  // namespace tripodal::navi
