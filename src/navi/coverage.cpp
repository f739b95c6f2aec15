#include "tripodal/navi/coverage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "tripodal/navi/distance_field.hpp"

namespace tripodal::navi {

// ---------------------------------------------------------------- cleaned cells

CleanedCells::CleanedCells(const OccupancyGrid& grid)
    : width_(grid.width()), height_(grid.height()), frame_(0, 0, grid.resolution_m(), grid.origin()),
      mask_(grid.size(), 0) {}

void CleanedCells::clear() noexcept { std::fill(mask_.begin(), mask_.end(), 0); }

void CleanedCells::mark_disc(Point2D centre, double radius_m) noexcept { mark_segment(centre, centre, radius_m); }

void CleanedCells::mark_segment(Point2D a, Point2D b, double radius_m) noexcept {
  if (width_ == 0 || height_ == 0) return;
  // Work in the grid frame, in cells: the capsule around a-b.
  const double res = frame_.resolution_m();
  const Point2D ga = frame_.to_grid_frame(a), gb = frame_.to_grid_frame(b);
  const double ax = ga.x_m / res, ay = ga.y_m / res, bx = gb.x_m / res, by = gb.y_m / res;
  const double r = radius_m / res;
  if (!std::isfinite(ax) || !std::isfinite(ay) || !std::isfinite(bx) || !std::isfinite(by) || !(r >= 0.0)) return;
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min(ax, bx) - r)));
  const int x1 = std::min(width_ - 1, static_cast<int>(std::ceil(std::max(ax, bx) + r)));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min(ay, by) - r)));
  const int y1 = std::min(height_ - 1, static_cast<int>(std::ceil(std::max(ay, by) + r)));
  const double dx = bx - ax, dy = by - ay;
  const double len2 = dx * dx + dy * dy;
  const double r2 = r * r + 1e-9;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const double px = x + 0.5 - ax, py = y + 0.5 - ay;
      double t = len2 > 0.0 ? (px * dx + py * dy) / len2 : 0.0;
      t = std::clamp(t, 0.0, 1.0);
      const double ex = px - t * dx, ey = py - t * dy;
      if (ex * ex + ey * ey <= r2) mask_[index({x, y})] = 1;
    }
  }
}

void CleanedCells::mark_path(const std::vector<Point2D>& path, double radius_m) noexcept {
  if (path.size() == 1) mark_disc(path[0], radius_m);
  for (std::size_t i = 1; i < path.size(); ++i) mark_segment(path[i - 1], path[i], radius_m);
}

std::size_t CleanedCells::count() const noexcept {
  return static_cast<std::size_t>(std::count(mask_.begin(), mask_.end(), std::uint8_t{1}));
}

double CleanedCells::coverage(const std::vector<std::size_t>& cells) const noexcept {
  if (cells.empty()) return 1.0;
  std::size_t n = 0;
  for (const std::size_t i : cells) n += mask_[i] != 0 ? 1 : 0;
  return static_cast<double>(n) / static_cast<double>(cells.size());
}

// ---------------------------------------------------------------- path statistics

PathStats path_stats(const std::vector<Point2D>& path, double turn_threshold_rad) noexcept {
  PathStats s;
  s.length_m = polyline_length_m(path);
  // headings of the legs that have a length
  double prev = 0.0;
  bool have_prev = false;
  for (std::size_t i = 1; i < path.size(); ++i) {
    const double dx = path[i].x_m - path[i - 1].x_m, dy = path[i].y_m - path[i - 1].y_m;
    if (std::hypot(dx, dy) < 1e-9) continue;
    const double h = std::atan2(dy, dx);
    if (have_prev) {
      double d = h - prev;
      while (d > std::numbers::pi) d -= 2.0 * std::numbers::pi;
      while (d < -std::numbers::pi) d += 2.0 * std::numbers::pi;
      s.total_turn_rad += std::abs(d);
      if (std::abs(d) > turn_threshold_rad) ++s.turns;
    }
    prev = h;
    have_prev = true;
  }
  return s;
}

// ---------------------------------------------------------------- coverage planner

