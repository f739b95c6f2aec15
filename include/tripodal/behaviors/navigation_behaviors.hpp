// The navigation behaviors of the cleaning robots (reactive layer): BhAutoMove (follow a planned
// path to a goal), BhCleaning / BhCleaningTwoWheel (the paper's wall-following full coverage of
// one section, omni and differential) and BhGlobalLocalization. They read the map, sections and
// cleaned-cell record of the sequencing layer through a NaviWorkspace the robot program owns.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/path_planner.hpp"
#include "tripodal/navi/regions.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal {

struct NaviWorkspaceOptions {
  /// Radius of the robot's body disc: obstacles are inflated by it for path planning.
  double robot_radius_m = 0.25;
  /// Diameter of the cleaning footprint (a disc centred on the robot).
  double cleaning_width_m = 0.4;
  /// Overlap of neighbouring coverage rounds.
  double overlap_m = 0.05;
  navi::SectionSplitterOptions splitter;
  /// The coverage path the cleaning behaviors follow: the paper's wall-following balloon, or the
  /// boustrophedon (plough) baseline, to measure one against the other on the robot.
  enum class Pattern { balloon, boustrophedon };
  Pattern pattern = Pattern::balloon;
};

/// What the navigation behaviors share with the sequencing layer: the grid map, the named
/// regions, the sections of the map (CSectionSplitter, once), the path planner, the coverage
/// generator, the cleaned-cells record and the progress of each section's coverage (so a
/// cleaning retried after a localization fault resumes where it paused). Not thread-safe: the
/// robot program steps behaviors and modules on one thread.
class NaviWorkspace final {
 public:
  NaviWorkspace(navi::OccupancyGrid grid, navi::RegionMap regions, NaviWorkspaceOptions options = {});

  [[nodiscard]] const navi::OccupancyGrid& grid() const noexcept { return grid_; }
  [[nodiscard]] const navi::RegionMap& regions() const noexcept { return regions_; }
  [[nodiscard]] const navi::SectionSet& sections() const noexcept { return sections_; }
  [[nodiscard]] const NaviWorkspaceOptions& options() const noexcept { return options_; }
  /// The section called `name` ("A"), nullptr when there is none.
  [[nodiscard]] const navi::Section* section(std::string_view name) const noexcept;
  /// Names of the sections most of whose cells lie in the room, in scan order; an error message
  /// naming the known rooms for an unknown room.
  struct RoomSections {
    bool ok = false;
    std::vector<std::string> names;
    std::string error;
  };
  [[nodiscard]] RoomSections sections_of_room(std::string_view room) const;

  [[nodiscard]] navi::PathPlanner& planner() noexcept { return planner_; }
  [[nodiscard]] navi::CoveragePlanner& coverage_planner() noexcept { return coverage_; }
  [[nodiscard]] navi::CleanedCells& cleaned() noexcept { return cleaned_; }
  [[nodiscard]] const navi::CleanedCells& cleaned() const noexcept { return cleaned_; }

  /// Where a goal name points: "<section>.entry" (the first point of the section's coverage
  /// path entered from `from`), a map node, a room (its centroid) or a section (its
  /// centroid). nullopt for an unknown name.
  [[nodiscard]] std::optional<navi::Point2D> resolve_goal(std::string_view name, navi::Point2D from);

  /// Coverage progress of one section: the balloon path being followed and how far along it.
  struct SectionProgress {
    navi::CoverageResult plan;
    double done_m = 0.0;   ///< arc length already followed
    bool finished = false;
  };
  /// The progress record of a section, the coverage path (options().pattern) computed from
  /// `from` on first use (and again when the previous one finished).
  SectionProgress& progress(const navi::Section& section, navi::Point2D from);
  [[nodiscard]] const std::map<std::string, SectionProgress, std::less<>>& all_progress() const noexcept {
    return progress_;
  }

  /// Global localization hook (the localizer's relocalize); false when none is set.
  void set_relocalizer(std::function<bool(Time)> relocalize) { relocalize_ = std::move(relocalize); }
  [[nodiscard]] bool relocalize(Time now) const noexcept;

 private:
  navi::OccupancyGrid grid_;
  navi::RegionMap regions_;
  NaviWorkspaceOptions options_;
  navi::SectionSet sections_;
  navi::PathPlanner planner_;
  navi::CoveragePlanner coverage_;
  navi::CleanedCells cleaned_;
  [[nodiscard]] navi::CoverageResult plan_coverage(const navi::Section& section, navi::Point2D from);
  std::map<std::string, SectionProgress, std::less<>> progress_;
  std::map<std::string, navi::CoverageResult, std::less<>> entry_plans_;
  std::function<bool(Time)> relocalize_;
};

