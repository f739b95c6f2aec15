// The hybrid pattern: round 0 of the balloon along every wall, then lanes over the inside swept
// cell by cell of a boustrophedon decomposition, toured in the order of least travel; lanes
// along the rows, the columns or slanted walls, whichever path costs least.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "coverage_internal.hpp"
#include "tripodal/navi/coverage.hpp"

namespace tripodal::navi {

using coverage_detail::dist2;
using coverage_detail::lane_cell;
using coverage_detail::lane_extent;
using coverage_detail::lane_runs;
using coverage_detail::LaneRun;

namespace {

// Cells of the boustrophedon decomposition: runs of neighbouring lanes that overlap one to one
// are swept in one go, lane after lane; a split or a merge (an obstacle, a bay) ends a cell.
std::vector<std::vector<std::size_t>> decompose(const std::vector<LaneRun>& runs) {
  std::vector<std::vector<std::size_t>> up(runs.size()), down(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    for (std::size_t j = i + 1; j < runs.size() && runs[j].lane <= runs[i].lane + 1; ++j) {
      if (runs[j].lane != runs[i].lane + 1) continue;
      if (runs[j].lo <= runs[i].hi && runs[i].lo <= runs[j].hi) {
        up[i].push_back(j);
        down[j].push_back(i);
      }
    }
  }
  const std::size_t none = runs.size();
  std::vector<std::size_t> next(runs.size(), none), prev(runs.size(), none);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (up[i].size() == 1 && down[up[i][0]].size() == 1) {
      next[i] = up[i][0];
      prev[up[i][0]] = i;
    }
  }
  std::vector<std::vector<std::size_t>> cells;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (prev[i] != none) continue;
    cells.emplace_back();
    for (std::size_t k = i; k != none; k = next[k]) cells.back().push_back(k);
  }
  return cells;
}

// A lane cell's runs from the first (or, from_top, the last), the first run swept one way or the
// other and each next from its end nearer to where the last one ended: visit(from, to) per run.
template <class Visit>
void sweep_order(const std::vector<LaneRun>& runs, const std::vector<std::size_t>& cell, bool from_top, bool first_flipped,
                 Visit&& visit) {
  std::vector<std::size_t> order = cell;
  if (from_top) std::reverse(order.begin(), order.end());
  CellIndex at{-1, -1};
  for (std::size_t k = 0; k < order.size(); ++k) {
    const LaneRun& run = runs[order[k]];
    const bool flip = k == 0 ? first_flipped : dist2(at, run.b) < dist2(at, run.a);
    visit(flip ? run.b : run.a, flip ? run.a : run.b);
    at = flip ? run.a : run.b;
  }
}

// One way through an item of the tour: where it is entered and left, and the travel inside it.
struct Way {
  CellIndex entry, exit;
  double inside_m = 0.0;  // travel within the item (lanes and the steps between them)
};

// The tour's items: the lane cells (entered at the first or the last run, that run swept one
// way or the other: 4 ways) and the open pieces of the round (from either end: 2 ways).
// item_piece: the piece of an item; kLaneCell for a lane cell (the first items).
constexpr std::size_t kLaneCell = std::numeric_limits<std::size_t>::max();
struct TourItems {
  std::vector<std::vector<Way>> ways;
  std::vector<std::size_t> item_piece;
};

template <class Piece>
TourItems tour_items(const std::vector<LaneRun>& runs, const std::vector<std::vector<std::size_t>>& cells,
                     const std::vector<Piece>& pieces, double res) {
  const auto metres = [&](CellIndex p, CellIndex q) { return std::sqrt(static_cast<double>(dist2(p, q))) * res; };
  TourItems t;
  for (const std::vector<std::size_t>& cell : cells) {
    t.ways.emplace_back();
    for (const int w : {0, 1, 2, 3}) {
      Way way;
      bool first = true;
      CellIndex at{};
      sweep_order(runs, cell, (w & 2) != 0, (w & 1) != 0, [&](CellIndex from, CellIndex to) {
        if (first)
          way.entry = from;
        else
          way.inside_m += metres(at, from);
        way.inside_m += metres(from, to);
        at = to;
        first = false;
      });
      way.exit = at;
      t.ways.back().push_back(way);
    }
    t.item_piece.push_back(kLaneCell);
  }
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    if (pieces[p].closed) continue;  // inserted afterwards (insert_round)
    const auto& pc = pieces[p].cells;
    const double len = static_cast<double>(pc.size()) * res;
    t.ways.push_back({Way{pc.front(), pc.back(), len}, Way{pc.back(), pc.front(), len}});
    t.item_piece.push_back(p);
  }
  return t;
}

