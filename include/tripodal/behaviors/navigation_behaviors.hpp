// The navigation behaviors of the cleaning robots (reactive layer): BhAutoMove (follow the path to
// a goal), BhCleaning / BhCleaningTwoWheel (follow a section's wall-following coverage path, omni and
// differential) and BhGlobalLocalization (turn while the localizer searches). They plan nothing:
// paths, coverage, detours and position fixes are the sequencing layer's navigation modules (navi/),
// which publish through NavigationData; the behaviors track what they are given and report where they
// are and what blocks them through NavigationFeedback.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"

namespace tripodal {

/// Follows a polyline (map frame; the poses' theta is not used) with a lookahead point: the
/// closest point is searched only a short arc ahead of the progress so far (a spiral's
/// neighbouring round is never mistaken for the current one), and progress never goes back.
/// Allocation-free once reserve()d for the longest path it will be given.
class PathTracker {
 public:
  /// Capacity for paths of up to `points` points (allocates).
  void reserve(std::size_t points);
  /// Takes up `path` at arc length start_m. Points beyond the reserved capacity are dropped, so
  /// this never allocates after reserve().
  void reset(std::span<const Pose2D> path, double start_m = 0.0) noexcept;
  struct Target {
    Pose2D point;              ///< the lookahead point (theta unused)
    double remaining_m = 0.0;  ///< arc length from the progress point to the end
    double cross_track_m = 0.0;
    double corner_rad = 0.0;   ///< heading change of the path between progress and lookahead
  };
  /// Advances the progress to the closest point near `position`; returns the lookahead target.
  /// The pose changes only when the sequencing layer publishes one (every few loop periods), so a
  /// call with the inputs of the previous one, which left the progress where it was, returns that
  /// call's target without searching again (the same result: the search is a function of the
  /// progress and the inputs).
  Target update(const Pose2D& position, double lookahead_m, double search_m) noexcept;
  [[nodiscard]] double progress_m() const noexcept { return s_now_; }
  /// The leg the progress is on: from points()[segment()] to the next point.
  [[nodiscard]] std::size_t segment() const noexcept { return seg_; }
  [[nodiscard]] double length_m() const noexcept { return s_.empty() ? 0.0 : s_.back(); }
  [[nodiscard]] bool empty() const noexcept { return pts_.empty(); }
  [[nodiscard]] std::size_t capacity() const noexcept { return pts_.capacity(); }
  /// The point at arc length s (clamped to the path).
  [[nodiscard]] Pose2D at(double s) const noexcept;
  [[nodiscard]] std::span<const Pose2D> points() const noexcept { return pts_; }

 private:
  [[nodiscard]] double heading_at(double s) const noexcept;
  [[nodiscard]] Target search(const Pose2D& position, double lookahead_m, double search_m) noexcept;
  std::vector<Pose2D> pts_;
  std::vector<double> s_;
  std::size_t seg_ = 0;
  double s_now_ = 0.0;
  // The last update's inputs and target, valid while the progress it left is unchanged.
  bool memo_valid_ = false;
  Pose2D memo_position_;
  double memo_lookahead_m_ = 0.0, memo_search_m_ = 0.0;
  Target memo_;
};

/// Common part of the path-following behaviors: takes up each new path the sequencing layer
/// publishes, looks ahead with the laser (counting only returns the map does not explain), keeps
/// the blocked timer, reports progress and blockage, and commands an omni or differential base
/// toward the lookahead point. Fails "path blocked" when stopped for blocked_timeout_s (the
/// sequencing layer's replans, each a new path, restart the timer; being held still by a safety
/// input for safety_hold_s counts as stopped), "no path" when none arrives
/// within blocked_timeout_s, or with the reason the sequencing layer gives (path_failure).
class CPathFollowingBehavior : public CBehavior {
 public:
  /// Longest path taken up (points); the control loop's max_path_points should not exceed it.
  static constexpr std::size_t kMaxPathPoints = 32768;
  [[nodiscard]] const PathTracker& tracker() const noexcept { return tracker_; }
  /// The last filtering of a scan for unexpected returns, shared by every following behavior
  /// watching the same laser (BhCleaning, BhAutoMove and BhCleaningTwoWheel active together filter
  /// the same scan from the same pose: one map lookup per near beam instead of three).
  struct NearReturns;

 protected:
  /// Reads the shared parameters (speeds, lookahead, laser, blocked timeout).
  void configure_following(const ParameterSet& params, const BehaviorContext& context);
  /// Takes up a new path, fails with the sequencing layer's reason, or times out waiting for a
  /// path. False when there is nothing to follow this period.
  bool take_path(const BehaviorContext& context) noexcept;
  /// Tracks the path from `pose` and writes the feedback; true when at its end: within
  /// `tolerance_m` of the last point and, `along_path`, with the progress there too.
  bool track(const Pose2D& pose, const BehaviorContext& context, double search_m, double tolerance_m, bool along_path,
             PathTracker::Target& target) noexcept;
  /// The clearance (metres beyond the body disc) along the body-frame direction (dx, dy) from
  /// the latest fresh scan, counting only returns from obstacles the map does not hold;
  /// +inf without such returns or without a fresh scan.
  [[nodiscard]] double clearance_along(double dx_body, double dy_body, const BehaviorContext& context) const noexcept;
  /// The command toward the lookahead target; `blocked` tells whether the laser stopped it.
  [[nodiscard]] Twist2D command_toward(const Pose2D& pose, const PathTracker::Target& target,
                                       const BehaviorContext& context, bool& blocked) noexcept;
  /// command_toward() with the blocked bookkeeping: fails "path blocked" (zero command) when
  /// blocked longer than blocked_timeout_s; reports the blockage in the feedback. Held still by a
  /// safety input for safety_hold_s (BehaviorContext::safety) counts as blocked too.
  [[nodiscard]] Twist2D drive_toward(const Pose2D& pose, const PathTracker::Target& target,
                                     const BehaviorContext& context) noexcept;