/// Follows a polyline with a lookahead point: the closest point is searched only a short arc
/// ahead of the progress so far (a spiral's neighbouring round is never mistaken for the
/// current one), and progress never goes back. No allocation after reset().
class PathTracker {
 public:
  void reset(std::vector<navi::Point2D> path, double start_m = 0.0);
  struct Target {
    navi::Point2D point;      ///< the lookahead point
    double remaining_m = 0.0; ///< arc length from the progress point to the end
    double cross_track_m = 0.0;
    double corner_rad = 0.0;  ///< heading change of the path between progress and lookahead
  };
  /// Advances the progress to the closest point near `position`; returns the lookahead target.
  Target update(navi::Point2D position, double lookahead_m, double search_m) noexcept;
  [[nodiscard]] double progress_m() const noexcept { return s_now_; }
  [[nodiscard]] double length_m() const noexcept { return s_.empty() ? 0.0 : s_.back(); }
  [[nodiscard]] bool empty() const noexcept { return pts_.empty(); }
  [[nodiscard]] navi::Point2D at(double s) const noexcept;
  [[nodiscard]] const std::vector<navi::Point2D>& points() const noexcept { return pts_; }
  /// Moves the progress to arc length s (clamped to the path), forward or back, keeping the path.
  void jump_to(double s) noexcept;

 private:
  [[nodiscard]] double heading_at(double s) const noexcept;
  std::vector<navi::Point2D> pts_;
  std::vector<double> s_;
  std::size_t seg_ = 0;
  double s_now_ = 0.0;
};

/// Common part of the path-following behaviors: laser look-ahead, localization pause, blocked
/// timer, and the omni / differential command toward a lookahead point.
class CPathFollowingBehavior : public CBehavior {
 protected:
  explicit CPathFollowingBehavior(NaviWorkspace& workspace) : workspace_(workspace) {}
  /// Reads the shared parameters (speeds, lookahead, laser, blocked timeout).
  void configure_following(const ParameterSet& params, const BehaviorContext& context);
  /// The clearance (metres beyond the body disc) along the body-frame direction (dx, dy) from
  /// the latest fresh scan, counting only returns from obstacles the map does not hold (seen
  /// from `pose`, map frame); +inf without such returns or without a fresh scan.
  [[nodiscard]] double clearance_along(double dx_body, double dy_body, const Pose2D& pose, Time now) const noexcept;
  /// The command toward the lookahead target; `blocked` tells whether the laser stopped it.
  [[nodiscard]] Twist2D command_toward(const Pose2D& pose, const PathTracker::Target& target,
                                       const BehaviorContext& context, bool& blocked) noexcept;
  /// Advances the blocked timer (blocked: the laser stopped the robot, or a bumper is pressed);
  /// true when blocked for longer than the timeout.
  [[nodiscard]] bool blocked_too_long(bool blocked, Time now) noexcept;
  /// command_toward() with the blocked bookkeeping: fails "path blocked" (zero command) when
  /// blocked longer than blocked_timeout_s, and calls plan_around_obstacle() when it is due.
  [[nodiscard]] Twist2D drive_toward(const Pose2D& pose, const PathTracker::Target& target,
                                     const BehaviorContext& context) noexcept;
  /// Plans a way around what blocks the robot (seen_obstacles_ after note_unmapped_returns()).
  virtual void plan_around_obstacle(const Pose2D& pose, Time now) noexcept = 0;
  /// Whether it is time to plan around what blocks the robot: blocked for replan_after_s since
  /// the last attempt (or since the block began), and attempts left.
  [[nodiscard]] bool replan_due(Time now) const noexcept;
  /// Appends to seen_obstacles_ the returns of the latest fresh scan within max_range_m that the
  /// map does not explain (map frame, seen from `pose`); records the attempt.
  void note_unmapped_returns(const Pose2D& pose, Time now, double max_range_m);
  /// Whether a point (map frame) lies on or next to an obstacle of the map.
  [[nodiscard]] bool near_mapped_obstacle(navi::Point2D p) const noexcept;

  NaviWorkspace& workspace_;
  const LaserResource* laser_ = nullptr;
  const BumperResource* bumpers_ = nullptr;
  PathTracker tracker_;
  double speed_ = 0.3, lookahead_m_ = 0.25, yaw_rate_ = 1.0, k_heading_ = 2.0;
  double stop_distance_m_ = 0.05, slow_distance_m_ = 0.4;
  double hold_heading_rad_ = 0.0;
  Duration blocked_timeout_{0};
  bool blocked_ = false;
  Time blocked_since_{0};
  // Planning around obstacles the map does not hold (replan_after_s, max_replans).
  Duration replan_after_{0};  ///< 0: never replan, wait for blocked_timeout_s
  int max_replans_ = 0;
  int replans_ = 0;           ///< attempts of this activation
  Time last_replan_{0};
  std::vector<navi::Point2D> seen_obstacles_;  ///< unmapped returns that blocked this activation
  bool has_last_ = false;
  Pose2D last_pose_;
};

