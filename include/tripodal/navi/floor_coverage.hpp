// A whole floor cleaned room by room (issue 39): the coverage planner's path in every room (or
// section), the rooms visited in a tour from where the robot stands — always the nearest room not
// cleaned yet by the way through the doors — and the links between them planned by A*. The cost
// of the rooms' paths and of the tour are measured apart, so a floor's planning time can be read.
#pragma once

#include <cstddef>
#include <vector>

#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal::navi {

enum class FloorPattern { balloon, boustrophedon, hybrid };

struct FloorCoverage {
  std::vector<int> order;             ///< section ids in the order cleaned
  std::vector<CoverageResult> rooms;  ///< per entry of `order`, started where the robot came in
  std::vector<double> link_m;         ///< per entry of `order`: the way there from the previous end
  std::vector<int> unreachable;       ///< sections no way of free cells leads to (not cleaned)
  double length_m = 0.0;              ///< the rooms' paths and the links
  std::size_t turns = 0;
  double total_turn_rad = 0.0;
  std::size_t reachable_cells = 0;
  std::size_t covered_cells = 0;
  double rooms_ms = 0.0;  ///< planning the rooms' paths
  double tour_ms = 0.0;   ///< choosing the order and planning the links
  [[nodiscard]] double coverage() const noexcept {
    return reachable_cells == 0 ? 1.0 : static_cast<double>(covered_cells) / static_cast<double>(reachable_cells);
  }
};

/// Plans the floor from `start` (map frame). Each room's path begins nearest where the robot
/// enters it; the next room is the nearest uncleaned one by a breadth-first search over free
/// cells from the end of the last path, which stops at the first room it meets (no search over
/// the whole floor per room).
[[nodiscard]] FloorCoverage plan_floor(const OccupancyGrid& grid, const SectionSet& rooms, const CoverageOptions& options,
                                       Point2D start, FloorPattern pattern = FloorPattern::hybrid);

}  // namespace tripodal::navi
