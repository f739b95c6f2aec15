// Planning a UV disinfection that reaches a target dose (issue 35, item 4): from the lamp model
// (a point source under the chassis, seed 001 section 2.4) the lane spacing, speed and number of
// passes that give every point between the lanes the target dose, the speed each lane of a
// coverage path may keep, and what the whole run will take. Sits in navi/ beside the coverage
// planner whose lanes it spaces; the simulator's dose map (sim/uv_dose.hpp) uses the same lamp.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "tripodal/core/geometry.hpp"

namespace tripodal::navi {

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

/// The dose (J/m^2) one straight pass at `speed_m_s` leaves on a floor point `lateral_m` beside
/// the lane, far from its ends: the irradiance integrated along the chord of the lit disc,
/// D = P h / (4 pi v) * 2L / (a^2 sqrt(L^2 + a^2)), a^2 = y^2 + h^2, L = sqrt(R^2 - y^2) (closed
/// form); 0 beyond the disc or for a speed that is not > 0.
[[nodiscard]] double lane_dose_j_m2(const UvLamp& lamp, double lateral_m, double speed_m_s) noexcept;

/// The least dose (J/m^2) on the floor between parallel lanes `spacing_m` apart, each driven
/// `passes` times at `speed_m_s` (every lane within the lit disc counts).
[[nodiscard]] double lanes_min_dose_j_m2(const UvLamp& lamp, double spacing_m, double speed_m_s, int passes = 1) noexcept;

/// What the robot can do and what the plan must allow for.
struct DoseLimits {
  double min_speed_m_s = 0.05;   ///< slowest the base tracks a lane steadily
  double max_speed_m_s = 0.3;    ///< the cleaning behavior's cruise speed
  double min_spacing_m = 0.05;   ///< the lanes lie on grid rows: one cell
  double max_spacing_m = 0.6;    ///< the widest the coverage planner may space lanes
  double spacing_step_m = 0.05;  ///< spacings tried: multiples of this (the grid's resolution)
  int max_passes = 3;            ///< passes over the same lanes the plan may ask for
  /// Lanes may lie this much farther apart than planned (the robot's tracking error, the lanes
  /// quantised to cells): the dose is planned for spacing + this.
  double tracking_error_m = 0.02;
};

/// Throws std::invalid_argument naming the field when a limit is out of range.
void validate(const DoseLimits& limits);

/// Lane spacing, speed and passes for a target dose.
struct DosePlan {
  double target_j_m2 = 0.0;
  double spacing_m = 0.0;       ///< between neighbouring lanes
  double speed_m_s = 0.0;       ///< along a lane at the planned spacing
  int passes = 1;               ///< over the same lanes
  double min_dose_j_m2 = 0.0;   ///< the least dose between lanes at spacing + tracking error
  double area_rate_m2_s = 0.0;  ///< floor dosed per second of lane travel: spacing * speed / passes
  /// Beside the outermost lane (the wall round), the floor within this lateral distance gets the
  /// target in `passes` passes at the minimum speed even with the round the tracking error off its
  /// line: the floor the lamp can dose at all.
  double reach_m = 0.0;
};

/// The plan that doses the floor fastest (greatest area_rate_m2_s) with at least `target_j_m2`
/// between lanes: for each spacing (multiples of spacing_step_m in [min, max]) and number of
/// passes, the fastest speed whose least dose reaches the target, kept when it is at least the
/// minimum speed; a second pass only where one pass at the minimum speed falls short. Throws
/// std::invalid_argument with the best dose the limits allow when no plan reaches the target.
[[nodiscard]] DosePlan plan_dose(const UvLamp& lamp, double target_j_m2, const DoseLimits& limits);

/// The speed (m/s) of one lane whose neighbours lie `gap_left_m` and `gap_right_m` away (lanes of
/// the same plan, same passes): the fastest, up to the maximum speed, at which the floor on both
/// sides still gets the target with the plan's passes. Never below the plan's speed for gaps no
/// wider than its spacing; a gap wider than that is taken as the spacing (the wall round or the
/// region's edge lies there, driven at the plan's speed).
[[nodiscard]] double lane_speed_m_s(const UvLamp& lamp, const DosePlan& plan, const DoseLimits& limits, double gap_left_m,
                                    double gap_right_m) noexcept;

/// The speed limit of each leg of a coverage path (speeds[i]: the leg from path[i] to path[i+1];
/// the last entry repeats): a straight leg at least `min_lane_m` long is a lane, sped up per
/// lane_speed_m_s() from its nearest parallel neighbours that overlap it; every shorter leg (the
/// wall round's cell chains, short links, touch-ups) goes at the minimum speed, which doses the
/// floor beside it out to the plan's reach_m where no lane does.
[[nodiscard]] std::vector<double> lane_speeds(const std::vector<Point2D>& path, const UvLamp& lamp, const DosePlan& plan,
                                              const DoseLimits& limits, double min_lane_m = 0.5);

/// A coverage path with its speed limits (DosePath::speed_m_s[i]: the leg from path[i] on).
struct DosePath {
  std::vector<Point2D> path;
  std::vector<double> speed_m_s;
};

/// The coverage path as driven for the dose: lane_speeds(), and each lane's last lit radius at
/// each end split off at half its speed (not below the minimum): a lane end gets light from one
/// side of the lamp only, so half the dose of the lane's middle at the same speed; at half speed
/// its end point gets the middle's dose.
[[nodiscard]] DosePath dose_path(const std::vector<Point2D>& path, const UvLamp& lamp, const DosePlan& plan,
                                 const DoseLimits& limits, double min_lane_m = 0.5);

/// Time (s) to drive `path` at these per-leg speeds (turns not counted; +inf for a leg of speed 0).
[[nodiscard]] double path_time_s(const std::vector<Point2D>& path, const std::vector<double>& speeds) noexcept;

}  // namespace tripodal::navi