using Tour = std::vector<std::pair<std::size_t, std::size_t>>;  // (item, way)

// Held-Karp over the items and their ways, straight-line links from `first_at` (none when
// first_at.x < 0), plus end_cost(exit) of the last item's exit.
template <class EndCost>
Tour tour_exact(const std::vector<std::vector<Way>>& ways, CellIndex first_at, double res, EndCost&& end_cost) {
  const auto metres = [&](CellIndex p, CellIndex q) { return std::sqrt(static_cast<double>(dist2(p, q))) * res; };
  const auto link_m = [&](CellIndex from, CellIndex to) { return from.x < 0 ? 0.0 : metres(from, to); };
  const std::size_t items = ways.size();
  constexpr std::size_t kWays = 4;
  const std::size_t masks = std::size_t{1} << items;
  const auto at = [&](std::size_t set, std::size_t i, std::size_t w) { return (set * items + i) * kWays + w; };
  std::vector<double> cost(masks * items * kWays, std::numeric_limits<double>::infinity());
  std::vector<std::uint32_t> parent(cost.size(), 0);
  // exit of (i, w) to entry of (j, v) plus the inside of (j, v), once
  std::vector<double> leg_m(items * kWays * items * kWays, std::numeric_limits<double>::infinity());
  const auto leg_at = [&](std::size_t i, std::size_t w, std::size_t j, std::size_t v) {
    return ((i * kWays + w) * items + j) * kWays + v;
  };
  for (std::size_t i = 0; i < items; ++i) {
    for (std::size_t w = 0; w < ways[i].size(); ++w) {
      for (std::size_t j = 0; j < items; ++j) {
        for (std::size_t v = 0; v < ways[j].size(); ++v) {
          leg_m[leg_at(i, w, j, v)] = metres(ways[i][w].exit, ways[j][v].entry) + ways[j][v].inside_m;
        }
      }
    }
  }
  for (std::size_t i = 0; i < items; ++i) {
    for (std::size_t w = 0; w < ways[i].size(); ++w) {
      cost[at(std::size_t{1} << i, i, w)] = link_m(first_at, ways[i][w].entry) + ways[i][w].inside_m;
    }
  }
  for (std::size_t set = 1; set < masks; ++set) {
    for (std::size_t i = 0; i < items; ++i) {
      if ((set & (std::size_t{1} << i)) == 0) continue;
      for (std::size_t w = 0; w < ways[i].size(); ++w) {
        const double c = cost[at(set, i, w)];
        if (!std::isfinite(c)) continue;
        for (std::size_t j = 0; j < items; ++j) {
          if ((set & (std::size_t{1} << j)) != 0) continue;
          const std::size_t grown = set | (std::size_t{1} << j);
          for (std::size_t v = 0; v < ways[j].size(); ++v) {
            const double nc = c + leg_m[leg_at(i, w, j, v)];
            if (nc < cost[at(grown, j, v)]) {
              cost[at(grown, j, v)] = nc;
              parent[at(grown, j, v)] = static_cast<std::uint32_t>(i * kWays + w);
            }
          }
        }
      }
    }
  }
  const std::size_t full = masks - 1;
  double best = std::numeric_limits<double>::infinity();
  std::size_t bi = 0, bw = 0;
  for (std::size_t i = 0; i < items; ++i) {
    for (std::size_t w = 0; w < ways[i].size(); ++w) {
      const double c = cost[at(full, i, w)] + end_cost(ways[i][w].exit);
      if (c < best) best = c, bi = i, bw = w;
    }
  }
  Tour tour;
  for (std::size_t set = full;;) {
    tour.emplace_back(bi, bw);
    const std::size_t before = set & ~(std::size_t{1} << bi);
    if (before == 0) break;
    const std::uint32_t p = parent[at(set, bi, bw)];
    set = before;
    bi = p / kWays;
    bw = p % kWays;
  }
  std::reverse(tour.begin(), tour.end());
  return tour;
}