  PathTracker tracker_;
  const LaserResource* laser_ = nullptr;
  const BumperResource* bumpers_ = nullptr;
  double speed_ = 0.3, lookahead_m_ = 0.25, yaw_rate_ = 1.0, k_heading_ = 2.0;
  double stop_distance_m_ = 0.05, slow_distance_m_ = 0.4;
  double hold_heading_rad_ = 0.0;
  Duration blocked_timeout_{0};

 private:
  [[nodiscard]] bool blocked_too_long(bool blocked, Time now) noexcept;
  /// Keeps the timer of the safety input holding the robot still; true once held for safety_hold_s.
  [[nodiscard]] bool held_by_safety(const BehaviorContext& context) noexcept;
  /// The beams' directions in the body frame, computed once per scan geometry (a cycle reads
  /// every beam: cos and sin per beam would dominate it).
  void update_beam_table(const LaserScan& scan) noexcept;
  /// Once per new scan: its near returns (body frame) that the map does not explain, seen from
  /// `pose` (map frame). The scan changes at the laser's rate, the loop runs far faster.
  void update_unexpected(const Pose2D& pose, const BehaviorContext& context) noexcept;
  std::shared_ptr<NearReturns> shared_;
  std::vector<Pose2D> unexpected_;
  std::size_t scan_seen_ = 0;
  std::vector<float> cos_, sin_;
  double table_angle_min_ = 0.0, table_increment_ = 0.0;
  std::uint32_t path_id_ = 0;  ///< the path being tracked; 0: none yet
  Time waiting_since_{};      ///< activation, for the "no path" timeout
  bool blocked_ = false;
  Time blocked_since_{};
  Duration safety_hold_{0};
  bool held_ = false;  ///< the safety input holds the robot still since held_since_
  Time held_since_{};
};

/// Moves to a named goal (parameter goal: "<section>.entry", a map node, a room or a section)
/// along the path the sequencing layer's path planner publishes (A* with the robot's radius),
/// tracked with a lookahead point; the laser slows and stops it before unexpected obstacles, and
/// the path planner replans around them (replan_after_s, max_replans). Holonomic base: translates
/// toward the lookahead point keeping its heading; differential: turns toward it and drives
/// forward. Pauses while not localized. Succeeds within goal_tolerance_m of the goal. Fails:
/// "unknown goal", "no path to the goal" (the planner's), "path blocked", "no path".
class BhAutoMove final : public CPathFollowingBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  double goal_tol_m_ = 0.1;
};

/// Shared implementation of the two cleaning behaviors: follows the coverage path of the section
/// the sequencing layer's coverage planner publishes (the paper's balloon: tangent to the walls,
/// offset growing each round), and detours it publishes around unexpected obstacles; succeeds at
/// the end of the coverage path. The coverage planner records the cleaned cells and where a
/// section's coverage stopped, so a re-activation for the same section resumes there.
class CCleaningBehavior : public CPathFollowingBehavior {
 protected:
  explicit CCleaningBehavior(bool needs_holonomic) : needs_holonomic_(needs_holonomic) {}
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  bool needs_holonomic_;
};

/// The wall-following coverage on an omni-directional base (PSR-2): translates along the
/// contours keeping its heading, so corners cost no rotation. Fails "BhCleaning needs an
/// omni-directional base" on a base without sideways motion.
class BhCleaning final : public CCleaningBehavior {
 public:
  BhCleaning() : CCleaningBehavior(true) {}
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
};

/// The same coverage on a two-wheel differential base: turns toward the lookahead point (in
/// place when it is far off the heading) and drives forward.
class BhCleaningTwoWheel final : public CCleaningBehavior {
 public:
  BhCleaningTwoWheel() : CCleaningBehavior(false) {}
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
};

/// Turns in place while the localizer attempts global position fixes (every attempt_period_s, a
/// parameter the localizer reads from this activation); succeeds when a fix is accepted
/// (NavigationData::fixes grows), fails "no position found" after timeout_s.
class BhGlobalLocalization final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  double yaw_rate_ = 0.5;
  Duration timeout_{0};
  Time started_{};
  std::uint32_t fixes_at_start_ = 0;
};

/// Registers BhAutoMove, BhCleaning, BhCleaningTwoWheel and BhGlobalLocalization.
void register_navigation_behaviors(BehaviorRegistry& registry);

}  // namespace tripodal
