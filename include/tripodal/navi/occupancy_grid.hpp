// The occupancy grid map of the navigation modules (sequencing layer): evenly spaced square cells
// in the map frame, as ROS nav_msgs/OccupancyGrid. The section splitter, the path planner, the
// coverage generators, the cleaned-cell record and the simulator's world all work on it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "tripodal/core/geometry.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

/// What a cell holds, as the planners and the simulator see it.
enum class Occupancy : std::uint8_t { free, occupied, unknown };

/// Cell values as nav_msgs/OccupancyGrid stores them: -1 unknown, 0 free, 100 occupied, 1..99 an
/// occupancy probability in percent (map_server's "scale" mode).
inline constexpr std::int8_t kUnknownValue = -1;
inline constexpr std::int8_t kFreeValue = 0;
inline constexpr std::int8_t kOccupiedValue = 100;

/// A cell address: column x (0 at the origin, growing along the map's +x) and row y (0 at the
/// origin, growing along +y). Row 0 is the BOTTOM of the map, as in nav_msgs; a PGM image's row 0
/// is its top, and the loader flips it.
struct CellIndex {
  int x = 0;
  int y = 0;
  friend bool operator==(const CellIndex&, const CellIndex&) = default;
};

// Point2D moved to the shared vocabulary (core/geometry.hpp); navi::Point2D still names it.
using tripodal::Point2D;

/// A rectangular grid of cells of side resolution_m. origin is map_from_grid: the pose of the
/// lower-left corner of cell (0, 0) in the map frame (the yaw of map_server's origin is honoured:
/// cells are laid along the rotated axes). Cells are stored row-major, row 0 first.
class OccupancyGrid {
 public:
  /// An empty 0 x 0 grid.
  OccupancyGrid() = default;
  /// A width x height grid, every cell set to fill. Throws std::invalid_argument for a negative
  /// size or a resolution that is not positive and finite.
  OccupancyGrid(int width, int height, double resolution_m, Pose2D origin = {},
                Occupancy fill = Occupancy::unknown);

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] std::size_t size() const noexcept { return values_.size(); }
  [[nodiscard]] double resolution_m() const noexcept { return resolution_m_; }
  [[nodiscard]] const Pose2D& origin() const noexcept { return origin_; }
  [[nodiscard]] double width_m() const noexcept { return width_ * resolution_m_; }
  [[nodiscard]] double height_m() const noexcept { return height_ * resolution_m_; }

  [[nodiscard]] bool contains(CellIndex c) const noexcept {
    return c.x >= 0 && c.y >= 0 && c.x < width_ && c.y < height_;
  }
  /// Row-major index of a cell; precondition: contains(c).
  [[nodiscard]] std::size_t index(CellIndex c) const noexcept {
    return static_cast<std::size_t>(c.y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(c.x);
  }
  /// The cell of a row-major index; precondition: i < size().
  [[nodiscard]] CellIndex cell(std::size_t i) const noexcept {
    return {static_cast<int>(i % static_cast<std::size_t>(width_)), static_cast<int>(i / static_cast<std::size_t>(width_))};
  }

  /// The state of a cell; cells outside the grid are unknown.
  [[nodiscard]] Occupancy state(CellIndex c) const noexcept;
  [[nodiscard]] Occupancy state(std::size_t i) const noexcept { return state_of(values_[i]); }
  [[nodiscard]] bool is_free(CellIndex c) const noexcept { return state(c) == Occupancy::free; }
  [[nodiscard]] bool is_occupied(CellIndex c) const noexcept { return state(c) == Occupancy::occupied; }
  /// Sets a cell to the canonical value of a state (0, 100 or -1); precondition: contains(c).
  void set_state(CellIndex c, Occupancy s) noexcept { values_[index(c)] = value_of(s); }

  /// The nav_msgs value of a cell (-1 unknown, 0..100); precondition: contains(c).
  [[nodiscard]] std::int8_t value(CellIndex c) const noexcept { return values_[index(c)]; }
  /// Sets a raw nav_msgs value; values outside -1..100 are stored as -1 (unknown).
  void set_value(CellIndex c, std::int8_t v) noexcept;
  [[nodiscard]] const std::vector<std::int8_t>& values() const noexcept { return values_; }

  /// How map_server's values read as states: -1 unknown, 0 free, 100 occupied; the in-between
  /// probabilities of scale mode are neither sure free nor sure occupied: unknown.
  [[nodiscard]] static constexpr Occupancy state_of(std::int8_t v) noexcept {
    return v == kFreeValue ? Occupancy::free : v == kOccupiedValue ? Occupancy::occupied : Occupancy::unknown;
  }
  [[nodiscard]] static constexpr std::int8_t value_of(Occupancy s) noexcept {
    return s == Occupancy::free ? kFreeValue : s == Occupancy::occupied ? kOccupiedValue : kUnknownValue;
  }

  /// Number of cells in a state.
  [[nodiscard]] std::size_t count(Occupancy s) const noexcept;

  /// The map-frame centre of a cell (any integer cell, inside or not).
  [[nodiscard]] Point2D cell_center(CellIndex c) const noexcept;
  /// The cell containing a map-frame point, whether inside the grid or not (check contains()).
  [[nodiscard]] CellIndex cell_at(Point2D p) const noexcept;
  /// The cell containing a map-frame point, or nothing when the point is outside the grid.
  [[nodiscard]] std::optional<CellIndex> world_to_cell(Point2D p) const noexcept;
  /// Grid-frame coordinates (metres from the origin corner along the grid axes) of a map point.
  [[nodiscard]] Point2D to_grid_frame(Point2D p) const noexcept;
  /// Map-frame point of grid-frame coordinates.
  [[nodiscard]] Point2D from_grid_frame(Point2D g) const noexcept;

  friend bool operator==(const OccupancyGrid&, const OccupancyGrid&) = default;

 private:
  int width_ = 0;
  int height_ = 0;
  double resolution_m_ = 0.05;
  Pose2D origin_;
  double cos_yaw_ = 1.0;
  double sin_yaw_ = 0.0;
  std::vector<std::int8_t> values_;
};

}  // namespace tripodal::navi