// Per-section working data on a window around the section's bounding box.
struct CoveragePlanner::Workspace {
  int x0 = 0, y0 = 0, w = 0, h = 0;  // window in grid cells
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

CoveragePlanner::CoveragePlanner(const OccupancyGrid& grid, CoverageOptions options)
    : grid_(grid), options_(options),
      planner_(grid, [&] {
        PathPlannerOptions o{options.robot_radius_m > 0.0 ? options.robot_radius_m : options.cleaning_width_m / 2.0,
                             true, true};
        if (options.link_margin_m > 0.0) o.preferred_clearance_m = o.robot_radius_m + options.link_margin_m;
        return o;
      }()) {
  if (options_.robot_radius_m <= 0.0) options_.robot_radius_m = options_.cleaning_width_m / 2.0;
  if (options_.simplify_tolerance_m <= 0.0) options_.simplify_tolerance_m = 0.75 * grid.resolution_m();
}

CoveragePlanner::Workspace CoveragePlanner::prepare(const Section& section) {
  Workspace ws;
  ws.cleaned = CleanedCells(grid_);
  ws.section_cells = section.cells.size();
  if (section.cells.empty()) return ws;
  ws.x0 = section.min.x - 1;
  ws.y0 = section.min.y - 1;
  ws.w = section.max.x - section.min.x + 3;
  ws.h = section.max.y - section.min.y + 3;
  const std::size_t n = static_cast<std::size_t>(ws.w) * static_cast<std::size_t>(ws.h);
  std::vector<bool> outside(n, true);
  for (const std::size_t i : section.cells) {
    const CellIndex c = grid_.cell(i);
    outside[ws.local(c.x - ws.x0, c.y - ws.y0)] = false;
  }
  const DistanceField dsec(ws.w, ws.h, grid_.resolution_m(), outside);
  const DistanceField& dphys = planner_.distance_field();
  const double half = options_.cleaning_width_m / 2.0;
  ws.offset.assign(n, -std::numeric_limits<float>::infinity());
  ws.stand.assign(n, 0);
  for (int ly = 0; ly < ws.h; ++ly) {
    for (int lx = 0; lx < ws.w; ++lx) {
      const std::size_t li = ws.local(lx, ly);
      if (outside[li]) continue;
      const std::size_t gi = grid_.index(ws.global(lx, ly));
      const double e = std::min(dsec.clearance_m(li) - half,
                                dphys.distance_m(gi) > 0.0 ? dphys.clearance_m(gi) - options_.robot_radius_m : -1.0);
      ws.offset[li] = static_cast<float>(e);
      ws.stand[li] = e >= 0.0 ? 1 : 0;
    }
  }
  // stand components (8-connected as A* moves); keep those the planner can link to the largest one
  std::vector<int> comp(n, -1);
  std::vector<std::vector<std::size_t>> comps;
  std::vector<std::size_t> stack;
  for (std::size_t s = 0; s < n; ++s) {
    if (ws.stand[s] == 0 || comp[s] >= 0) continue;
    const int id = static_cast<int>(comps.size());
    comps.emplace_back();
    comp[s] = id;
    stack.push_back(s);
    while (!stack.empty()) {
      const std::size_t li = stack.back();
      stack.pop_back();
      comps.back().push_back(li);
      const int lx = static_cast<int>(li % static_cast<std::size_t>(ws.w));
      const int ly = static_cast<int>(li / static_cast<std::size_t>(ws.w));
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (!ws.inside(lx + dx, ly + dy)) continue;
          // diagonal neighbours as A* has them: not across the corner of an inflated obstacle
          if (dx != 0 && dy != 0 &&
              (!planner_.traversable(ws.global(lx + dx, ly)) || !planner_.traversable(ws.global(lx, ly + dy)))) {
            continue;
          }
          const std::size_t k = ws.local(lx + dx, ly + dy);
          if (ws.stand[k] != 0 && comp[k] < 0) {
            comp[k] = id;
            stack.push_back(k);
          }
        }
      }
    }
  }
  if (comps.empty()) return ws;
  std::size_t main = 0;
  for (std::size_t k = 1; k < comps.size(); ++k) {
    if (comps[k].size() > comps[main].size()) main = k;
  }
  const auto cell_of_local = [&](std::size_t li) {
    return ws.global(static_cast<int>(li % static_cast<std::size_t>(ws.w)),
                     static_cast<int>(li / static_cast<std::size_t>(ws.w)));
  };
  for (std::size_t k = 0; k < comps.size(); ++k) {
    if (k == main) continue;
    if (!planner_.plan(cell_of_local(comps[main].front()), cell_of_local(comps[k].front())).ok()) {
      for (const std::size_t li : comps[k]) ws.stand[li] = 0;
    }
  }
  // reachable: section cells within the footprint radius of a standing cell
  std::vector<bool> is_stand(n);
  for (std::size_t li = 0; li < n; ++li) is_stand[li] = ws.stand[li] != 0;
  const DistanceField to_stand(ws.w, ws.h, grid_.resolution_m(), is_stand, false);
  for (std::size_t li = 0; li < n; ++li) {
    if (outside[li]) continue;
    const std::size_t gi = grid_.index(cell_of_local(li));
    if (ws.stand[li] != 0) ws.stand_cells_global.push_back(gi);
    if (to_stand.distance_m(li) <= half + 1e-6) ws.reachable.push_back(gi);  // float distances
  }
  return ws;
}

