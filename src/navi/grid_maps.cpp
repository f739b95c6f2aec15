#include "tripodal/navi/grid_maps.hpp"

#include <cmath>
#include <filesystem>

#include "tripodal/hardware/hardware.hpp"
#include "tripodal/navi/map_io.hpp"

namespace tripodal::navi {

const ModuleManifest& CGridMaps::static_manifest() {
  static const ModuleManifest m = navi_manifest(
      "GridMaps", "the occupancy grid (ROS map_server) and named regions of the workspace, and the A* planner on it",
      {}, {"grid_map"},
      {ParameterSpec{"map", ValueType::string, Value{std::string()}, "",
                     "map_server YAML file, relative to the robot profile (empty: the simulated world's map)", {}, {}},
       ParameterSpec{"regions", ValueType::string, Value{std::string()}, "",
                     "rooms and nodes YAML file, relative to the robot profile (empty: the world's, or none)", {}, {}},
       ParameterSpec{"robot_radius_m", ValueType::number, Value{0.25}, "m",
                     "radius of the planning footprint: obstacles are inflated by it", 0.01, 5.0}});
  return m;
}

void CGridMaps::set_map(OccupancyGrid grid, RegionMap regions) {
  grid_ = std::move(grid);
  regions_ = std::move(regions);
  planner_.reset();
  near_mask_.clear();
}

void CGridMaps::on_configure(const ParameterSet& params) {
  robot_radius_m_ = params.number("robot_radius_m");
  planner_.reset();
  map_file_ = params.string("map");
  regions_file_ = params.string("regions");
}

void CGridMaps::on_start(ModuleContext& context) {
  // Files are named relative to the profile that configures the module.
  if (!map_file_.empty()) grid_ = load_map(context.profile_dir / map_file_).grid;
  if (!regions_file_.empty()) regions_ = load_regions(context.profile_dir / regions_file_);
  if (!grid_) {
    const auto* source = dynamic_cast<const MapSource*>(context.hardware);
    if (source == nullptr) {
      throw ConfigError(where(), "GridMaps has no map: give the parameter `map` (a map_server YAML file)");
    }
    grid_ = source->world_map();
    if (regions_.room_names().empty()) regions_ = source->world_regions();
  }
  (void)planner();  // built now, not in the first period that needs it
  const OccupancyGrid& g = *grid_;
  near_mask_.assign(g.size(), 0);
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.state(i) == Occupancy::free) continue;
    const CellIndex c = g.cell(i);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const CellIndex n{c.x + dx, c.y + dy};
        if (g.contains(n)) near_mask_[g.index(n)] = 1;
      }
    }
  }
  context.navigation->map = this;
  context.navigation->robot_radius_m = robot_radius_m_;
}

void CGridMaps::on_update(ModuleContext& context) {
  context.navigation->map = this;
  context.navigation->robot_radius_m = robot_radius_m_;
}

const OccupancyGrid& CGridMaps::grid() const {
  if (!grid_) throw std::logic_error("GridMaps: no map yet (configure with `map`, set_map(), or start on simulated hardware)");
  return *grid_;
}

PathPlanner& CGridMaps::planner() {
  if (!planner_) {
    PathPlannerOptions o;
    o.robot_radius_m = robot_radius_m_;
    planner_ = std::make_unique<PathPlanner>(grid(), o);
  }
  return *planner_;
}

bool CGridMaps::near_obstacle(double x_m, double y_m) const noexcept {
  if (!grid_) return false;
  const CellIndex cell = grid_->cell_at({x_m, y_m});
  if (!near_mask_.empty()) return !grid_->contains(cell) || near_mask_[grid_->index(cell)] != 0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (grid_->state(CellIndex{cell.x + dx, cell.y + dy}) != Occupancy::free) return true;
    }
  }
  return false;
}

void CGridMaps::unmapped_returns(const LaserScan& scan, const Pose2D& pose, double max_range_m, std::vector<Point2D>& out) const {
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < scan.range_min_m || r > std::min<double>(scan.range_max_m, max_range_m)) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double bx = r * std::cos(a), by = r * std::sin(a);
    const Point2D p{pose.x_m + c * bx - s * by, pose.y_m + s * bx + c * by};
    if (!near_obstacle(p.x_m, p.y_m)) out.push_back(p);
  }
}

}  // namespace tripodal::navi
