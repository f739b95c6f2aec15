// Zelinsky's distance-transform coverage (Zelinsky et al., 1993), the third baseline beside the
// balloon and the plough (navi::CoveragePlanner): the paper claims wall-following beats it, and
// docs/coverage.md measures where. The section is cut into cells the size of the cleaning tool;
// a wave from the goal numbers them by distance, and the robot always steps to the unvisited
// neighbour farthest from the goal, so it sweeps the far parts first and ends at the goal.
#pragma once

#include <optional>

#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal::navi {

/// The distance-transform coverage path of `section` from `start` back to `goal` (both default:
/// the section's standable cell nearest its first cell). Uses CoverageOptions' cleaning width,
/// overlap, robot radius, turn threshold and simplification; the result's figures are measured
/// like CoveragePlanner's (reachable cells, covered cells, length and turns of the simplified
/// path). There is no touch-up: the strips the tool-sized cells leave along walls stay uncovered,
/// as in the method. An empty section, or one where the robot cannot stand, gives an empty path.
[[nodiscard]] CoverageResult distance_transform_coverage(const OccupancyGrid& grid, const Section& section,
                                                         const CoverageOptions& options,
                                                         std::optional<Point2D> start = std::nullopt,
                                                         std::optional<Point2D> goal = std::nullopt);

}  // namespace tripodal::navi
