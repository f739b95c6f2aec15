// The planners of the sequencing layer that serve the reactive layer's path-following behaviors:
// CPathPlanner (type "PathPlanner") plans BhAutoMove's path to its goal and replans around
// obstacles the map does not hold; CCoveragePlanner (type "CoveragePlanner") gives the cleaning
// behaviors their section's coverage path (hybrid, balloon or boustrophedon), resumes a section where its
// coverage stopped, plans detours around unexpected obstacles and records the cleaned cells. Both
// publish through NavigationData and read the behaviors' NavigationFeedback; planning never runs in
// the reactive loop.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/dose_planner.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal::navi {

class CCoveragePlanner;

/// Replanning around what blocks a path-following behavior: when the behavior has reported being
/// blocked for replan_after_s (and again every replan_after_s), at most max_replans times per
/// activation, the returns of the latest scan the map does not explain become obstacles to plan
/// around. The two parameters are the behavior's (its manifest declares them).
class ObstacleReplanner {
 public:
  void reset(const ParameterSet& behavior_params);
  /// Whether a replan is due now, given the behavior's feedback.
  [[nodiscard]] bool due(const NavigationFeedback& feedback, Time now) const noexcept;
  /// Records an attempt and appends what the laser sees that the map does not hold; false when
  /// nothing new was seen (a bumper: the same plan again would not help).
  bool observe(const CGridMaps& maps, const ModuleContext& context);
  [[nodiscard]] const std::vector<Point2D>& obstacles() const noexcept { return seen_; }
  [[nodiscard]] int attempts() const noexcept { return attempts_; }

 private:
  Duration after_{0};
  int max_ = 0;
  int attempts_ = 0;
  Time last_{};
  std::vector<Point2D> seen_;
};

/// A path published for the reactive layer, kept by the module that publishes it.
class PublishedPath {
 public:
  /// Publishes `points` under a new id, taken up at start_m; `final`: its end is the goal.
  /// `speeds_m_s`: per-leg speed limits (NavigationData::path_speed_m_s), empty for none.
  void publish(const std::vector<Point2D>& points, double start_m, bool final, ModuleContext& context,
               const std::vector<double>& speeds_m_s = {});
  /// Publishes a failure reason (static storage) for the active behavior.
  void fail(std::string_view reason, ModuleContext& context);
  /// Withdraws what this module published (if it is still what the loop is given).
  void withdraw(ModuleContext& context);
  [[nodiscard]] std::uint32_t id() const noexcept { return id_; }
  [[nodiscard]] const std::vector<Pose2D>& points() const noexcept { return points_; }
  /// Point at arc length s along the path (clamped).
  [[nodiscard]] Point2D at(double s) const noexcept;
  [[nodiscard]] double length_m() const noexcept { return s_.empty() ? 0.0 : s_.back(); }

 private:
  std::vector<Pose2D> points_;
  std::vector<double> s_;
  std::vector<double> speeds_;
  std::uint32_t id_ = 0;
};

/// Type "PathPlanner": serves BhAutoMove (parameter `serves`: the behaviors it plans for, comma
/// separated). At activation it resolves the goal ("<section>.entry" — the first point of the
/// section's coverage path from here, a map node, a room or a section: their centroids) and plans
/// with A* on the map inflated by the robot's radius; the behavior fails with "unknown goal" or
/// "no path to the goal" when it cannot.
class CPathPlanner final : public CNaviModules {
 public:
  static const ModuleManifest& static_manifest();
  /// Where a goal name points, from `from`; nullopt for an unknown name.
  [[nodiscard]] std::optional<Point2D> resolve_goal(std::string_view name, Point2D from);
  [[nodiscard]] const PublishedPath& path() const noexcept { return path_; }
  /// Plans around unexpected obstacles in the current activation.
  [[nodiscard]] int replans() const noexcept { return replanner_.attempts(); }

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  void on_update(ModuleContext& context) override;
  void on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) override;
  void on_behavior_deactivated(std::string_view behavior, ModuleContext& context) override;

 private:
  std::vector<std::string> serves_;
  CGridMaps* maps_ = nullptr;
  const CSectionSplitter* splitter_ = nullptr;
  CCoveragePlanner* coverage_ = nullptr;
  bool active_ = false;
  Point2D goal_;
  ObstacleReplanner replanner_;
  PublishedPath path_;
};