void CoveragePlanner::link(std::vector<Point2D>& path, CellIndex from, CellIndex to) {
  if (from == to) return;
  const double keep = planner_.leg_clearance_m(from, to);
  if (planner_.line_of_sight(from, to, keep)) {
    path.push_back(grid_.cell_center(to));
    return;
  }
  const PlannedPath p = planner_.plan(from, to, keep);
  if (!p.ok()) return;  // cannot happen for cells of linked components; leave a jump rather than fail
  path.insert(path.end(), p.waypoints.begin() + 1, p.waypoints.end());
}

void CoveragePlanner::finish(CoverageResult& r, Workspace& ws, CellIndex cur) {
  const double half = options_.cleaning_width_m / 2.0;
  ws.cleaned.mark_path(r.path, half);
  if (options_.touch_up && !ws.stand_cells_global.empty()) {
    std::vector<std::size_t> todo;
    for (const std::size_t i : ws.reachable) {
      if (!ws.cleaned.cleaned(i)) todo.push_back(i);
    }
    const int reach = static_cast<int>(std::ceil(half / grid_.resolution_m()));
    while (!todo.empty()) {
      // nearest uncleaned cell
      std::size_t best = 0;
      long long best_d = std::numeric_limits<long long>::max();
      for (std::size_t k = 0; k < todo.size(); ++k) {
        const CellIndex c = grid_.cell(todo[k]);
        const long long d = 1LL * (c.x - cur.x) * (c.x - cur.x) + 1LL * (c.y - cur.y) * (c.y - cur.y);
        if (d < best_d) {
          best_d = d;
          best = k;
        }
      }
      const CellIndex u = grid_.cell(todo[best]);
      // a standing cell whose footprint covers u, the nearest to the robot
      std::optional<CellIndex> target;
      long long target_d = std::numeric_limits<long long>::max();
      const double r2 = (half / grid_.resolution_m()) * (half / grid_.resolution_m()) + 1e-9;
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          if (dx * dx + dy * dy > r2) continue;
          const int lx = u.x + dx - ws.x0, ly = u.y + dy - ws.y0;
          if (!ws.inside(lx, ly) || ws.stand[ws.local(lx, ly)] == 0) continue;
          const CellIndex t{u.x + dx, u.y + dy};
          const long long d = 1LL * (t.x - cur.x) * (t.x - cur.x) + 1LL * (t.y - cur.y) * (t.y - cur.y);
          if (d < target_d) {
            target_d = d;
            target = t;
          }
        }
      }
      const std::size_t before = r.path.size();
      if (target) {
        if (r.path.empty()) r.path.push_back(grid_.cell_center(*target));
        link(r.path, cur, *target);
        cur = *target;
        ++r.touch_ups;
        for (std::size_t k = before == 0 ? 0 : before - 1; k + 1 < r.path.size(); ++k) {
          ws.cleaned.mark_segment(r.path[k], r.path[k + 1], half);
        }
        ws.cleaned.mark_disc(grid_.cell_center(cur), half);
      }
      ws.cleaned.mark_disc(grid_.cell_center(u), 0.0);  // never pick u again, even if unreachable
      const auto unclean = [&](std::size_t i) { return !ws.cleaned.cleaned(i); };
      std::vector<std::size_t> next;
      next.reserve(todo.size());
      for (const std::size_t i : todo) {
        if (unclean(i)) next.push_back(i);
      }
      todo.swap(next);
    }
    // the forced marks above are not cleaning: recount from the path itself
    ws.cleaned.clear();
    ws.cleaned.mark_path(r.path, half);
  }
  // Measured on the path's shape: a chain of cell centres along a slanted contour is a staircase
  // whose steps are not turns of the robot.
  const std::vector<Point2D> shape = douglas_peucker(r.path, options_.simplify_tolerance_m);
  r.stats = path_stats(shape, options_.turn_threshold_rad);
  r.section_cells = ws.section_cells;
  r.reachable_cells = ws.reachable.size();
  r.covered_cells = 0;
  for (const std::size_t i : ws.reachable) r.covered_cells += ws.cleaned.cleaned(i) ? 1 : 0;
}