/// Moves to a named goal (parameter goal: "<section>.entry", a map node, a room or a section) on
/// the shortest collision-free path (A* on the map with the robot's radius, navi::PathPlanner),
/// tracked with a lookahead point; the laser slows and stops it before unexpected obstacles.
/// Holonomic base: translates toward the lookahead point keeping its heading; differential:
/// turns toward it and drives forward. Pauses while not localized. Succeeds within
/// goal_tolerance_m of the goal. Stopped by an obstacle the map does not hold for replan_after_s,
/// it plans again around what the laser sees (navi::PathPlanner::plan_around), at most
/// max_replans times. Fails: "unknown goal", "no path to the goal", "not localized" (no pose at
/// activation), "path blocked" (stopped for blocked_timeout_s: no way around was found).
class BhAutoMove final : public CPathFollowingBehavior {
 public:
  explicit BhAutoMove(NaviWorkspace& workspace) : CPathFollowingBehavior(workspace) {}
  static const ModuleManifest& static_manifest();
  /// The planned path of the current activation (map frame); the last replanned one.
  [[nodiscard]] const std::vector<navi::Point2D>& path() const noexcept { return tracker_.points(); }
  /// Paths planned around unexpected obstacles in this activation.
  [[nodiscard]] int replans() const noexcept { return replans_; }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  /// Plans again to the goal around what the laser sees (PathPlanner::plan_around).
  void plan_around_obstacle(const Pose2D& pose, Time now) noexcept override;
  double goal_tol_m_ = 0.1;
  navi::Point2D goal_;
};

/// Shared implementation of the two cleaning behaviors: follows the balloon coverage path of the
/// section (navi::CoveragePlanner::balloon: tangent to the walls, offset growing each round so
/// the robot spirals inward), marks the cells under the cleaning footprint as it goes, and
/// succeeds at the end of the path. Re-activated for the same section it resumes where it was.
class CCleaningBehavior : public CPathFollowingBehavior {
 public:
  /// Fraction of the section's reachable cells cleaned so far (navi::CleanedCells).
  [[nodiscard]] double section_coverage() const noexcept;

 protected:
  CCleaningBehavior(NaviWorkspace& workspace, bool needs_holonomic)
      : CPathFollowingBehavior(workspace), needs_holonomic_(needs_holonomic) {}
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;
  void on_deactivate() noexcept override;

 private:
  /// Plans a detour around what blocks the coverage path to the first point of the path
  /// clear of it; the cells skipped are left to the section's touch-ups or a later pass.
  void plan_around_obstacle(const Pose2D& pose, Time now) noexcept override;
  bool needs_holonomic_;
  PathTracker detour_;       ///< followed instead of the coverage path while detouring
  bool detouring_ = false;
  double resume_m_ = 0.0;    ///< where the coverage path is taken up again after the detour
  const navi::Section* section_ = nullptr;
  NaviWorkspace::SectionProgress* progress_ = nullptr;
  std::vector<std::size_t> reachable_;
};

/// The wall-following coverage on an omni-directional base (PSR-2): translates along the
/// contours keeping its heading, so corners cost no rotation. Fails "BhCleaning needs an
/// omni-directional base" on a base without sideways motion.
class BhCleaning final : public CCleaningBehavior {
 public:
  explicit BhCleaning(NaviWorkspace& workspace) : CCleaningBehavior(workspace, true) {}
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
};

/// The same coverage on a two-wheel differential base: turns toward the lookahead point (in
/// place when it is far off the heading) and drives forward.
class BhCleaningTwoWheel final : public CCleaningBehavior {
 public:
  explicit BhCleaningTwoWheel(NaviWorkspace& workspace) : CCleaningBehavior(workspace, false) {}
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
};

/// Turns in place and asks the localizer for a global position fix (NaviWorkspace::relocalize)
/// every attempt_period_s; succeeds when one is accepted, fails "no position found" after
/// timeout_s.
class BhGlobalLocalization final : public CBehavior {
 public:
  explicit BhGlobalLocalization(NaviWorkspace& workspace) : workspace_(workspace) {}
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  NaviWorkspace& workspace_;
  double yaw_rate_ = 0.5;
  Duration attempt_{0}, timeout_{0};
  Time started_{0}, last_attempt_{0};
};

/// Registers BhAutoMove, BhCleaning, BhCleaningTwoWheel and BhGlobalLocalization, created on
/// `workspace` (which must outlive the registry's behaviors).
void register_navigation_behaviors(BehaviorRegistry& registry, NaviWorkspace& workspace);

}  // namespace tripodal
