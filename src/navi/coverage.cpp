#include "tripodal/navi/coverage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "coverage_internal.hpp"
#include "tripodal/navi/distance_field.hpp"

namespace tripodal::navi {

using coverage_detail::dist2;

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
  if (!keep_linked_stand(ws)) return ws;
  const auto cell_of_local = [&](std::size_t li) {
    return ws.global(static_cast<int>(li % static_cast<std::size_t>(ws.w)),
                     static_cast<int>(li / static_cast<std::size_t>(ws.w)));
  };
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

bool CoveragePlanner::keep_linked_stand(Workspace& ws) {
  const std::size_t n = ws.stand.size();
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
  if (comps.empty()) return false;
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
  return true;
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
    touch_up(r, ws, cur);
    // the forced marks of the touch-up are not cleaning: recount from the path itself
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

void CoveragePlanner::touch_up(CoverageResult& r, Workspace& ws, CellIndex cur) {
  const double half = options_.cleaning_width_m / 2.0;
  std::vector<std::size_t> todo;
  for (const std::size_t i : ws.reachable) {
    if (!ws.cleaned.cleaned(i)) todo.push_back(i);
  }
  std::vector<std::uint8_t> left(ws.offset.size(), 0);  // reachable cells, window-local
  for (const std::size_t i : ws.reachable) {
    const CellIndex c = grid_.cell(i);
    left[ws.local(c.x - ws.x0, c.y - ws.y0)] = 1;
  }
  while (!todo.empty()) {
    // nearest uncleaned cell
    std::size_t best = 0;
    long long best_d = std::numeric_limits<long long>::max();
    for (std::size_t k = 0; k < todo.size(); ++k) {
      const long long d = dist2(grid_.cell(todo[k]), cur);
      if (d < best_d) {
        best_d = d;
        best = k;
      }
    }
    const CellIndex u = grid_.cell(todo[best]);
    const std::size_t before = r.path.size();
    if (const std::optional<CellIndex> target = touch_up_target(ws, left, u, cur)) {
      ++r.touch_ups;
      if (const auto inserted = insert_visit(r.path, *target)) {
        for (std::size_t k = inserted->first == 0 ? 0 : inserted->first - 1; k < inserted->second && k + 1 < r.path.size(); ++k) {
          ws.cleaned.mark_segment(r.path[k], r.path[k + 1], half);
        }
      } else {
        if (r.path.empty()) r.path.push_back(grid_.cell_center(*target));
        link(r.path, cur, *target);
        cur = *target;
        for (std::size_t k = before == 0 ? 0 : before - 1; k + 1 < r.path.size(); ++k) {
          ws.cleaned.mark_segment(r.path[k], r.path[k + 1], half);
        }
      }
      ws.cleaned.mark_disc(grid_.cell_center(*target), half);
    }
    ws.cleaned.mark_disc(grid_.cell_center(u), 0.0);  // never pick u again, even if unreachable
    std::erase_if(todo, [&](std::size_t i) { return ws.cleaned.cleaned(i); });
  }
}

std::optional<CellIndex> CoveragePlanner::touch_up_target(const Workspace& ws, const std::vector<std::uint8_t>& left, CellIndex u,
                                                          CellIndex cur) const {
  // A standing cell whose footprint covers u and the most cells still left around it (the
  // nearest to the robot among equals): the cell nearest to the robot alone covered u at the
  // footprint's edge and little else, so the wedges along a slanted wall took a visit each.
  const double half = options_.cleaning_width_m / 2.0;
  const int reach = static_cast<int>(std::ceil(half / grid_.resolution_m()));
  const double r2 = (half / grid_.resolution_m()) * (half / grid_.resolution_m()) + 1e-9;
  const auto gain = [&](CellIndex t) {
    std::size_t g = 0;
    for (int ey = -reach; ey <= reach; ++ey) {
      for (int ex = -reach; ex <= reach; ++ex) {
        if (ex * ex + ey * ey > r2) continue;
        const int lx = t.x + ex - ws.x0, ly = t.y + ey - ws.y0;
        if (!ws.inside(lx, ly) || left[ws.local(lx, ly)] == 0) continue;
        g += ws.cleaned.cleaned(grid_.index({t.x + ex, t.y + ey})) ? 0 : 1;
      }
    }
    return g;
  };
  std::optional<CellIndex> target;
  long long target_d = std::numeric_limits<long long>::max();
  std::size_t target_gain = 0;
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      if (dx * dx + dy * dy > r2) continue;
      const int lx = u.x + dx - ws.x0, ly = u.y + dy - ws.y0;
      if (!ws.inside(lx, ly) || ws.stand[ws.local(lx, ly)] == 0) continue;
      const CellIndex t{u.x + dx, u.y + dy};
      const long long d = dist2(t, cur);
      const std::size_t g = gain(t);
      if (g > target_gain || (g == target_gain && d < target_d)) {
        target_gain = g;
        target_d = d;
        target = t;
      }
    }
  }
  return target;
}

