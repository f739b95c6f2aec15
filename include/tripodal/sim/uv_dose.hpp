// The UV germicidal lamp's dose on the floor, as the simulator's ground truth (seed 001, section
// 2.4: a 253.7 nm UVC tube under the chassis sterilises the ground while the robot moves). What
// `tripodal run` reports for a disinfection task: the fraction of the reachable floor that
// received the target dose. Sits beside the simulator; the simulated board exposes it.
#pragma once

#include <cstddef>
#include <vector>

#include "tripodal/core/geometry.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/navi/dose_planner.hpp"
#include "tripodal/navi/occupancy_grid.hpp"

namespace tripodal::sim {

/// The lamp model is navigation's (navi/dose_planner.hpp), so the dose a plan promises and the
/// dose the simulator counts come from one formula.
using navi::uv_irradiance_w_m2;
using navi::UvLamp;
using navi::validate;

/// Dose (J/m^2) received by each cell of a grid: irradiance at the cell's centre integrated over
/// the time the lamp is on. Allocates once, at construction.
class UvDoseMap {
 public:
  /// Cells and geometry of `grid` (its occupancy is not used: the lamp lights what is under it).
  UvDoseMap(const navi::OccupancyGrid& grid, UvLamp lamp);

  /// The lamp at `lamp_xy` (map frame) for `dt`: every cell of the lit disc gains E x dt.
  void expose(Point2D lamp_xy, Duration dt) noexcept;

  [[nodiscard]] double dose_j_m2(std::size_t cell) const noexcept { return dose_[cell]; }
  /// The dose of the cell holding `p` (0 outside the grid).
  [[nodiscard]] double dose_at_j_m2(Point2D p) const noexcept;
  [[nodiscard]] const navi::OccupancyGrid& grid() const noexcept { return grid_; }
  [[nodiscard]] const UvLamp& lamp() const noexcept { return lamp_; }
  /// Time the lamp has been on (sum of the exposures).
  [[nodiscard]] Duration lamp_on() const noexcept { return lamp_on_; }

 private:
  navi::OccupancyGrid grid_;  // geometry only
  UvLamp lamp_;
  std::vector<double> dose_;
  Duration lamp_on_{0};
};

}  // namespace tripodal::sim