std::optional<std::vector<CoveragePlanner::RoundPiece>> CoveragePlanner::round_pieces(
    Workspace& ws, const std::vector<std::uint8_t>& in_round, CellIndex cur) const {
  const std::size_t n = ws.offset.size();
  std::vector<std::uint8_t> boundary(n, 0), used(n, 0), near(n, 0);
  std::vector<std::size_t> boundary_cells;
  for (int ly = 0; ly < ws.h; ++ly) {
    for (int lx = 0; lx < ws.w; ++lx) {
      const std::size_t li = ws.local(lx, ly);
      if (in_round[li] == 0) continue;
      const int nx[4] = {lx + 1, lx - 1, lx, lx};
      const int ny[4] = {ly, ly, ly + 1, ly - 1};
      for (int q = 0; q < 4; ++q) {
        if (!ws.inside(nx[q], ny[q]) || in_round[ws.local(nx[q], ny[q])] == 0) {
          boundary[li] = 1;
          boundary_cells.push_back(li);
          break;
        }
      }
    }
  }
  if (boundary_cells.empty()) return std::nullopt;
  std::vector<RoundPiece> pieces;
  std::vector<CellIndex> chain;
  for (;;) {
    // the nearest boundary cell not yet walked or beside a walked one
    std::size_t seed = n;
    long long seed_d = std::numeric_limits<long long>::max();
    for (const std::size_t li : boundary_cells) {
      if (used[li] != 0 || near[li] != 0) continue;
      const int lx = static_cast<int>(li % static_cast<std::size_t>(ws.w));
      const int ly = static_cast<int>(li / static_cast<std::size_t>(ws.w));
      const CellIndex g = ws.global(lx, ly);
      const long long d = cur.x < 0 ? static_cast<long long>(li)
                                    : 1LL * (g.x - cur.x) * (g.x - cur.x) + 1LL * (g.y - cur.y) * (g.y - cur.y);
      if (d < seed_d) {
        seed_d = d;
        seed = li;
      }
    }
    if (seed == n) break;
    // walk the chain, keeping the heading where possible
    chain.clear();
    int lx = static_cast<int>(seed % static_cast<std::size_t>(ws.w));
    int ly = static_cast<int>(seed / static_cast<std::size_t>(ws.w));
    int hx = 0, hy = 0;
    for (;;) {
      const std::size_t li = ws.local(lx, ly);
      used[li] = 1;
      chain.push_back(ws.global(lx, ly));
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (ws.inside(lx + dx, ly + dy)) near[ws.local(lx + dx, ly + dy)] = 1;
        }
      }
      int best_dx = 0, best_dy = 0;
      double best_cost = std::numeric_limits<double>::infinity();
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if ((dx == 0 && dy == 0) || !ws.inside(lx + dx, ly + dy)) continue;
          const std::size_t k2 = ws.local(lx + dx, ly + dy);
          if (boundary[k2] == 0 || used[k2] != 0) continue;
          // as A* does: a diagonal step may not cut the corner of an inflated obstacle
          if (dx != 0 && dy != 0 &&
              (!planner_.traversable(ws.global(lx + dx, ly)) || !planner_.traversable(ws.global(lx, ly + dy)))) {
            continue;
          }
          double cost = 0.0;
          if (hx != 0 || hy != 0) {
            const double dot = (dx * hx + dy * hy) / (std::hypot(dx, dy) * std::hypot(hx, hy));
            cost = std::acos(std::clamp(dot, -1.0, 1.0));
          }
          if (dx != 0 && dy != 0) cost += 1e-3;  // on a tie, the side step
          if (cost < best_cost) {
            best_cost = cost;
            best_dx = dx;
            best_dy = dy;
          }
        }
      }
      if (!std::isfinite(best_cost) || best_cost > 2.0) break;  // dead end or a turn back
      hx = best_dx;
      hy = best_dy;
      lx += best_dx;
      ly += best_dy;
    }
    if (chain.size() < 3) continue;  // specks: the touch-up visits them if they matter
    const CellIndex first = chain.front();
    const CellIndex last = chain.back();
    // closed when the last cell steps back onto the first as A* could (not across a corner)
    const bool closed = chain.size() > 4 && std::abs(first.x - last.x) <= 1 && std::abs(first.y - last.y) <= 1 &&
                        (first.x == last.x || first.y == last.y ||
                         (planner_.traversable({first.x, last.y}) && planner_.traversable({last.x, first.y})));
    pieces.push_back({chain, closed});
    cur = closed ? first : last;
  }
  return pieces;
}

void CoveragePlanner::append_piece(CoverageResult& r, CellIndex& cur, const RoundPiece& piece,
                                   std::optional<Point2D> start) {
  const CellIndex first = piece.cells.front();
  std::vector<Point2D> pts;
  for (const CellIndex& c : piece.cells) pts.push_back(grid_.cell_center(c));
  if (piece.closed) pts.push_back(grid_.cell_center(first));
  if (r.path.empty()) {
    if (start) {
      r.path.push_back(*start);
      if (cur.x >= 0 && grid_.contains(cur) && planner_.traversable(cur)) link(r.path, cur, first);
    }
  } else {
    link(r.path, cur, first);
  }
  std::size_t from = 0;
  if (!r.path.empty() && std::hypot(r.path.back().x_m - pts.front().x_m, r.path.back().y_m - pts.front().y_m) < 1e-9) {
    from = 1;
  }
  r.path.insert(r.path.end(), pts.begin() + static_cast<std::ptrdiff_t>(from), pts.end());
  cur = piece.closed ? first : piece.cells.back();
  ++r.passes;
}

CellIndex CoveragePlanner::start_cell(std::optional<Point2D> start) const noexcept {
  if (start) {
    if (const auto c = grid_.world_to_cell(*start)) return *c;
  }
  return {-1, -1};
}

