// Ray casting on an occupancy grid for the simulator's laser scanner: the solid-cell mask of the
// world (static map plus boxes that appeared) and a scanner model with precomputed beam-angle
// tables, tracing each beam cell by cell (Amanatides-Woo traversal).
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/resources/readings.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::sim {

/// Which cells stop rays and bodies, over the geometry (size, resolution, origin) of a grid.
/// Occupied cells of the grid are solid; free and unknown ones are not. Rays skip open floor:
/// from each cell the distance transform gives a length a ray may jump without meeting a solid
/// cell, and the cell-by-cell traversal resumes from there; the result is the same as the plain
/// traversal, only faster in open space.
class SolidMap {
 public:
  SolidMap() = default;
  explicit SolidMap(const navi::OccupancyGrid& grid);

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] double resolution_m() const noexcept { return resolution_m_; }
  [[nodiscard]] bool contains(int x, int y) const noexcept { return x >= 0 && y >= 0 && x < width_ && y < height_; }
  /// Whether a cell is solid; cells outside the grid are not.
  [[nodiscard]] bool solid(int x, int y) const noexcept {
    return contains(x, y) && cells_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)] != 0;
  }
  /// Precondition: contains(x, y). Until refresh(), rays traverse every cell (still exact).
  void set_solid(int x, int y, bool solid) noexcept {
    cells_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)] = solid ? 1 : 0;
    jumps_valid_ = false;
  }
  /// Recomputes the jump lengths after set_solid() (a distance transform of the whole grid).
  void refresh();
  [[nodiscard]] bool jumps_valid() const noexcept { return jumps_valid_; }
  [[nodiscard]] const std::vector<std::uint8_t>& cells() const noexcept { return cells_; }

  /// Grid-frame coordinates in cell units (cell (i, j) spans [i, i+1) x [j, j+1)) of a map point.
  [[nodiscard]] navi::Point2D to_cells(navi::Point2D map_point) const noexcept;
  /// The grid-frame direction of a map-frame heading.
  [[nodiscard]] double to_grid_angle(double map_angle_rad) const noexcept { return map_angle_rad - origin_.theta_rad; }

  /// Distance (m) from `from` (map frame) along heading `angle_rad` (map frame) to the first solid
  /// cell, or +infinity when none is met within max_range_m or the ray leaves the grid. A ray
  /// starting in a solid cell or outside the grid returns 0 or +infinity respectively.
  [[nodiscard]] double cast(navi::Point2D from, double angle_rad, double max_range_m) const noexcept;
  /// The same in grid cell units: from (gx, gy), unit direction (dx, dy), at most max_t cells.
  [[nodiscard]] double cast_cells(double gx, double gy, double dx, double dy, double max_t) const noexcept;

  /// Whether a disc of radius_m centred at `center` (map frame) overlaps a solid cell or leaves
  /// the grid.
  [[nodiscard]] bool disc_overlaps(navi::Point2D center, double radius_m) const noexcept;

 private:
  int width_ = 0;
  int height_ = 0;
  double resolution_m_ = 0.05;
  Pose2D origin_;
  double cos_yaw_ = 1.0;
  double sin_yaw_ = 0.0;
  std::vector<std::uint8_t> cells_;
  std::vector<float> jump_;  // cells a ray may advance from anywhere in the cell without a hit
  bool jumps_valid_ = false;
};

/// A laser scanner: beam directions tabulated once (cos and sin of every beam angle), so a scan
/// costs one rotation and one grid traversal per beam. Not thread-safe (keeps the noise state).
class LaserModel {
 public:
  LaserModel(const LaserConfig& config, std::uint64_t seed);
  [[nodiscard]] const LaserConfig& config() const noexcept { return config_; }

  /// Fills `scan` (ranges reused: no allocation after the first scan) with the beams seen from
  /// the robot at map_from_base, stamped `stamp`. Ranges are in [range_min, range_max] with
  /// seeded Gaussian noise, +infinity for no return (nothing within range_max) and for beams
  /// closer than range_min.
  void scan(const SolidMap& world, const Pose2D& map_from_base, Time stamp, LaserScan& scan) noexcept;
  /// The same without noise.
  void scan_exact(const SolidMap& world, const Pose2D& map_from_base, Time stamp, LaserScan& scan) const noexcept;

 private:
  void fill(const SolidMap& world, const Pose2D& map_from_base, Time stamp, LaserScan& scan) const noexcept;
  LaserConfig config_;
  std::vector<double> cos_, sin_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_;
};

}  // namespace tripodal::sim
