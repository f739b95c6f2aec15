// Euclidean distance from every cell to the nearest obstacle cell of an occupancy grid, computed
// once per map: the path planner inflates obstacles by the robot radius with it and the balloon
// coverage follows its level sets (contours at a fixed distance from the walls).
#pragma once

#include <cstddef>
#include <vector>

#include "tripodal/navi/occupancy_grid.hpp"

namespace tripodal::navi {

/// Exact Euclidean distance transform (two-pass, Felzenszwalb-Huttenlocher lower envelope), in
/// metres between cell centres. Obstacles are occupied cells, unknown cells too when
/// unknown_is_obstacle, and everything beyond the grid's border. clearance_m(c) is the distance
/// from c's centre to the nearest obstacle cell's EDGE: distance - resolution / 2 (0 inside an
/// obstacle). A disc of radius r centred on c touches no obstacle cell when clearance_m(c) >= r.
class DistanceField {
 public:
  DistanceField() = default;
  /// Distances to the obstacles of grid (O(cells)).
  explicit DistanceField(const OccupancyGrid& grid, bool unknown_is_obstacle = true);
  /// Distances to the cells where obstacle[i] is true, on a width x height grid of the given
  /// resolution (obstacle.size() == width * height); the outside of the grid counts as obstacle
  /// unless outside_is_obstacle is false (then a grid without obstacles is all +infinity).
  DistanceField(int width, int height, double resolution_m, const std::vector<bool>& obstacle,
                bool outside_is_obstacle = true);

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] double resolution_m() const noexcept { return resolution_m_; }
  /// Centre-to-centre distance to the nearest obstacle cell, metres (0 on an obstacle).
  [[nodiscard]] double distance_m(std::size_t i) const noexcept { return distance_m_[i]; }
  [[nodiscard]] double clearance_m(std::size_t i) const noexcept {
    const double d = distance_m_[i] - 0.5 * resolution_m_;
    return d > 0.0 ? d : 0.0;
  }
  [[nodiscard]] const std::vector<float>& distances_m() const noexcept { return distance_m_; }

 private:
  void compute(const std::vector<bool>& obstacle, bool outside_is_obstacle);
  int width_ = 0;
  int height_ = 0;
  double resolution_m_ = 0.05;
  std::vector<float> distance_m_;
};

}  // namespace tripodal::navi