CoverageResult CoveragePlanner::balloon(const Section& section, std::optional<Point2D> start) {
  CoverageResult r;
  Workspace ws = prepare(section);
  if (ws.stand_cells_global.empty()) {
    finish(r, ws, {0, 0});
    return r;
  }
  const double spacing = std::max(grid_.resolution_m(), options_.cleaning_width_m - options_.overlap_m);
  const std::size_t n = ws.offset.size();
  std::vector<std::uint8_t> in_round(n);
  CellIndex cur = start_cell(start);
  // The last, "ridge" round: where the offsets of both sides meet (the medial axis of the
  // section), a strip narrower than the spacing stays unswept; its outline is walked once.
  bool ridge = false;
  for (std::size_t k = 0;; ++k) {
    const float level = static_cast<float>(static_cast<double>(k) * spacing);
    if (!ridge) {
      for (std::size_t li = 0; li < n; ++li) in_round[li] = ws.stand[li] != 0 && ws.offset[li] >= level ? 1 : 0;
    } else {
      CleanedCells swept(grid_);
      swept.mark_path(r.path, options_.cleaning_width_m / 2.0);
      for (int ly = 0; ly < ws.h; ++ly) {
        for (int lx = 0; lx < ws.w; ++lx) {
          const std::size_t li = ws.local(lx, ly);
          in_round[li] = ws.stand[li] != 0 && !swept.cleaned(ws.global(lx, ly)) ? 1 : 0;
        }
      }
    }
    const auto pieces = round_pieces(ws, in_round, cur);
    if (!pieces) {
      if (ridge) break;
      ridge = true;
      continue;
    }
    for (const RoundPiece& piece : *pieces) append_piece(r, cur, piece, start);
    ++r.rounds;
    if (ridge) break;
  }
  finish(r, ws, cur);
  return r;
}

namespace {

// One run of a lane: the cells of a row (or column) of the window between its ends, inclusive.
struct LaneRun {
  int lane = 0;      // position in the list of lanes
  int lo = 0, hi = 0;  // along the lane, window cells
  CellIndex a, b;    // grid cells at lo and hi
  bool done = false;
};

}  // namespace

// The runs of `mask` along the given lanes (window rows when `rows`, else columns).
static std::vector<LaneRun> lane_runs(const std::vector<std::uint8_t>& mask, int w, int h, int x0, int y0, bool rows,
                                      const std::vector<int>& lanes) {
  std::vector<LaneRun> runs;
  const int along_extent = rows ? w : h;
  const auto at = [&](int lane, int a) {
    return rows ? mask[static_cast<std::size_t>(lane) * static_cast<std::size_t>(w) + static_cast<std::size_t>(a)] != 0
                : mask[static_cast<std::size_t>(a) * static_cast<std::size_t>(w) + static_cast<std::size_t>(lane)] != 0;
  };
  const auto cell = [&](int lane, int a) { return rows ? CellIndex{a + x0, lane + y0} : CellIndex{lane + x0, a + y0}; };
  for (std::size_t k = 0; k < lanes.size(); ++k) {
    const int l = lanes[k];
    int a = 0;
    while (a < along_extent) {
      if (!at(l, a)) {
        ++a;
        continue;
      }
      const int s = a;
      while (a < along_extent && at(l, a)) ++a;
      runs.push_back({static_cast<int>(k), s, a - 1, cell(l, s), cell(l, a - 1), false});
    }
  }
  return runs;
}

// The first and last lane of `mask` (window rows or columns holding a marked cell); lo > hi if none.
static std::pair<int, int> lane_extent(const std::vector<std::uint8_t>& mask, int w, int h, bool rows) {
  const int lanes_extent = rows ? h : w;
  int lo = lanes_extent, hi = -1;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (mask[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] == 0) continue;
      const int l = rows ? y : x;
      lo = std::min(lo, l);
      hi = std::max(hi, l);
    }
  }
  return {lo, hi};
}

static long long dist2(CellIndex a, CellIndex b) noexcept {
  return 1LL * (a.x - b.x) * (a.x - b.x) + 1LL * (a.y - b.y) * (a.y - b.y);
}

