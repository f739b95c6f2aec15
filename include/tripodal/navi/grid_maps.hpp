// CGridMaps, the map module of the sequencing layer: the occupancy grid (a ROS map_server map) and
// the named regions (rooms, nodes) of the robot's workspace, with the A* planner inflated by the
// robot's radius that the path and coverage planners share. It is also what the reactive layer's
// behaviors ask whether a laser return is a wall the map holds (ObstacleMap).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/navi/path_planner.hpp"
#include "tripodal/navi/regions.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

/// Hardware that knows the map of the world it runs in (the simulator): the map a robot uses when
/// its profile names none.
class MapSource {
 public:
  virtual ~MapSource() = default;
  [[nodiscard]] virtual const OccupancyGrid& world_map() const noexcept = 0;
  [[nodiscard]] virtual const RegionMap& world_regions() const noexcept = 0;
};

/// Type "GridMaps". Parameters: map (map_server YAML, relative to the profile), regions (rooms and
/// nodes YAML), robot_radius_m (the planning footprint). Without `map` it takes the map of the
/// hardware (a simulated world) at start.
class CGridMaps final : public CNaviModules, public ObstacleMap {
 public:
  static const ModuleManifest& static_manifest();
  /// Gives the map directly (tests, tools), instead of the `map` parameter.
  void set_map(OccupancyGrid grid, RegionMap regions);

  [[nodiscard]] const OccupancyGrid& grid() const;
  [[nodiscard]] const RegionMap& regions() const noexcept { return regions_; }
  [[nodiscard]] double robot_radius_m() const noexcept { return robot_radius_m_; }
  /// A* on the grid inflated by robot_radius_m (shared by the planners; one thread uses it).
  [[nodiscard]] PathPlanner& planner();
  /// ObstacleMap: on or next to (8-neighbourhood) a cell that is not free.
  [[nodiscard]] bool near_obstacle(double x_m, double y_m) const noexcept override;
  /// Appends the returns of `scan` (seen from `pose`, map frame) within max_range_m that the
  /// map does not explain.
  void unmapped_returns(const LaserScan& scan, const Pose2D& pose, double max_range_m, std::vector<Point2D>& out) const;

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  void on_update(ModuleContext& context) override;

 private:
  std::string map_file_, regions_file_;
  std::optional<OccupancyGrid> grid_;
  RegionMap regions_;
  double robot_radius_m_ = 0.25;
  std::unique_ptr<PathPlanner> planner_;
  std::vector<std::uint8_t> near_mask_;  ///< 1 where a cell or a neighbour is not free: one look-up per query
};

}  // namespace tripodal::navi