// Nearest entry next, from `first_at` (any item first when first_at.x < 0).
Tour tour_nearest_next(const std::vector<std::vector<Way>>& ways, CellIndex first_at, double res) {
  const auto link_m = [&](CellIndex from, CellIndex to) {
    return from.x < 0 ? 0.0 : std::sqrt(static_cast<double>(dist2(from, to))) * res;
  };
  const std::size_t items = ways.size();
  Tour tour;
  std::vector<bool> used(items, false);
  CellIndex at = first_at;
  for (std::size_t left = items; left > 0; --left) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t bi = 0, bw = 0;
    for (std::size_t i = 0; i < items; ++i) {
      if (used[i]) continue;
      for (std::size_t w = 0; w < ways[i].size(); ++w) {
        const double d = link_m(at, ways[i][w].entry);
        if (d < best) best = d, bi = i, bw = w;
      }
    }
    used[bi] = true;
    tour.emplace_back(bi, bw);
    at = ways[bi][bw].exit;
  }
  return tour;
}

}  // namespace

std::vector<int> CoveragePlanner::place_lanes(const Workspace& ws, const std::vector<std::uint8_t>& mask,
                                              const LaneFrame& frame) const {
  // The lanes lie where the offset leaves a lane spacing to the wall round (the first lane's
  // swath meets the round's); along a lane, its run goes on over `mask`, closer to the round.
  const double lane_spacing = std::max(grid_.resolution_m(), options_.cleaning_width_m - options_.lane_overlap_m);
  std::vector<std::uint8_t> far(mask.size());
  for (std::size_t li = 0; li < mask.size(); ++li) {
    far[li] = mask[li] != 0 && ws.offset[li] >= static_cast<float>(lane_spacing) ? 1 : 0;
  }
  const auto [lo, hi] = lane_extent(far, ws.w, ws.h, frame);
  // Lanes spread evenly from the first to the last lane, at most one spacing apart: no thin
  // last lane that repeats its neighbour.
  const double step = lane_spacing / grid_.resolution_m();
  const int count = lo > hi ? 0 : static_cast<int>(std::ceil(static_cast<double>(hi - lo) / step - 1e-9)) + 1;
  std::vector<int> lanes;
  lanes.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    lanes.push_back(count == 1 ? (lo + hi) / 2
                               : lo + static_cast<int>(std::lround(static_cast<double>(k) * (hi - lo) / (count - 1))));
  }
  return lanes;
}