/// Type "CoveragePlanner": serves BhCleaning and BhCleaningTwoWheel (parameter `serves`). At
/// activation it gives the section's coverage path (parameter section), from where the last
/// activation for that section stopped; while the behavior runs it records the cleaned cells under
/// the cleaning footprint (from the localized pose) and the progress along the path, and plans a
/// detour to the first point of the path clear of an obstacle that blocks it.
class CCoveragePlanner final : public CNaviModules {
 public:
  static const ModuleManifest& static_manifest();

  /// Coverage progress of one section: the path being followed and how far along it.
  struct SectionProgress {
    CoverageResult plan;
    double done_m = 0.0;  ///< arc length already followed
    bool finished = false;
  };
  /// The coverage path of `section` from `from`, planned once and kept as the one the cleaning
  /// will follow (its first point is the section's entry).
  [[nodiscard]] const CoverageResult& entry_plan(const Section& section, Point2D from);
  [[nodiscard]] const std::map<std::string, SectionProgress, std::less<>>& progress() const noexcept { return progress_; }
  [[nodiscard]] const CleanedCells& cleaned() const noexcept { return cleaned_; }
  [[nodiscard]] CoveragePlanner& planner();
  /// The lane width the paths are planned with (a dose plan's spacing + lane overlap when
  /// dose_target_j_m2 is set).
  [[nodiscard]] double cleaning_width_m() const noexcept { return options_.cleaning_width_m; }
  /// The coverage path of `section` from `from` as an activation would plan it (not kept): the
  /// dose plan's lane speeds and passes included.
  [[nodiscard]] CoverageResult plan(const Section& section, Point2D from);
  /// The profile's cleaning footprint (parameter cleaning_width_m), whatever the dose plan spaces.
  [[nodiscard]] double footprint_width_m() const noexcept { return footprint_width_m_; }
  /// The dose plan (parameter dose_target_j_m2 > 0), from the lamp and the speed limits.
  [[nodiscard]] const std::optional<DosePlan>& dose_plan() const noexcept { return dose_plan_; }
  [[nodiscard]] const UvLamp& uv_lamp() const noexcept { return lamp_; }
  [[nodiscard]] const DoseLimits& dose_limits() const noexcept { return dose_limits_; }
  /// "hybrid", "balloon" or "boustrophedon"
  [[nodiscard]] const std::string& pattern() const noexcept { return pattern_; }
  /// Fraction of the cells its plan can reach in `section` cleaned so far.
  [[nodiscard]] double section_coverage(const Section& section) const;

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  void on_update(ModuleContext& context) override;
  void on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) override;
  void on_behavior_deactivated(std::string_view behavior, ModuleContext& context) override;

 private:
  /// The centroid of the nearest section not cleaned yet (where the hybrid path should end).
  [[nodiscard]] std::optional<Point2D> next_section_centroid(const Section& section) const;
  void plan_detour(const Pose2D& pose, ModuleContext& context);
  /// A section taken up again away from where it stopped: the way back to the path, planned.
  void rejoin(Point2D from, ModuleContext& context);

  std::vector<std::string> serves_;
  CoverageOptions options_;
  double footprint_width_m_ = 0.0;
  UvLamp lamp_;
  DoseLimits dose_limits_;
  std::optional<DosePlan> dose_plan_;
  std::string pattern_ = "hybrid";
  CGridMaps* maps_ = nullptr;
  const CSectionSplitter* splitter_ = nullptr;
  std::optional<CoveragePlanner> planner_;
  CleanedCells cleaned_;
  std::map<std::string, SectionProgress, std::less<>> progress_;
  std::map<std::string, CoverageResult, std::less<>> entry_plans_;

  // The activation being served.
  SectionProgress* active_ = nullptr;
  PublishedPath coverage_path_;
  PublishedPath detour_;
  bool detouring_ = false;
  double resume_m_ = 0.0;
  ObstacleReplanner replanner_;
  bool has_last_ = false;
  Pose2D last_pose_;
};

}  // namespace tripodal::navi
