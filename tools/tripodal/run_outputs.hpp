// What `tripodal run` writes after a run, besides the report's figures: the map picture
// (map.png), the trajectory (trajectory.csv) and the text helpers they share. Internal to the
// tool (tools/tripodal), between run_task.cpp and the writers, one file each.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "png.hpp"
#include "tripodal/core/geometry.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::app {

// The robot's navigation modules, which the measures read.
struct Navigation {
  const navi::CGridMaps* maps = nullptr;
  const navi::CSectionSplitter* splitter = nullptr;
  navi::CCoveragePlanner* coverage = nullptr;
};

/// One 10 Hz sample of the run: the simulator's true pose and the robot's estimate.
struct TrajectorySample {
  Time t{};
  Pose2D truth;
  Pose2D estimate;
  bool localized = false;
  bool cleaning = false;
};

/// The parameters a run on the simulator sets in the robot's profile: the hardware's seed, the
/// test-double localizer's seed, the scan-matching localizer's initial pose (the world's start).
std::vector<ParameterOverride> simulation_overrides(const RobotProfile& profile, const sim::World& world, std::uint64_t seed);

/// `v` with `digits` decimals.
std::string fixed(double v, int digits);

/// Writes `text` to `file`; std::runtime_error naming the file when it cannot.
void write_text(const std::filesystem::path& file, const std::string& text);

// The map (2 pixels per cell): walls black, unknown grey, sections tinted, cleaned cells green,
// cells the footprint could reach but did not clean red, virtual walls dashed red, the true path
// dark blue, start and end markers. A run without a task has no reachable cells and no path:
// `reachable` may be empty (or shorter than the grid), `traj` too; the map is drawn all the same.
RgbImage draw_map(const Navigation& nav, const navi::CleanedCells& cleaned, const std::vector<char>& reachable,
                  const std::vector<TrajectorySample>& traj);

/// dose.png: each floor cell's UV dose against the target (dose(i), J/m^2): walls black, cells
/// outside the measured floor grey; on it, red (no dose) through yellow (half) to green (the
/// target reached), and a darker green from twice the target.
template <typename DoseAt>
RgbImage draw_dose_map(const navi::OccupancyGrid& g, const std::vector<char>& floor, double target_j_m2, DoseAt dose);

/// trajectory.csv: one line per sample, SI units, header line first.
std::string trajectory_csv(const std::vector<TrajectorySample>& traj);

template <typename DoseAt>
RgbImage draw_dose_map(const navi::OccupancyGrid& g, const std::vector<char>& floor, double target_j_m2, DoseAt dose) {
  constexpr int kScale = 2;
  RgbImage img(g.width() * kScale, g.height() * kScale);
  for (std::size_t i = 0; i < g.size(); ++i) {
    const navi::CellIndex c = g.cell(i);
    std::array<std::uint8_t, 3> rgb{225, 225, 225};
    if (g.state(i) == navi::Occupancy::occupied) {
      rgb = {0, 0, 0};
    } else if (i < floor.size() && floor[i] != 0) {
      const double f = target_j_m2 > 0.0 ? dose(i) / target_j_m2 : 0.0;
      if (f >= 2.0)
        rgb = {20, 120, 40};
      else if (f >= 1.0)
        rgb = {60, 190, 70};
      else {
        const double t = std::clamp(f, 0.0, 1.0);  // red -> yellow
        rgb = {230, static_cast<std::uint8_t>(40 + 190 * t), 40};
      }
    }
    for (int dy = 0; dy < kScale; ++dy) {
      for (int dx = 0; dx < kScale; ++dx)
        img.set(c.x * kScale + dx, (g.height() - 1 - c.y) * kScale + dy, rgb[0], rgb[1], rgb[2]);
    }
  }
  return img;
}

}  // namespace tripodal::app
