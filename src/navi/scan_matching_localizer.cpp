#include "tripodal/navi/scan_matching_localizer.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/resources/resource.hpp"

namespace tripodal::navi {

CScanMatchingLocalizer::CScanMatchingLocalizer(ScanMatchingLocalizerOptions options) : options_(options) {
  pose_ = options_.initial_pose;
  need_global_ = options_.start_global;
}

CScanMatchingLocalizer::~CScanMatchingLocalizer() = default;

const ModuleManifest& CScanMatchingLocalizer::static_manifest() {
  const ScanMatchingLocalizerOptions d;
  static const ModuleManifest m = navi_manifest(
      "ScanMatchingLocalizer",
      "pose from the odometry corrected by matching each laser scan against the map (likelihood field, "
      "correlative search; branch-and-bound global search); posts localizer.ok / localizer.lost from the match "
      "quality",
      {"grid_map", "laser_scan", "odometry"}, {"map_from_base", "position_fix", "localizer.ok", "localizer.lost"},
      {ParameterSpec{"laser", ValueType::string, Value{std::string()}, "", "laser resource (empty: the first)", {}, {}},
       ParameterSpec{"odometry", ValueType::string, Value{std::string()}, "", "odometry resource (empty: the first)",
                     {}, {}},
       ParameterSpec{"laser_x_m", ValueType::number, Value{0.0}, "m", "scanner position on the base, forward", {}, {}},
       ParameterSpec{"laser_y_m", ValueType::number, Value{0.0}, "m", "scanner position on the base, leftward", {}, {}},
       ParameterSpec{"laser_yaw_rad", ValueType::number, Value{0.0}, "rad", "scanner heading on the base", {}, {}},
       ParameterSpec{"initial_x_m", ValueType::number, Value{0.0}, "m", "start pose in the map", {}, {}},
       ParameterSpec{"initial_y_m", ValueType::number, Value{0.0}, "m", "start pose in the map", {}, {}},
       ParameterSpec{"initial_theta_rad", ValueType::number, Value{0.0}, "rad", "start heading in the map", {}, {}},
       ParameterSpec{"start_global", ValueType::boolean, Value{false}, "",
                     "find the start pose by a global search on the first scan", {}, {}},
       ParameterSpec{"sigma_m", ValueType::number, Value{d.matcher.sigma_m}, "m",
                     "spread of the likelihood field around the walls", 0.005, 2.0},
       ParameterSpec{"max_range_m", ValueType::number, Value{d.matcher.max_range_m}, "m",
                     "returns beyond are not matched", 0.1, 500.0},
       ParameterSpec{"max_points", ValueType::number, Value{static_cast<double>(d.matcher.max_points)}, "",
                     "points matched per scan (decimated evenly)", 3.0, 100000.0},
       ParameterSpec{"search_xy_m", ValueType::number, Value{d.matcher.search_xy_m}, "m",
                     "half width of the tracking window", 0.0, 5.0},
       ParameterSpec{"search_theta_rad", ValueType::number, Value{d.matcher.search_theta_rad}, "rad",
                     "half width of the tracking window in heading", 0.0, 3.15},
       ParameterSpec{"surface_at_cell_face", ValueType::boolean, Value{d.matcher.surface_at_cell_face}, "",
                     "the map's walls are solid cells (a drawn map, the simulator's world): a wall's surface is an "
                     "occupied cell's face; false: inside the cell, at its centre on average (a map built from scans)",
                     {}, {}},
       ParameterSpec{"odometry_reset_m", ValueType::number, Value{d.odometry_reset_m}, "m",
                     "an odometry increment longer than this between two scans is a reset, not motion (0: never)",
                     0.0, 100.0},
       ParameterSpec{"lost_quality", ValueType::number, Value{d.lost_quality}, "",
                     "match quality (mean likelihood of the points, 0..1) below which a scan is no evidence", 0.0,
                     1.0},
       ParameterSpec{"lost_after_scans", ValueType::number, Value{static_cast<double>(d.lost_after_scans)}, "",
                     "scans in a row below lost_quality that make the robot lost", 1.0, 100000.0},
       ParameterSpec{"relocalize_quality", ValueType::number, Value{d.relocalize_quality}, "",
                     "quality a global search must reach to be accepted", 0.0, 1.0},
       ParameterSpec{"consistency_margin", ValueType::number, Value{d.consistency_margin}, "",
                     "a match this far below the median of the recent ones, and far from the odometry's prediction, "
                     "is not taken (unreliable)", 0.0, 1.0},
       ParameterSpec{"odometry_tolerance_m", ValueType::number, Value{d.odometry_tolerance_m}, "m",
                     "a correction of the odometry within this (plus 0.3 m per metre moved) agrees with it", 0.0,
                     100.0},
       ParameterSpec{"odometry_tolerance_rad", ValueType::number, Value{d.odometry_tolerance_rad}, "rad",
                     "a heading correction within this (plus 0.3 rad per radian turned) agrees with the odometry",
                     0.0, 3.15},
       ParameterSpec{"retry_quality", ValueType::number, Value{d.window.retry_quality}, "",
                     "below this quality a scan is searched again in the widest window", 0.0, 1.0},
       ParameterSpec{"serves", ValueType::string, Value{std::string("BhGlobalLocalization")}, "",
                     "the behavior during whose activation it runs the global search (its parameter "
                     "attempt_period_s)", {}, {}}});
  return m;
}

void CScanMatchingLocalizer::on_configure(const ParameterSet& params) {
  ScanMatchingLocalizerOptions o;
  o.base_from_laser = {params.number("laser_x_m"), params.number("laser_y_m"), params.number("laser_yaw_rad")};
  o.initial_pose = {params.number("initial_x_m"), params.number("initial_y_m"), params.number("initial_theta_rad")};
  o.start_global = params.boolean("start_global");
  o.matcher.sigma_m = params.number("sigma_m");
  o.matcher.max_range_m = params.number("max_range_m");
  o.matcher.max_points = static_cast<int>(params.number("max_points"));
  o.matcher.search_xy_m = params.number("search_xy_m");
  o.matcher.search_theta_rad = params.number("search_theta_rad");
  o.matcher.surface_at_cell_face = params.boolean("surface_at_cell_face");
  o.odometry_reset_m = params.number("odometry_reset_m");
  o.lost_quality = params.number("lost_quality");
  o.lost_after_scans = static_cast<int>(params.number("lost_after_scans"));
  o.relocalize_quality = params.number("relocalize_quality");
  o.consistency_margin = params.number("consistency_margin");
  o.odometry_tolerance_m = params.number("odometry_tolerance_m");
  o.odometry_tolerance_rad = params.number("odometry_tolerance_rad");
  o.window.retry_quality = params.number("retry_quality");
  validate(o.matcher, where());
  laser_name_ = params.string("laser");
  odometry_name_ = params.string("odometry");
  fix_attempts_.serves = params.string("serves");
  options_ = o;
  pose_ = o.initial_pose;
  need_global_ = o.start_global;
  last_odom_.reset();
  state_ = State::unknown;
  low_scans_ = 0;
  qualities_.clear();
  unreliable_ = 0;
  verdict_ = ScanVerdict::kNone;
  matcher_.reset();
}

void CScanMatchingLocalizer::set_map(const OccupancyGrid& map) {
  matcher_ = std::make_unique<ScanMatcher>(map, options_.matcher, where());
}

void CScanMatchingLocalizer::on_start(ModuleContext& context) {
  if (!matcher_) {
    const CGridMaps* maps = context.modules != nullptr ? context.modules->find<CGridMaps>() : nullptr;
    if (maps == nullptr) {
      throw ConfigError(where(), "ScanMatchingLocalizer matches scans against the map of a GridMaps module, and the "
                                 "robot has none: add a module of type GridMaps before it");
    }
    set_map(maps->grid());
  }
  laser_ = &sensor_of<LaserScan>(context, laser_name_, "ScanMatchingLocalizer", "a laser scanner", "laser", where());
  odometry_ = &sensor_of<OdometryReading>(context, odometry_name_, "ScanMatchingLocalizer", "odometry", "odometry", where());
}

void CScanMatchingLocalizer::post(State next, Time now, std::vector<ModuleEvent>& out) {
  if (next == state_) return;
  state_ = next;
  const bool ok = next == State::ok;
  std::ostringstream msg;
  msg.precision(3);
  msg << (ok ? "the scan matches the map" : "the scans stopped matching the map") << " (quality " << last_.quality
      << ", threshold " << options_.lost_quality << ")";
  out.push_back({now, ok ? "localizer.ok" : "localizer.lost", msg.str()});
}

void CScanMatchingLocalizer::step(const LaserScan& scan, const Pose2D& odom_from_base, Time now,
                                  std::vector<ModuleEvent>& out) {
  if (!matcher_) return;
  Pose2D motion;
  if (last_odom_) {
    motion = compose(inverse(*last_odom_), odom_from_base);
    // More than the widest tracking window between two scans is no motion the base made: the
    // odometry was reset (as `tripodal run` does to the start pose after the first reading).
    if (!plausible(motion)) motion = Pose2D{};
    pose_ = compose(pose_, motion);
  }
  last_odom_ = odom_from_base;
  stamp_ = now;
  matcher_->set_scan(scan, options_.base_from_laser);
  if (need_global_) {
    need_global_ = false;
    if (!relocalize()) {
      last_.quality = 0.0;
      post(State::lost, now, out);
      return;
    }
  }
  ScanMatch m = matcher_->track(pose_, motion, options_.window);
  // Judged on what the map can explain: a cart beside the robot hides a quarter of its scan and
  // is no sign of a wrong pose (the pose itself comes from the match, the cart's points pull
  // nowhere).
  m.quality = matcher_->explained_quality(m.pose);
  last_ = m;
  verdict_ = judge(m, motion);
  if (verdict_ == ScanVerdict::kConsistent) {
    pose_ = m.pose;
    low_scans_ = 0;
    qualities_.add(m.quality);
    post(State::ok, now, out);
    return;
  }
  // No evidence, or evidence at odds with the odometry: keep dead reckoning, and after enough
  // scans in a row say so.
  ++unreliable_;
  if (++low_scans_ >= options_.lost_after_scans) post(State::lost, now, out);
}

ScanVerdict CScanMatchingLocalizer::judge(const ScanMatch& m, const Pose2D& motion) const noexcept {
  if (m.quality < options_.lost_quality) return ScanVerdict::kNoEvidence;
  const double typical = typical_quality();
  if (typical <= 0.0 || m.quality >= typical - options_.consistency_margin) return ScanVerdict::kConsistent;
  // weaker than usual: taken only where the odometry put the robot
  const Pose2D correction = compose(inverse(pose_), m.pose);
  const double moved_m = std::hypot(motion.x_m, motion.y_m), turned = std::abs(motion.theta_rad);
  const double k = options_.tolerance_per_motion;
  const bool agrees = std::hypot(correction.x_m, correction.y_m) <= options_.odometry_tolerance_m + k * moved_m &&
                      std::abs(correction.theta_rad) <= options_.odometry_tolerance_rad + k * turned;
  return agrees ? ScanVerdict::kConsistent : ScanVerdict::kInconsistent;
}


bool CScanMatchingLocalizer::plausible(const Pose2D& motion) const noexcept {
  // Translation only: a base turns fast between scans, while a reset moves the origin by metres.
  return options_.odometry_reset_m <= 0.0 || std::hypot(motion.x_m, motion.y_m) <= options_.odometry_reset_m;
}

bool CScanMatchingLocalizer::relocalize() {
  if (!matcher_ || matcher_->points() == 0) return false;
  ScanMatch m = matcher_->match_global();
  m.quality = matcher_->explained_quality(m.pose);
  if (m.quality < options_.relocalize_quality) return false;
  pose_ = m.pose;
  last_ = m;
  low_scans_ = 0;
  verdict_ = ScanVerdict::kConsistent;
  return true;
}

void CScanMatchingLocalizer::publish(NavigationData& data) const noexcept {
  data.map_from_base = pose_;
  data.pose_stamp = stamp_;
  data.pose_covariance = last_.covariance;
  data.localized = localized();
}

void CScanMatchingLocalizer::on_update(ModuleContext& context) {
  const LaserScan& scan = laser_->latest();
  if (laser_->has_reading() && (!has_scan_ || scan.stamp != last_scan_stamp_)) {
    has_scan_ = true;
    last_scan_stamp_ = scan.stamp;
    step(scan, odometry_->latest().pose, context.now, context.events);
  }
  if (has_scan_ && fix_attempts_.due(context.now) && relocalize()) ++fixes_;
  context.heartbeat = true;
  publish(*context.navigation);
  // The scans come at a few hertz, the sequencing loop runs at 20: between two scans the pose
  // goes on with the odometry since the last one (else the estimate lags the robot by up to a
  // scan period, centimetres at cleaning speed).
  if (last_odom_ && odometry_->has_reading()) {
    const Pose2D since_scan = compose(inverse(*last_odom_), odometry_->latest().pose);
    if (plausible(since_scan)) {
      context.navigation->map_from_base = compose(pose_, since_scan);
      context.navigation->pose_stamp = context.now;
    }
  }
  context.navigation->fixes = fixes_;
}

void CScanMatchingLocalizer::on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) {
  fix_attempts_.activated(activation, context.now);
}

void CScanMatchingLocalizer::on_behavior_deactivated(std::string_view behavior, ModuleContext& /*context*/) {
  fix_attempts_.deactivated(behavior);
}

}  // namespace tripodal::navi
