// The UV germicidal lamp's dose on the floor, as the simulator's ground truth (seed 001, section
// 2.4: a 253.7 nm UVC tube under the chassis sterilises the ground while the robot moves). What
// `tripodal run` reports for a disinfection task: the fraction of the reachable floor that
// received the target dose. Sits beside the simulator; the simulated board exposes it.
#pragma once

#include <cstddef>
#include <vector>

#include "tripodal/core/geometry.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/navi/occupancy_grid.hpp"

namespace tripodal::sim {

/// The lamp as a point source under the chassis centre. The thesis gives no optical figures: the
/// defaults are a small low-pressure tube (about 1 W of UVC) a few centimetres above the floor,
/// lighting the disc its reflector and skirt leave open.
struct UvLamp {
  double uvc_power_w = 1.0;  ///< radiant UVC output (not the electrical power)
  double height_m = 0.05;    ///< above the floor
  double radius_m = 0.3;     ///< lit disc on the floor, centred under the lamp (the shield's edge)
};

/// Throws std::invalid_argument naming the field when a value is not finite and > 0.
void validate(const UvLamp& lamp);

/// Irradiance (W/m^2) on the floor at horizontal distance `r_m` from the point under the lamp: an
/// isotropic source, inverse square with the cosine of incidence, E = P h / (4 pi d^3) with
/// d^2 = r^2 + h^2; zero beyond the lit disc.
[[nodiscard]] double uv_irradiance_w_m2(const UvLamp& lamp, double r_m) noexcept;

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
