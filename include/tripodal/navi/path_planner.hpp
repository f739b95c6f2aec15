// The path planner of the navigation modules (sequencing layer): the shortest collision-free path
// for a round robot on an occupancy grid, used by PrAutoMove/BhAutoMove to reach a goal or the
// nearest uncleaned section, and by the coverage generators to link passes.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tripodal/navi/distance_field.hpp"
#include "tripodal/navi/occupancy_grid.hpp"

namespace tripodal::navi {

struct PathPlannerOptions {
  double robot_radius_m = 0.25;     ///< obstacles are inflated by this much (footprint disc)
  bool unknown_is_obstacle = true;  ///< plan only through cells known to be free
  bool shortcut = true;             ///< drop waypoints joined by a collision-free straight line
  /// Clearance kept where the way allows (0 or at most robot_radius_m: none). A path that
  /// passes an obstacle corner at just the robot radius leaves the follower no room for its
  /// tracking error: A* cells nearer than this cost more (up to 1 + kClearanceWeight times a
  /// step at the robot radius), and a shortcut never comes nearer than the cells it replaces.
  double preferred_clearance_m = 0.0;
  /// A robot stands where its follower left it: at the end of a lane along a wall it may stand a
  /// few millimetres inside the margin the planner keeps (tracking error, the lane's cells). A
  /// start (plan(Point2D, Point2D)) with at least robot_radius_m - start_tolerance_m of clearance
  /// is not in collision: the plan first leads straight out to the nearest cell of full clearance,
  /// never nearer the obstacle than the robot stands.
  double start_tolerance_m = 0.1;
};

enum class PlanStatus { ok, start_outside_map, goal_outside_map, start_in_collision, goal_in_collision, unreachable };

[[nodiscard]] const char* to_string(PlanStatus s) noexcept;

struct PlannedPath {
  PlanStatus status = PlanStatus::unreachable;
  std::string message;              ///< why it failed, with the positions and clearances
  std::vector<CellIndex> cells;     ///< the A* cell path, start to goal (before shortcutting)
  std::vector<Point2D> waypoints;   ///< map frame: start, the corners kept, goal
  double length_m = 0.0;            ///< along the waypoints
  std::size_t expanded = 0;         ///< A* nodes expanded
  [[nodiscard]] bool ok() const noexcept { return status == PlanStatus::ok; }
};

/// A* on the 8-connected grid (diagonal moves cost sqrt 2 and may not cut an obstacle corner)
/// with the octile-distance heuristic, restricted to cells whose clearance (DistanceField) is at
/// least the robot radius; then the path is shortcut: from each kept waypoint the farthest later
/// cell visible along a straight line of collision-free cells becomes the next one. The distance
/// field is computed once, in the constructor; planning reuses its buffers, so one planner must
/// not plan from two threads at once. Failures are statuses with a message, never exceptions.
class PathPlanner final {
 public:
  PathPlanner(const OccupancyGrid& grid, PathPlannerOptions options = {});

  /// Plans from start to goal (map frame, metres); a start within start_tolerance_m of the
  /// robot radius gets the way out first (PathPlannerOptions::start_tolerance_m).
  [[nodiscard]] PlannedPath plan(Point2D start, Point2D goal);
  /// Plans between two cells.
  [[nodiscard]] PlannedPath plan(CellIndex start, CellIndex goal) { return plan(start, goal, options_.preferred_clearance_m); }
  /// Plans between two cells keeping this clearance where the way allows (as the option
  /// preferred_clearance_m, for this plan: a link between two cells along a wall keeps theirs,
  /// leg_clearance_m, rather than stepping out to the preferred clearance and back).
  [[nodiscard]] PlannedPath plan(CellIndex start, CellIndex goal, double keep_clearance_m);
  /// Plans from start to goal around obstacles the map does not hold (points seen by a laser,
  /// map frame), for this plan only: the cells within the robot radius of a point are closed,
  /// and those within the radius plus margin_m too, except near the start (a robot stopped
  /// before an obstacle stands inside that margin and must be able to back away from it). The
  /// start cell itself is always open. The map and later plans are not changed.
  [[nodiscard]] PlannedPath plan_around(Point2D start, Point2D goal, std::span<const Point2D> obstacles,
                                        double margin_m = 0.1);

  /// Whether the robot's disc centred on the cell touches no obstacle.
  [[nodiscard]] bool traversable(CellIndex c) const noexcept {
    return grid_.contains(c) && traversable_[grid_.index(c)] != 0;
  }
  /// Whether every cell on the straight segment a-b (supercover line) is traversable.
  [[nodiscard]] bool line_of_sight(CellIndex a, CellIndex b) const noexcept { return line_of_sight(a, b, 0.0); }
  /// Whether every cell on the segment a-b is traversable and has at least this clearance.
  [[nodiscard]] bool line_of_sight(CellIndex a, CellIndex b, double min_clearance_m) const noexcept;
  /// Clearance of the cell's centre from the nearest obstacle (0 outside the grid).
  [[nodiscard]] double clearance_m(CellIndex c) const noexcept {
    return grid_.contains(c) ? field_.clearance_m(grid_.index(c)) : 0.0;
  }
  /// The clearance a straight leg between a and b keeps where the way allows: the preferred
  /// clearance, or less where an end of the leg itself is nearer an obstacle (a lane end, a
  /// contour along a wall). Without a preferred clearance: 0 (traversable is enough).
  [[nodiscard]] double leg_clearance_m(CellIndex a, CellIndex b) const noexcept;

  /// Extra cost of a step onto a cell at the robot radius, relative to a step at the clearance
  /// kept (falls linearly to 0 there).
  static constexpr float kClearanceWeight = 4.0F;

  [[nodiscard]] const OccupancyGrid& grid() const noexcept { return grid_; }
  [[nodiscard]] const DistanceField& distance_field() const noexcept { return field_; }
  [[nodiscard]] const PathPlannerOptions& options() const noexcept { return options_; }

 private:
  // The nearest traversable cell a straight move from `start` reaches without coming nearer an
  // obstacle, when start lies within start_tolerance_m of the robot radius; nullopt otherwise.
  [[nodiscard]] std::optional<CellIndex> way_out(CellIndex start) const;

  OccupancyGrid grid_;
  PathPlannerOptions options_;
  DistanceField field_;
  std::vector<std::uint8_t> traversable_;
  // A* works on a copy of traversable_ padded by one blocked cell on every side, so neighbours
  // need no bounds check: padded index = (y + 1) * (width + 2) + (x + 1).
  int padded_width_ = 0;
  [[nodiscard]] std::size_t padded_index(int x, int y) const noexcept {
    return static_cast<std::size_t>(y + 1) * static_cast<std::size_t>(padded_width_) + static_cast<std::size_t>(x + 1);
  }
  std::vector<std::uint8_t> open_cell_;
  // Per padded cell: the clearance (0 on the padding), for the cost of steps near obstacles.
  std::vector<float> clearance_;
  // A* scratch (padded indices), reused across plans; valid where stamp_ == search_id_.
  std::vector<float> g_;
  std::vector<std::uint32_t> parent_;
  std::vector<std::uint32_t> stamp_;
  std::vector<std::uint8_t> closed_;
  std::uint32_t search_id_ = 0;
};

/// Length of a polyline, metres.
[[nodiscard]] double polyline_length_m(const std::vector<Point2D>& points) noexcept;

}  // namespace tripodal::navi
