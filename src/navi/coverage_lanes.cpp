// Lanes on a section's window (rows, columns or slanted lines) and the boustrophedon baseline:
// plough lanes along the longer side of the section, nearest end first.
#include <algorithm>
#include <cmath>
#include <limits>

#include "coverage_internal.hpp"
#include "tripodal/navi/coverage.hpp"

namespace tripodal::navi {

namespace coverage_detail {

// The cell of lane `lane` at `along` (window cells, rounded to the nearest cell centre).
CellIndex lane_cell(const CoveragePlanner::LaneFrame& f, int lane, int along) noexcept {
  return {static_cast<int>(std::lround(lane * f.across_x + along * f.along_x)),
          static_cast<int>(std::lround(lane * f.across_y + along * f.along_y))};
}

// The runs of `mask` along the given lanes of the frame (on the axes: window rows or columns).
std::vector<LaneRun> lane_runs(const std::vector<std::uint8_t>& mask, int w, int h, int x0, int y0,
                               const CoveragePlanner::LaneFrame& f, const std::vector<int>& lanes) {
  std::vector<LaneRun> runs;
  // along positions that can fall in the window: the window's corners projected on the lanes
  double amin = std::numeric_limits<double>::infinity(), amax = -amin;
  for (const int cx : {0, w - 1}) {
    for (const int cy : {0, h - 1}) {
      const double a = cx * f.along_x + cy * f.along_y;
      amin = std::min(amin, a);
      amax = std::max(amax, a);
    }
  }
  const int a0 = static_cast<int>(std::floor(amin - 1e-9)), a1 = static_cast<int>(std::ceil(amax + 1e-9));
  const auto at = [&](int lane, int a) {
    const CellIndex c = lane_cell(f, lane, a);
    return c.x >= 0 && c.y >= 0 && c.x < w && c.y < h &&
           mask[static_cast<std::size_t>(c.y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c.x)] != 0;
  };
  const auto cell = [&](int lane, int a) {
    const CellIndex c = lane_cell(f, lane, a);
    return CellIndex{c.x + x0, c.y + y0};
  };
  for (std::size_t k = 0; k < lanes.size(); ++k) {
    const int l = lanes[k];
    int a = a0;
    while (a <= a1) {
      if (!at(l, a)) {
        ++a;
        continue;
      }
      const int s = a;
      while (a <= a1 && at(l, a)) ++a;
      runs.push_back({static_cast<int>(k), s, a - 1, cell(l, s), cell(l, a - 1), false});
    }
  }
  return runs;
}

// The first and last lane of `mask` across the frame (lanes holding a marked cell); lo > hi if none.
std::pair<int, int> lane_extent(const std::vector<std::uint8_t>& mask, int w, int h, const CoveragePlanner::LaneFrame& f) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (mask[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] == 0) continue;
      const double l = x * f.across_x + y * f.across_y;
      lo = std::min(lo, l);
      hi = std::max(hi, l);
    }
  }
  if (lo > hi) return {1, 0};
  return {static_cast<int>(std::lround(lo)), static_cast<int>(std::lround(hi))};
}

}  // namespace coverage_detail

using coverage_detail::LaneRun;

CoverageResult CoveragePlanner::boustrophedon(const Section& section, std::optional<Point2D> start) {
  CoverageResult r;
  Workspace ws = prepare(section);
  if (ws.stand_cells_global.empty()) {
    finish(r, ws, {0, 0});
    return r;
  }
  const bool rows = (section.max.x - section.min.x) >= (section.max.y - section.min.y);
  const double spacing = std::max(grid_.resolution_m(), options_.cleaning_width_m - options_.overlap_m);
  const int step = std::max(1, static_cast<int>(std::floor(spacing / grid_.resolution_m() + 1e-9)));
  const LaneFrame frame = rows ? kRows : kColumns;
  const auto [lo, hi] = coverage_detail::lane_extent(ws.stand, ws.w, ws.h, frame);
  std::vector<int> lanes;
  for (int l = lo; l <= hi; l += step) lanes.push_back(l);
  if (!lanes.empty() && lanes.back() != hi) lanes.push_back(hi);
  std::vector<LaneRun> iv = coverage_detail::lane_runs(ws.stand, ws.w, ws.h, ws.x0, ws.y0, frame, lanes);
  CellIndex cur = iv.empty() ? CellIndex{0, 0} : iv.front().a;
  if (start) {
    const auto c = grid_.world_to_cell(*start);
    if (c && planner_.traversable(*c)) {
      cur = *c;
      r.path.push_back(*start);
    }
  }
  for (std::size_t done = 0; done < iv.size(); ++done) {
    std::size_t best = iv.size();
    bool flip = false;
    long long best_d = std::numeric_limits<long long>::max();
    for (std::size_t k = 0; k < iv.size(); ++k) {
      if (iv[k].done) continue;
      const auto d2 = [&](CellIndex c) { return 1LL * (c.x - cur.x) * (c.x - cur.x) + 1LL * (c.y - cur.y) * (c.y - cur.y); };
      if (d2(iv[k].a) < best_d) {
        best_d = d2(iv[k].a);
        best = k;
        flip = false;
      }
      if (d2(iv[k].b) < best_d) {
        best_d = d2(iv[k].b);
        best = k;
        flip = true;
      }
    }
    LaneRun& it = iv[best];
    it.done = true;
    const CellIndex from = flip ? it.b : it.a;
    const CellIndex to = flip ? it.a : it.b;
    if (r.path.empty())
      r.path.push_back(grid_.cell_center(from));
    else
      link(r.path, cur, from);
    if (!(from == to)) r.path.push_back(grid_.cell_center(to));
    cur = to;
    ++r.passes;
  }
  finish(r, ws, cur);
  return r;
}

}  // namespace tripodal::navi