std::optional<std::pair<std::size_t, std::size_t>> CoveragePlanner::insert_visit(std::vector<Point2D>& path, CellIndex target) {
  // The point S of a leg nearest to the target, from where it is in plain sight: the visit goes
  // S -> target -> S there (2 |S t| + turn_cost_m), unless going on from the path's end (|end t|)
  // is cheaper.
  if (path.size() < 2) return std::nullopt;
  const Point2D t = grid_.cell_center(target);
  const auto d2 = [](Point2D p, Point2D q) { return (p.x_m - q.x_m) * (p.x_m - q.x_m) + (p.y_m - q.y_m) * (p.y_m - q.y_m); };
  // a visit from a leg turns twice more than one from the end: weighed as turn_cost_m of travel
  const double via_end_m = std::sqrt(d2(path.back(), t)) - options_.turn_cost_m;
  if (via_end_m <= 0.0) return std::nullopt;
  double best2 = via_end_m * via_end_m / 4.0;
  std::size_t best_leg = path.size();
  Point2D split{};
  for (std::size_t k = 0; k + 1 < path.size(); ++k) {
    const Point2D a = path[k], b = path[k + 1];
    const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m, len2 = dx * dx + dy * dy;
    const double u = len2 > 0.0 ? std::clamp(((t.x_m - a.x_m) * dx + (t.y_m - a.y_m) * dy) / len2, 0.0, 1.0) : 0.0;
    const Point2D p{a.x_m + u * dx, a.y_m + u * dy};
    if (d2(p, t) >= best2) continue;
    const CellIndex sc = grid_.cell_at(p);
    if (!grid_.contains(sc) || !planner_.traversable(sc)) continue;
    const double keep = planner_.leg_clearance_m(sc, target);
    if (!planner_.line_of_sight(sc, target, keep)) continue;
    // the halves of the leg, cell to cell, in plain sight as every leg is
    if (!planner_.line_of_sight(grid_.cell_at(a), sc) || !planner_.line_of_sight(sc, grid_.cell_at(b))) continue;
    best2 = d2(p, t), best_leg = k, split = p;
  }
  if (best_leg == path.size()) return std::nullopt;
  // S itself, not its cell's centre: the leg keeps its swath (the cells it cleaned stay cleaned)
  std::vector<Point2D> detour{split, t, split};
  const auto same = [](Point2D p, Point2D q) { return std::hypot(p.x_m - q.x_m, p.y_m - q.y_m) < 1e-9; };
  if (same(detour.back(), path[best_leg + 1])) detour.pop_back();
  if (same(detour.front(), path[best_leg])) detour.erase(detour.begin());
  const std::size_t at = best_leg + 1;
  path.insert(path.begin() + static_cast<std::ptrdiff_t>(at), detour.begin(), detour.end());
  return std::pair{at, at + detour.size()};
}

CellIndex CoveragePlanner::start_cell(std::optional<Point2D> start) const noexcept {
  if (start) {
    if (const auto c = grid_.world_to_cell(*start)) return *c;
  }
  return {-1, -1};
}

}  // namespace tripodal::navi