void CoveragePlanner::plough(Workspace& ws, const std::vector<std::uint8_t>& mask, bool rows,
                             const std::vector<RoundPiece>& pieces, CellIndex& cur, CoverageResult& r,
                             std::optional<Point2D> start, std::optional<Point2D> finish_near) {
  // The lanes lie where the offset leaves a lane spacing to the wall round (the first lane's
  // swath meets the round's); along a lane, its run goes on over `mask`, closer to the round.
  const double lane_spacing = std::max(grid_.resolution_m(), options_.cleaning_width_m - options_.lane_overlap_m);
  std::vector<std::uint8_t> far(mask.size());
  for (std::size_t li = 0; li < mask.size(); ++li) {
    far[li] = mask[li] != 0 && ws.offset[li] >= static_cast<float>(lane_spacing) ? 1 : 0;
  }
  const auto [lo, hi] = lane_extent(far, ws.w, ws.h, rows);
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
  std::vector<LaneRun> runs = lane_runs(mask, ws.w, ws.h, ws.x0, ws.y0, rows, lanes);
  // a run whose cells are all within the footprint radius of the round lies in its swath
  const auto beyond_round = static_cast<float>(options_.cleaning_width_m / 2.0);
  std::erase_if(runs, [&](const LaneRun& run) {
    for (int a = run.lo; a <= run.hi; ++a) {
      const int l = lanes[static_cast<std::size_t>(run.lane)];
      if (ws.offset[rows ? ws.local(a, l) : ws.local(l, a)] > beyond_round) return false;
    }
    return true;
  });
  // Cells of the boustrophedon decomposition: runs of neighbouring lanes that overlap one to one
  // are swept in one go, lane after lane; a split or a merge (an obstacle, a bay) ends a cell.
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
  // One greedy tour over the lane cells and the round's pieces: the nearest entry next (a lane
  // cell's four corners, an open piece's two ends, any cell of a closed piece), so the round
  // around an obstacle is walked when the lanes pass by it.
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
  // The closed pieces (rounds around obstacles inside the section) are left out of the tour and
  // inserted afterwards where it passes nearest (insert_round): the greedy tour would otherwise
  // jump to one as soon as it is the nearest thing and jump back, several metres each way.
  // The tour's items: the lane cells (entered at the first or the last run, that run swept one
  // way or the other: 4 ways) and the open pieces of the round (from either end: 2 ways).
  struct Way {
    CellIndex entry, exit;
    double inside_m = 0.0;  // travel within the item (lanes and the steps between them)
  };
  const double res = grid_.resolution_m();
  const auto metres = [&](CellIndex p, CellIndex q) { return std::sqrt(static_cast<double>(dist2(p, q))) * res; };
  const auto sweep_order = [&](std::size_t c, bool from_top, bool first_flipped, auto&& visit) {
    std::vector<std::size_t> order = cells[c];
    if (from_top) std::reverse(order.begin(), order.end());
    CellIndex at{-1, -1};
    for (std::size_t k = 0; k < order.size(); ++k) {
      const LaneRun& run = runs[order[k]];
      const bool flip = k == 0 ? first_flipped : dist2(at, run.b) < dist2(at, run.a);
      visit(flip ? run.b : run.a, flip ? run.a : run.b);
      at = flip ? run.a : run.b;
    }
  };
  std::vector<std::vector<Way>> ways;
  constexpr std::size_t kLaneCell = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> item_piece;  // the piece of an item; kLaneCell for a lane cell
  for (std::size_t c = 0; c < cells.size(); ++c) {
    ways.emplace_back();
    for (const int w : {0, 1, 2, 3}) {
      Way way;
      bool first = true;
      CellIndex at{};
      sweep_order(c, (w & 2) != 0, (w & 1) != 0, [&](CellIndex from, CellIndex to) {
        if (first) way.entry = from;
        else way.inside_m += metres(at, from);
        way.inside_m += metres(from, to);
        at = to;
        first = false;
      });
      way.exit = at;
      ways.back().push_back(way);
    }
    item_piece.push_back(kLaneCell);
  }
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    if (pieces[p].closed) continue;  // inserted afterwards (insert_round)
    const auto& pc = pieces[p].cells;
    const double len = static_cast<double>(pc.size()) * res;
    ways.push_back({Way{pc.front(), pc.back(), len}, Way{pc.back(), pc.front(), len}});
    item_piece.push_back(p);
  }
  const std::size_t items = ways.size();
  // The order: exact (Held-Karp over items and ways, straight-line links) for the few items of
  // a room-sized section, nearest-next beyond. With `finish_near`, the distance from the tour's
  // end to it counts too: the next section's path starts there.
  std::vector<std::pair<std::size_t, std::size_t>> tour;  // (item, way)
  const auto end_cost = [&](CellIndex exit) {
    return finish_near ? std::hypot(grid_.cell_center(exit).x_m - finish_near->x_m, grid_.cell_center(exit).y_m - finish_near->y_m)
                       : 0.0;
  };
  const CellIndex first_at = cur;
  const auto link_m = [&](CellIndex from, CellIndex to) { return from.x < 0 ? 0.0 : metres(from, to); };
  if (items > 0 && items <= kExactTourItems) {
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
  } else {
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
  }
  const std::size_t tour_begin = r.path.size();
  for (const auto& [item, way] : tour) {
    if (item_piece[item] != kLaneCell) {
      RoundPiece piece = pieces[item_piece[item]];
      if (way == 1) std::reverse(piece.cells.begin(), piece.cells.end());
      append_piece(r, cur, piece, start);
      continue;
    }
    sweep_order(item, (way & 2) != 0, (way & 1) != 0, [&](CellIndex from, CellIndex to) {
      go_to(from);
      go_to(to);
      ++r.passes;
    });
  }
  for (const RoundPiece& piece : pieces) {
    if (piece.closed) insert_round(r, cur, piece, tour_begin, start);
  }
}

