#include "tripodal/navi/distance_transform_coverage.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>

#include "tripodal/navi/distance_field.hpp"

namespace tripodal::navi {

namespace {

constexpr std::array<std::array<int, 2>, 8> kSteps = {{{1, 0}, {0, 1}, {-1, 0}, {0, -1}, {1, 1}, {-1, 1}, {-1, -1}, {1, -1}}};
constexpr int kNone = -1;

// The tool-sized cells: each has the standable fine cell nearest its centre as its waypoint.
struct Coarse {
  int w = 0;
  int h = 0;
  int k = 1;                          // fine cells per side
  std::vector<std::size_t> waypoint;  // fine index, or kNoWaypoint where the robot cannot stand
  // The index of coarse cell (x, y) (both within the grid).
  [[nodiscard]] std::size_t at(int x, int y) const noexcept {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
  }
  [[nodiscard]] bool free(int x, int y) const noexcept {
    return x >= 0 && y >= 0 && x < w && y < h && waypoint[at(x, y)] != kNoWaypoint;
  }
  static constexpr std::size_t kNoWaypoint = std::numeric_limits<std::size_t>::max();
};

// Breadth-first distances (8-connected) over the free coarse cells from `from`.
std::vector<int> wave(const Coarse& c, int from) {
  std::vector<int> d(c.waypoint.size(), kNone);
  std::deque<int> q{from};
  d[static_cast<std::size_t>(from)] = 0;
  while (!q.empty()) {
    const int i = q.front();
    q.pop_front();
    for (const auto& s : kSteps) {
      const int x = i % c.w + s[0], y = i / c.w + s[1];
      if (!c.free(x, y) || d[c.at(x, y)] != kNone) continue;
      d[c.at(x, y)] = d[static_cast<std::size_t>(i)] + 1;
      q.push_back(y * c.w + x);
    }
  }
  return d;
}

// The shortest way (8-connected, over free coarse cells) from `from` to the nearest cell not yet
// visited, excluding `from`; empty when none is left.
std::vector<int> way_to_unvisited(const Coarse& c, int from, const std::vector<std::uint8_t>& visited) {
  std::vector<int> parent(c.waypoint.size(), kNone - 1);
  std::deque<int> q{from};
  parent[static_cast<std::size_t>(from)] = kNone;
  while (!q.empty()) {
    const int i = q.front();
    q.pop_front();
    if (i != from && visited[static_cast<std::size_t>(i)] == 0) {
      std::vector<int> way;
      for (int at = i; at != from; at = parent[static_cast<std::size_t>(at)]) way.push_back(at);
      std::reverse(way.begin(), way.end());
      return way;
    }
    for (const auto& s : kSteps) {
      const int x = i % c.w + s[0], y = i / c.w + s[1];
      if (!c.free(x, y) || parent[c.at(x, y)] != kNone - 1) continue;
      parent[c.at(x, y)] = i;
      q.push_back(y * c.w + x);
    }
  }
  return {};
}

}  // namespace

CoverageResult distance_transform_coverage(const OccupancyGrid& grid, const Section& section, const CoverageOptions& o,
                                           std::optional<Point2D> start, std::optional<Point2D> goal) {
  CoverageResult r;
  r.section_cells = section.cells.size();
  if (section.cells.empty()) return r;
  const double res = grid.resolution_m();
  const double half = o.cleaning_width_m / 2.0;
  const double body = o.robot_radius_m > 0.0 ? o.robot_radius_m : half;

  // Where the robot may stand: inside the section, half the tool from its boundary and the body's
  // radius from anything physical (as CoveragePlanner has it).
  // Computed in a window around the section (its extent and a margin beyond the body and the
  // tool): a floor's rooms each cost their own size, not the floor's.
  const int margin = static_cast<int>(std::ceil(std::max(body, half) / res)) + 2;
  const int wx0 = std::max(0, section.min.x - margin), wy0 = std::max(0, section.min.y - margin);
  const int wx1 = std::min(grid.width() - 1, section.max.x + margin), wy1 = std::min(grid.height() - 1, section.max.y + margin);
  const int ww = wx1 - wx0 + 1, wh = wy1 - wy0 + 1;
  const auto local = [&](std::size_t i) {
    const CellIndex c = grid.cell(i);
    return static_cast<std::size_t>(c.y - wy0) * static_cast<std::size_t>(ww) + static_cast<std::size_t>(c.x - wx0);
  };
  std::vector<bool> outside(static_cast<std::size_t>(ww) * static_cast<std::size_t>(wh), true);
  for (const std::size_t i : section.cells) outside[local(i)] = false;
  std::vector<bool> physical(outside.size(), false);
  for (int y = wy0; y <= wy1; ++y) {
    for (int x = wx0; x <= wx1; ++x)
      physical[static_cast<std::size_t>(y - wy0) * static_cast<std::size_t>(ww) + static_cast<std::size_t>(x - wx0)] =
          !grid.is_free({x, y});
  }
  const DistanceField to_boundary(ww, wh, res, outside);
  const DistanceField to_obstacle(ww, wh, res, physical);
  std::vector<bool> standable(grid.size(), false);
  for (const std::size_t i : section.cells) {
    standable[i] = to_boundary.clearance_m(local(i)) >= half - 1e-9 && to_obstacle.clearance_m(local(i)) >= body - 1e-9;
  }

  // The tool-sized cells over the section's extent.
  Coarse c;
  c.k = std::max(1, static_cast<int>(std::floor((o.cleaning_width_m - o.overlap_m) / res)));
  const int x0 = section.min.x, y0 = section.min.y;
  c.w = (section.max.x - x0) / c.k + 1;
  c.h = (section.max.y - y0) / c.k + 1;
  c.waypoint.assign(static_cast<std::size_t>(c.w) * static_cast<std::size_t>(c.h), Coarse::kNoWaypoint);
  for (int cy = 0; cy < c.h; ++cy) {
    for (int cx = 0; cx < c.w; ++cx) {
      const double mx = x0 + cx * c.k + (c.k - 1) / 2.0, my = y0 + cy * c.k + (c.k - 1) / 2.0;
      double best = std::numeric_limits<double>::infinity();
      for (int y = y0 + cy * c.k; y < y0 + (cy + 1) * c.k; ++y) {
        for (int x = x0 + cx * c.k; x < x0 + (cx + 1) * c.k; ++x) {
          if (!grid.contains({x, y}) || !standable[grid.index({x, y})]) continue;
          const double d = std::hypot(x - mx, y - my);
          if (d < best) {
            best = d;
            c.waypoint[c.at(cx, cy)] = grid.index({x, y});
          }
        }
      }
    }
  }
  const auto coarse_of = [&](std::optional<Point2D> p) {
    // The free coarse cell whose waypoint is nearest p (the section's first standable one without p).
    int best = kNone;
    double best_d = std::numeric_limits<double>::infinity();
    for (int i = 0; i < c.w * c.h; ++i) {
      const std::size_t f = c.waypoint[static_cast<std::size_t>(i)];
      if (f == Coarse::kNoWaypoint) continue;
      if (!p) return i;
      const Point2D q = grid.cell_center(grid.cell(f));
      const double d = std::hypot(q.x_m - p->x_m, q.y_m - p->y_m);
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    return best;
  };
  const int from = coarse_of(start);
  if (from == kNone) return r;
  const int to = goal ? coarse_of(goal) : from;

  // Zelinsky's rule: step to the unvisited neighbour farthest from the goal (ties: keep the
  // heading); with none, go the shortest way to the nearest unvisited cell.
  const std::vector<int> dist = wave(c, to);
  std::vector<std::uint8_t> visited(c.waypoint.size(), 0);
  std::vector<int> route{from};
  visited[static_cast<std::size_t>(from)] = 1;
  std::array<int, 2> heading{0, 0};
  int at = from;
  for (;;) {
    int next = kNone;
    int next_d = -1;
    bool next_straight = false;
    for (const auto& s : kSteps) {
      const int x = at % c.w + s[0], y = at / c.w + s[1];
      if (!c.free(x, y)) continue;
      const int i = y * c.w + x;
      if (visited[static_cast<std::size_t>(i)] != 0 || dist[static_cast<std::size_t>(i)] == kNone) continue;
      const int d = dist[static_cast<std::size_t>(i)];
      const bool straight = s[0] == heading[0] && s[1] == heading[1];
      if (d > next_d || (d == next_d && straight && !next_straight)) {
        next = i;
        next_d = d;
        next_straight = straight;
      }
    }
    if (next != kNone) {
      heading = {next % c.w - at % c.w, next / c.w - at / c.w};
      visited[static_cast<std::size_t>(next)] = 1;
      route.push_back(next);
      at = next;
      continue;
    }
    const std::vector<int> way = way_to_unvisited(c, at, visited);
    if (way.empty()) break;
    for (const int i : way) {
      visited[static_cast<std::size_t>(i)] = 1;
      route.push_back(i);
    }
    heading = {0, 0};
    at = way.back();
  }
  // Back to the goal, the shortest way.
  if (at != to) {
    std::vector<std::uint8_t> only_goal(c.waypoint.size(), 1);
    only_goal[static_cast<std::size_t>(to)] = 0;
    for (const int i : way_to_unvisited(c, at, only_goal)) route.push_back(i);
  }

  for (const int i : route) r.path.push_back(grid.cell_center(grid.cell(c.waypoint[static_cast<std::size_t>(i)])));
  r.passes = 1;
  r.stats = path_stats(r.path, o.turn_threshold_rad);

  // Reachable: section cells within half the tool of a standable cell; covered: of those, the
  // ones the footprint sweeps along the path.
  std::vector<bool> stand(outside.size(), false);
  for (const std::size_t i : section.cells) stand[local(i)] = standable[i];
  const DistanceField to_stand(ww, wh, res, stand, false);
  CleanedCells cleaned(grid);
  cleaned.mark_path(r.path, half);
  for (const std::size_t i : section.cells) {
    if (to_stand.distance_m(local(i)) > half + 1e-9) continue;
    ++r.reachable_cells;
    if (cleaned.cleaned(i)) ++r.covered_cells;
  }
  return r;
}

}  // namespace tripodal::navi
