// What `tripodal run` writes after a run, besides the report's figures: the map picture
// (map.png), the trajectory (trajectory.csv) and the text helpers they share. Internal to the
// tool (tools/tripodal), between run_task.cpp and the writers, one file each.
#pragma once

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
  navi::CCoverageModule* coverage = nullptr;
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

/// trajectory.csv: one line per sample, SI units, header line first.
std::string trajectory_csv(const std::vector<TrajectorySample>& traj);

}  // namespace tripodal::app