void CoveragePlanner::plough(Workspace& ws, const std::vector<std::uint8_t>& mask, const LaneFrame& frame,
                             const std::vector<RoundPiece>& pieces, CellIndex& cur, CoverageResult& r,
                             std::optional<Point2D> start, std::optional<Point2D> finish_near) {
  const std::vector<int> lanes = place_lanes(ws, mask, frame);
  std::vector<LaneRun> runs = lane_runs(mask, ws.w, ws.h, ws.x0, ws.y0, frame, lanes);
  // a run whose cells are all within the footprint radius of the round lies in its swath
  const auto beyond_round = static_cast<float>(options_.cleaning_width_m / 2.0);
  std::erase_if(runs, [&](const LaneRun& run) {
    for (int a = run.lo; a <= run.hi; ++a) {
      const CellIndex c = lane_cell(frame, lanes[static_cast<std::size_t>(run.lane)], a);
      if (ws.inside(c.x, c.y) && ws.offset[ws.local(c.x, c.y)] > beyond_round) return false;
    }
    return true;
  });
  const std::vector<std::vector<std::size_t>> cells = decompose(runs);
  // The closed pieces (rounds around obstacles inside the section) are left out of the tour and
  // inserted afterwards where it passes nearest (insert_round): a greedy tour would otherwise
  // jump to one as soon as it is the nearest thing and jump back, several metres each way.
  const TourItems items = tour_items(runs, cells, pieces, grid_.resolution_m());
  // The order: exact (Held-Karp over items and ways, straight-line links) for the few items of
  // a room-sized section, nearest-next beyond. With `finish_near`, the distance from the tour's
  // end to it counts too: the next section's path starts there.
  const auto end_cost = [&](CellIndex exit) {
    return finish_near
               ? std::hypot(grid_.cell_center(exit).x_m - finish_near->x_m, grid_.cell_center(exit).y_m - finish_near->y_m)
               : 0.0;
  };
  const std::size_t n_items = items.ways.size();
  const Tour tour = n_items > 0 && n_items <= kExactTourItems ? tour_exact(items.ways, cur, grid_.resolution_m(), end_cost)
                                                              : tour_nearest_next(items.ways, cur, grid_.resolution_m());
  const auto go_to = [&](CellIndex to) {
    if (r.path.empty()) {
      if (start) {
        r.path.push_back(*start);
        if (cur.x >= 0 && grid_.contains(cur) && planner_.traversable(cur)) link(r.path, cur, to);
      }
      const Point2D p = grid_.cell_center(to);
      if (r.path.empty() || std::hypot(r.path.back().x_m - p.x_m, r.path.back().y_m - p.y_m) > 1e-9) r.path.push_back(p);
    } else {
      link(r.path, cur, to);
    }
    cur = to;
  };
  const std::size_t tour_begin = r.path.size();
  for (const auto& [item, way] : tour) {
    if (items.item_piece[item] != kLaneCell) {
      RoundPiece piece = pieces[items.item_piece[item]];
      if (way == 1) std::reverse(piece.cells.begin(), piece.cells.end());
      append_piece(r, cur, piece, start);
      continue;
    }
    sweep_order(runs, cells[item], (way & 2) != 0, (way & 1) != 0, [&](CellIndex from, CellIndex to) {
      go_to(from);
      go_to(to);
      ++r.passes;
    });
  }
  for (const RoundPiece& piece : pieces) {
    if (piece.closed) insert_round(r, cur, piece, tour_begin, start);
  }
}

std::optional<double> CoveragePlanner::slanted_walls_rad(const std::vector<RoundPiece>& pieces) const {
  // The round's pieces simplified to straight sides; their directions modulo a right angle,
  // weighted by length, in 1-degree bins smoothed over +-2 degrees: the peak is the walls' way.
  constexpr int kBins = 90;
  std::vector<double> weight(kBins, 0.0), sum_sin(kBins, 0.0), sum_cos(kBins, 0.0);
  const double tolerance = 2.0 * grid_.resolution_m();
  for (const RoundPiece& piece : pieces) {
    std::vector<Point2D> pts;
    pts.reserve(piece.cells.size());
    for (const CellIndex& c : piece.cells) pts.push_back(grid_.cell_center(c));
    const std::vector<Point2D> sides = douglas_peucker(pts, tolerance);
    for (std::size_t k = 1; k < sides.size(); ++k) {
      const double dx = sides[k].x_m - sides[k - 1].x_m, dy = sides[k].y_m - sides[k - 1].y_m;
      const double len = std::hypot(dx, dy);
      if (len < 4.0 * tolerance) continue;
      // the angle modulo 90 degrees, averaged on the circle of 4x the angle
      const double q = 4.0 * std::atan2(dy, dx);
      double deg = std::atan2(std::sin(q), std::cos(q)) / 4.0 * 180.0 / std::numbers::pi;
      if (deg < 0.0) deg += 90.0;
      const int bin = std::clamp(static_cast<int>(deg), 0, kBins - 1);
      weight[static_cast<std::size_t>(bin)] += len;
      sum_sin[static_cast<std::size_t>(bin)] += len * std::sin(q);
      sum_cos[static_cast<std::size_t>(bin)] += len * std::cos(q);
    }
  }
  int peak = -1;
  double peak_w = 0.0;
  for (int b = 0; b < kBins; ++b) {
    double w = 0.0;
    for (int d = -2; d <= 2; ++d) w += weight[static_cast<std::size_t>((b + d + kBins) % kBins)];
    if (w > peak_w) peak_w = w, peak = b;
  }
  if (peak < 0) return std::nullopt;
  double ss = 0.0, sc = 0.0;
  for (int d = -2; d <= 2; ++d) {
    ss += sum_sin[static_cast<std::size_t>((peak + d + kBins) % kBins)];
    sc += sum_cos[static_cast<std::size_t>((peak + d + kBins) % kBins)];
  }
  const double angle = std::atan2(ss, sc) / 4.0;  // (-45, 45] degrees
  // within a few degrees of the grid's axes the rows and columns are those lanes already
  if (std::abs(angle) < kSlantedWallsMinRad) return std::nullopt;
  return angle;
}

