// Shared by the coverage planner's units (coverage.cpp: the section's window, links and the
// touch-up; coverage_rounds.cpp: the balloon's rounds; coverage_lanes.cpp: lanes and the
// boustrophedon; coverage_hybrid.cpp: the hybrid's decomposition and tour). Not installed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "tripodal/navi/coverage.hpp"

namespace tripodal::navi {

// Per-section working data on a window around the section's bounding box.
struct CoveragePlanner::Workspace {
  int x0 = 0, y0 = 0, w = 0, h = 0;    // window in grid cells
  std::vector<float> offset;           // E, metres; -inf outside the section
  std::vector<std::uint8_t> stand;     // where the robot centre may be
  std::vector<std::size_t> reachable;  // global indices
  std::vector<std::size_t> stand_cells_global;
  CleanedCells cleaned;
  std::size_t section_cells = 0;

  [[nodiscard]] bool inside(int lx, int ly) const noexcept { return lx >= 0 && ly >= 0 && lx < w && ly < h; }
  [[nodiscard]] std::size_t local(int lx, int ly) const noexcept {
    return static_cast<std::size_t>(ly) * static_cast<std::size_t>(w) + static_cast<std::size_t>(lx);
  }
  [[nodiscard]] CellIndex global(int lx, int ly) const noexcept { return {lx + x0, ly + y0}; }
};

namespace coverage_detail {

// One run of a lane: the cells of a lane (a row, a column, or a slanted line) of the window
// between its ends, inclusive.
struct LaneRun {
  int lane = 0;        // position in the list of lanes
  int lo = 0, hi = 0;  // along the lane, window cells
  CellIndex a, b;      // grid cells at lo and hi
  bool done = false;
};

// The cell of lane `lane` at `along` (window cells, rounded to the nearest cell centre).
[[nodiscard]] CellIndex lane_cell(const CoveragePlanner::LaneFrame& f, int lane, int along) noexcept;

// The runs of `mask` along the given lanes of the frame (on the axes: window rows or columns).
[[nodiscard]] std::vector<LaneRun> lane_runs(const std::vector<std::uint8_t>& mask, int w, int h, int x0, int y0,
                                             const CoveragePlanner::LaneFrame& f, const std::vector<int>& lanes);

// The first and last lane of `mask` across the frame (lanes holding a marked cell); lo > hi if none.
[[nodiscard]] std::pair<int, int> lane_extent(const std::vector<std::uint8_t>& mask, int w, int h,
                                              const CoveragePlanner::LaneFrame& f);

[[nodiscard]] inline long long dist2(CellIndex a, CellIndex b) noexcept {
  return 1LL * (a.x - b.x) * (a.x - b.x) + 1LL * (a.y - b.y) * (a.y - b.y);
}

}  // namespace coverage_detail
}  // namespace tripodal::navi