void CoveragePlanner::join_pieces(std::vector<RoundPiece>& pieces) {
  // round_pieces breaks a chain where it would turn by more than a right angle, so the round
  // around a box comes as its four sides. Ends a few cells apart with a clear line between them
  // are one walk: sides joined at the corners, and a chain whose ends meet is closed.
  constexpr int kGap = 6;  // cells, Chebyshev: around the corner of a box, a quarter of a pillar
  std::vector<CellIndex> between;  // the cells that join two ends, when they are near
  const auto near = [&](CellIndex a, CellIndex b) {
    between.clear();
    if (std::abs(a.x - b.x) > kGap || std::abs(a.y - b.y) > kGap) return false;
    if (planner_.line_of_sight(a, b)) return true;
    return local_path(a, b, kGap, between);
  };
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i < pieces.size() && !merged; ++i) {
      if (pieces[i].closed) continue;
      for (std::size_t j = i + 1; j < pieces.size() && !merged; ++j) {
        if (pieces[j].closed) continue;
        auto& a = pieces[i].cells;
        auto b = pieces[j].cells;
        if (near(a.back(), b.back()) || near(a.front(), b.front())) std::reverse(b.begin(), b.end());
        if (near(a.back(), b.front())) {
          a.insert(a.end(), between.begin(), between.end());
          a.insert(a.end(), b.begin(), b.end());
        } else if (near(b.back(), a.front())) {
          b.insert(b.end(), between.begin(), between.end());
          b.insert(b.end(), a.begin(), a.end());
          a = std::move(b);
        } else {
          continue;
        }
        pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(j));
        merged = true;
      }
    }
  }
  for (RoundPiece& p : pieces) {
    if (!p.closed && p.cells.size() > std::size_t{2} * kGap && near(p.cells.back(), p.cells.front())) {
      p.cells.insert(p.cells.end(), between.begin(), between.end());
      p.closed = true;
    }
  }
}

bool CoveragePlanner::local_path(CellIndex a, CellIndex b, int margin, std::vector<CellIndex>& between) const {
  // Breadth-first over the traversable cells of the box around a and b (8-connected, a diagonal
  // never cutting a corner, as A* moves): the planner's A* would search the whole map before
  // failing for ends that a wall separates.
  const int x0 = std::min(a.x, b.x) - margin, y0 = std::min(a.y, b.y) - margin;
  const int w = std::abs(a.x - b.x) + 2 * margin + 1, h = std::abs(a.y - b.y) + 2 * margin + 1;
  const auto index = [&](CellIndex c) {
    return static_cast<std::size_t>(c.y - y0) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c.x - x0);
  };
  const auto open = [&](CellIndex c) {
    return c.x >= x0 && c.y >= y0 && c.x < x0 + w && c.y < y0 + h && grid_.contains(c) && planner_.traversable(c);
  };
  std::vector<int> from(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), -1);
  std::vector<CellIndex> queue{a};
  from[index(a)] = static_cast<int>(index(a));
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const CellIndex c = queue[q];
    if (c == b) break;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const CellIndex n{c.x + dx, c.y + dy};
        if ((dx == 0 && dy == 0) || !open(n) || from[index(n)] >= 0) continue;
        if (dx != 0 && dy != 0 && (!open({c.x + dx, c.y}) || !open({c.x, c.y + dy}))) continue;
        from[index(n)] = static_cast<int>(index(c));
        queue.push_back(n);
      }
    }
  }
  if (!open(b) || from[index(b)] < 0) return false;
  between.clear();
  for (std::size_t i = static_cast<std::size_t>(from[index(b)]); i != index(a); i = static_cast<std::size_t>(from[i])) {
    between.push_back({x0 + static_cast<int>(i) % w, y0 + static_cast<int>(i) / w});
  }
  std::reverse(between.begin(), between.end());
  return between.size() <= 2 * static_cast<std::size_t>(margin);
}