CoverageResult CoveragePlanner::hybrid(const Section& section, std::optional<Point2D> start, std::optional<Point2D> finish_near) {
  Workspace ws = prepare(section);
  if (ws.stand_cells_global.empty()) {
    CoverageResult r;
    finish(r, ws, {0, 0});
    return r;
  }
  const std::size_t n = ws.offset.size();
  // Round 0 of the balloon, tangent to every wall and obstacle; inside it, lanes over the region
  // whose offset from the round is at least the inset. On paper the lanes' round end caps close
  // the gaps between lane ends and the round up to r + sqrt(r^2 - spacing^2 / 4) (0.44 m at
  // PSR-2's 0.64 m), but a driven robot rounds the corners of its U-turns and leaves wedges
  // there: lanes that end one cell inside the round turn on its swath (demo, seed 1, PSR-2:
  // 99.67 % driven coverage, against 97.96 % at the paper's inset).
  const double inset = options_.lane_inset_m > 0.0 ? options_.lane_inset_m : grid_.resolution_m();
  std::vector<std::uint8_t> wall(n), inner(n);
  for (std::size_t li = 0; li < n; ++li) {
    wall[li] = ws.stand[li] != 0 ? 1 : 0;
    inner[li] = ws.stand[li] != 0 && ws.offset[li] >= static_cast<float>(inset) ? 1 : 0;
  }
  std::optional<CoverageResult> best;
  double best_cost = std::numeric_limits<double>::infinity();
  // Rows and columns, and where the walls run slanted to the grid (a pentagonal building, a
  // wing at an angle), lanes along and across them: lanes on the grid axes end in staircases
  // at slanted walls and leave wedges the touch-up then visits one by one.
  std::vector<LaneFrame> frames{kRows, kColumns};
  {
    const CellIndex from = start_cell(start);
    auto pieces = round_pieces(ws, wall, from);
    if (pieces) {
      join_pieces(*pieces);  // along a slanted wall the walk breaks into pieces of a few cells
      if (const auto angle = slanted_walls_rad(*pieces)) {
        const double c = std::cos(*angle), s = std::sin(*angle);
        frames.push_back({c, s, -s, c});
        frames.push_back({-s, c, c, s});
      }
    }
  }
  for (const LaneFrame& frame : frames) {
    Workspace w = ws;
    CoverageResult res;
    CellIndex cur = start_cell(start);
    auto pieces = round_pieces(w, wall, cur);
    if (pieces) {
      res.rounds = 1;
      join_pieces(*pieces);
    }
    plough(w, inner, frame, pieces ? *pieces : std::vector<RoundPiece>{}, cur, res, start, finish_near);
    finish(res, w, cur);
    // Lanes across the shorter way cost turns and lane ends: keep the direction whose path is
    // cheaper, a turn counted as options_.turn_cost_m of travel, and the way on to finish_near.
    double cost = res.stats.length_m + options_.turn_cost_m * static_cast<double>(res.stats.turns);
    if (finish_near && !res.path.empty()) {
      cost += std::hypot(res.path.back().x_m - finish_near->x_m, res.path.back().y_m - finish_near->y_m);
    }
    if (cost < best_cost) {
      best_cost = cost;
      best = std::move(res);
    }
  }
  return std::move(*best);
}

}  // namespace tripodal::navi