void CoveragePlanner::insert_round(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::size_t tour_begin,
                                   std::optional<Point2D> start) {
  // The cheapest place: a point S of a leg of the tour (a lane passing by, usually) from which
  // the round is entered at its nearest cell and left again at S: 2 |S c| of travel added. The
  // other choice is after the tour's end, |end c|, with no way back.
  const auto& path = r.path;
  std::vector<Point2D> centres;
  centres.reserve(piece.cells.size());
  for (const CellIndex& c : piece.cells) centres.push_back(grid_.cell_center(c));
  double best2 = std::numeric_limits<double>::infinity();  // |S c|^2
  std::size_t best_leg = 0, best_cell = 0;
  CellIndex split{};
  for (std::size_t k = tour_begin; k + 1 < path.size(); ++k) {
    const Point2D a = path[k], b = path[k + 1];
    const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m, len2 = dx * dx + dy * dy;
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const Point2D c = centres[i];
      const double t = len2 > 0.0 ? std::clamp(((c.x_m - a.x_m) * dx + (c.y_m - a.y_m) * dy) / len2, 0.0, 1.0) : 0.0;
      const Point2D s{a.x_m + t * dx, a.y_m + t * dy};
      const double d2 = (c.x_m - s.x_m) * (c.x_m - s.x_m) + (c.y_m - s.y_m) * (c.y_m - s.y_m);
      if (d2 >= best2) continue;
      // S on a cell centre of the leg (legs of lanes run along cell rows or columns)
      const CellIndex sc = grid_.cell_at(s);
      if (!grid_.contains(sc) || !planner_.traversable(sc)) continue;
      // snapped to a cell centre, S may leave the leg: both halves must stay in plain sight
      if (!planner_.line_of_sight(grid_.cell_at(a), sc) || !planner_.line_of_sight(sc, grid_.cell_at(b))) continue;
      best2 = d2, best_leg = k, best_cell = i, split = sc;
    }
  }
  if (path.size() > tour_begin) {
    const Point2D end = path.back();
    for (const Point2D c : centres) {
      // after the end: |end c| against 2 |S c| there and back
      if ((c.x_m - end.x_m) * (c.x_m - end.x_m) + (c.y_m - end.y_m) * (c.y_m - end.y_m) < 4.0 * best2) {
        return append_from(r, cur, piece, start);
      }
    }
  }
  if (!std::isfinite(best2)) return append_from(r, cur, piece, start);
  const CellIndex entry = piece.cells[best_cell];
  std::vector<Point2D> detour;
  detour.push_back(grid_.cell_center(split));
  link(detour, split, entry);
  for (std::size_t j = 1; j <= piece.cells.size(); ++j) {
    detour.push_back(grid_.cell_center(piece.cells[(best_cell + j) % piece.cells.size()]));
  }
  link(detour, entry, split);
  // S itself is on the leg; it is not repeated where it coincides with the leg's ends
  const auto same = [](Point2D p, Point2D q) { return std::hypot(p.x_m - q.x_m, p.y_m - q.y_m) < 1e-9; };
  if (same(detour.back(), path[best_leg + 1])) detour.pop_back();
  if (same(detour.front(), path[best_leg])) detour.erase(detour.begin());
  r.path.insert(r.path.begin() + static_cast<std::ptrdiff_t>(best_leg + 1), detour.begin(), detour.end());
  ++r.passes;
}

void CoveragePlanner::append_from(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::optional<Point2D> start) {
  // a closed piece entered at its cell nearest to the robot
  std::size_t entry = 0;
  long long best = std::numeric_limits<long long>::max();
  for (std::size_t k = 0; k < piece.cells.size(); ++k) {
    const long long d = cur.x < 0 ? 0 : dist2(cur, piece.cells[k]);
    if (d < best) best = d, entry = k;
  }
  RoundPiece rotated = piece;
  std::rotate(rotated.cells.begin(), rotated.cells.begin() + static_cast<std::ptrdiff_t>(entry), rotated.cells.end());
  append_piece(r, cur, rotated, start);
}

CoverageResult CoveragePlanner::hybrid(const Section& section, std::optional<Point2D> start,
                                       std::optional<Point2D> finish_near) {
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
  for (const bool rows : {true, false}) {
    Workspace w = ws;
    CoverageResult res;
    CellIndex cur = start_cell(start);
    auto pieces = round_pieces(w, wall, cur);
    if (pieces) {
      res.rounds = 1;
      join_pieces(*pieces);
    }
    plough(w, inner, rows, pieces ? *pieces : std::vector<RoundPiece>{}, cur, res, start, finish_near);
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
  const auto [lo, hi] = lane_extent(ws.stand, ws.w, ws.h, rows);
  std::vector<int> lanes;
  for (int l = lo; l <= hi; l += step) lanes.push_back(l);
  if (!lanes.empty() && lanes.back() != hi) lanes.push_back(hi);
  std::vector<LaneRun> iv = lane_runs(ws.stand, ws.w, ws.h, ws.x0, ws.y0, rows, lanes);
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
    if (r.path.empty()) r.path.push_back(grid_.cell_center(from));
    else link(r.path, cur, from);
    if (!(from == to)) r.path.push_back(grid_.cell_center(to));
    cur = to;
    ++r.passes;
  }
  finish(r, ws, cur);
  return r;
}

}  // namespace tripodal::navi
