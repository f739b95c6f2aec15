#include "tripodal/navi/path_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>

namespace tripodal::navi {

const char* to_string(PlanStatus s) noexcept {
  switch (s) {
    case PlanStatus::ok: return "ok";
    case PlanStatus::start_outside_map: return "start outside the map";
    case PlanStatus::goal_outside_map: return "goal outside the map";
    case PlanStatus::start_in_collision: return "start in collision";
    case PlanStatus::goal_in_collision: return "goal in collision";
    case PlanStatus::unreachable: return "goal unreachable";
  }
  return "?";
}

double polyline_length_m(const std::vector<Point2D>& points) noexcept {
  double len = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    len += std::hypot(points[i].x_m - points[i - 1].x_m, points[i].y_m - points[i - 1].y_m);
  }
  return len;
}

PathPlanner::PathPlanner(const OccupancyGrid& grid, PathPlannerOptions options)
    : grid_(grid), options_(options), field_(grid, options.unknown_is_obstacle) {
  traversable_.resize(grid_.size());
  for (std::size_t i = 0; i < grid_.size(); ++i) {
    traversable_[i] = field_.distance_m(i) > 0.0 && field_.clearance_m(i) >= options_.robot_radius_m ? 1 : 0;
  }
  padded_width_ = grid_.width() + 2;
  const std::size_t padded = static_cast<std::size_t>(padded_width_) * static_cast<std::size_t>(grid_.height() + 2);
  open_cell_.assign(padded, 0);
  for (int y = 0; y < grid_.height(); ++y) {
    for (int x = 0; x < grid_.width(); ++x) {
      open_cell_[padded_index(x, y)] = traversable_[grid_.index({x, y})];
    }
  }
  clearance_.assign(padded, 0.0F);
  for (int y = 0; y < grid_.height(); ++y) {
    for (int x = 0; x < grid_.width(); ++x) {
      clearance_[padded_index(x, y)] = static_cast<float>(field_.clearance_m(grid_.index({x, y})));
    }
  }
  g_.resize(padded);
  parent_.resize(padded);
  stamp_.assign(padded, 0);
  closed_.resize(padded);
}

double PathPlanner::leg_clearance_m(CellIndex a, CellIndex b) const noexcept {
  if (options_.preferred_clearance_m <= options_.robot_radius_m) return 0.0;
  return std::min({options_.preferred_clearance_m, clearance_m(a), clearance_m(b)});
}

bool PathPlanner::line_of_sight(CellIndex a, CellIndex b, double min_clearance_m) const noexcept {
  // Supercover walk: every cell the segment between the two centres passes through.
  int x = a.x, y = a.y;
  const int dx = std::abs(b.x - a.x), dy = std::abs(b.y - a.y);
  const int sx = b.x > a.x ? 1 : -1, sy = b.y > a.y ? 1 : -1;
  const auto open = [&](CellIndex c) {
    return traversable(c) && (min_clearance_m <= 0.0 || field_.clearance_m(grid_.index(c)) >= min_clearance_m);
  };
  if (!open({x, y})) return false;
  int ix = 0, iy = 0;
  while (ix < dx || iy < dy) {
    // compare (0.5 + ix) / dx with (0.5 + iy) / dy without division
    const long long lhs = static_cast<long long>(1 + 2 * ix) * dy;
    const long long rhs = static_cast<long long>(1 + 2 * iy) * dx;
    if (lhs == rhs) {  // through a corner: both side cells must be free
      if (!open({x + sx, y}) || !open({x, y + sy})) return false;
      x += sx;
      y += sy;
      ++ix;
      ++iy;
    } else if (lhs < rhs) {
      x += sx;
      ++ix;
    } else {
      y += sy;
      ++iy;
    }
    if (!open({x, y})) return false;
  }
  return true;
}

PlannedPath PathPlanner::plan(Point2D start, Point2D goal) {
  PlannedPath out;
  const auto s = grid_.world_to_cell(start);
  const auto g = grid_.world_to_cell(goal);
  std::ostringstream msg;
  if (!s) {
    out.status = PlanStatus::start_outside_map;
    msg << "start (" << start.x_m << ", " << start.y_m << ") m is outside the map";
    out.message = msg.str();
    return out;
  }
  if (!g) {
    out.status = PlanStatus::goal_outside_map;
    msg << "goal (" << goal.x_m << ", " << goal.y_m << ") m is outside the map";
    out.message = msg.str();
    return out;
  }
  const std::optional<CellIndex> out_of_margin = traversable(*s) ? std::nullopt : way_out(*s);
  out = plan(out_of_margin.value_or(*s), *g);
  if (out.ok()) {
    // Keep the exact end points rather than the cell centres; a start inside the margin first
    // goes straight to the cell the search started from.
    if (out_of_margin) {
      out.cells.insert(out.cells.begin(), *s);
      out.waypoints.insert(out.waypoints.begin(), start);
      if (out.waypoints.size() == 2) out.waypoints.push_back(goal);  // the way out was the whole way
    } else {
      out.waypoints.front() = start;
    }
    out.waypoints.back() = goal;
    out.length_m = polyline_length_m(out.waypoints);
  }
  return out;
}

std::optional<CellIndex> PathPlanner::way_out(CellIndex start) const {
  if (!grid_.contains(start)) return std::nullopt;
  const double here = clearance_m(start);
  if (field_.distance_m(grid_.index(start)) <= 0.0 || here < options_.robot_radius_m - options_.start_tolerance_m) {
    return std::nullopt;
  }
  const double res = grid_.resolution_m();
  const int reach = static_cast<int>(std::ceil(options_.start_tolerance_m / res)) + 1;
  const Point2D from = grid_.cell_center(start);
  // Straight from the start cell to c, every cell passed at least as clear as the start's.
  const auto outward = [&](CellIndex c) {
    const Point2D to = grid_.cell_center(c);
    const double len = std::hypot(to.x_m - from.x_m, to.y_m - from.y_m);
    const int steps = std::max(1, static_cast<int>(std::ceil(len / (0.25 * res))));
    for (int k = 1; k < steps; ++k) {
      const double t = static_cast<double>(k) / steps;
      const auto cell = grid_.world_to_cell({from.x_m + t * (to.x_m - from.x_m), from.y_m + t * (to.y_m - from.y_m)});
      if (!cell || clearance_m(*cell) < here) return false;
    }
    return true;
  };
  std::optional<CellIndex> best;
  int best_d2 = std::numeric_limits<int>::max();
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      const CellIndex c{start.x + dx, start.y + dy};
      const int d2 = dx * dx + dy * dy;
      if (d2 >= best_d2 || !traversable(c) || !outward(c)) continue;
      best = c;
      best_d2 = d2;
    }
  }
  return best;
}

PlannedPath PathPlanner::plan_around(Point2D start, Point2D goal, std::span<const Point2D> obstacles, double margin_m) {
  // Close the cells around the points in traversable_ and in A*'s padded copy, plan, then
  // reopen exactly the cells this call closed (also when planning throws).
  struct Closed {
    PathPlanner& planner;
    std::vector<std::size_t> cells;  // grid indices
    ~Closed() {
      for (const std::size_t i : cells) {
        planner.traversable_[i] = 1;
        const CellIndex c = planner.grid_.cell(i);
        planner.open_cell_[planner.padded_index(c.x, c.y)] = 1;
      }
    }
  } closed{*this, {}};
  const std::optional<CellIndex> start_cell = grid_.world_to_cell(start);
  const double r = options_.robot_radius_m;
  const double outer = r + std::max(0.0, margin_m);
  const double near_start = 2.0 * std::max(0.0, margin_m) + grid_.resolution_m();
  const int reach = static_cast<int>(std::ceil(outer / grid_.resolution_m())) + 1;
  for (const Point2D& p : obstacles) {
    const std::optional<CellIndex> pc = grid_.world_to_cell(p);
    if (!pc) continue;
    for (int y = pc->y - reach; y <= pc->y + reach; ++y) {
      for (int x = pc->x - reach; x <= pc->x + reach; ++x) {
        const CellIndex c{x, y};
        if (!grid_.contains(c) || (start_cell && c == *start_cell)) continue;
        const std::size_t i = grid_.index(c);
        if (traversable_[i] == 0) continue;
        const Point2D cc = grid_.cell_center(c);
        const double d = std::hypot(cc.x_m - p.x_m, cc.y_m - p.y_m);
        if (d > outer) continue;
        if (d > r && std::hypot(cc.x_m - start.x_m, cc.y_m - start.y_m) < near_start) continue;
        traversable_[i] = 0;
        open_cell_[padded_index(x, y)] = 0;
        closed.cells.push_back(i);
      }
    }
  }
  // A detour starts where a safety stop or the laser held the robot: the way out of the margin
  // (plan(Point2D, Point2D)) knows nothing of the points just closed, so it is not taken here.
  const std::optional<CellIndex> goal_cell = grid_.world_to_cell(goal);
  if (!start_cell || !goal_cell) return plan(start, goal);  // the outside-the-map messages
  PlannedPath out = plan(*start_cell, *goal_cell);
  if (out.ok()) {
    out.waypoints.front() = start;
    out.waypoints.back() = goal;
    out.length_m = polyline_length_m(out.waypoints);
  }
  return out;
}

namespace {

constexpr float kSqrt2 = 1.41421356F;
// Scaling h by (1 + 1/1000) breaks the ties among the many equal-cost grid paths in favour of
// progress; a path found is at most 0.1 % longer than the shortest (in practice equal).
constexpr float kTieBreak = 1.001F;

// The octile distance from padded cell p to `goal`, tie-broken: A*'s heuristic.
float octile(std::uint32_t p, int padded_width, CellIndex goal) noexcept {
  const int x = static_cast<int>(p % static_cast<std::uint32_t>(padded_width)) - 1;
  const int y = static_cast<int>(p / static_cast<std::uint32_t>(padded_width)) - 1;
  const float dx = static_cast<float>(std::abs(x - goal.x));
  const float dy = static_cast<float>(std::abs(y - goal.y));
  return kTieBreak * ((dx > dy) ? dx + (kSqrt2 - 1.0F) * dy : dy + (kSqrt2 - 1.0F) * dx);
}

struct Node {
  float f;
  float h;
  std::uint32_t i;
};

// Why no path can be planned between `start` and `goal` (outside the grid, in collision), in
// out.status and out.message; false when one can.
bool refuse_ends(const PathPlanner& planner, CellIndex start, CellIndex goal, PlannedPath& out) {
  const OccupancyGrid& grid = planner.grid();
  std::ostringstream msg;
  const auto describe = [&](const char* what, CellIndex c) {
    msg << what << " cell (" << c.x << ", " << c.y << ")";
    if (grid.contains(c)) {
      msg << " has clearance " << planner.distance_field().clearance_m(grid.index(c)) << " m, the robot radius is "
          << planner.options().robot_radius_m << " m";
    } else {
      msg << " is outside the " << grid.width() << " x " << grid.height() << " grid";
    }
  };
  if (!grid.contains(start)) {
    out.status = PlanStatus::start_outside_map;
    describe("start", start);
  } else if (!grid.contains(goal)) {
    out.status = PlanStatus::goal_outside_map;
    describe("goal", goal);
  } else if (!planner.traversable(start)) {
    out.status = PlanStatus::start_in_collision;
    describe("start", start);
  } else if (!planner.traversable(goal)) {
    out.status = PlanStatus::goal_in_collision;
    describe("goal", goal);
  }
  out.message = msg.str();
  return !out.message.empty();
}

std::string unreachable_message(CellIndex start, CellIndex goal, double robot_radius_m, std::size_t expanded) {
  std::ostringstream msg;
  msg << "no collision-free path from cell (" << start.x << ", " << start.y << ") to cell (" << goal.x << ", " << goal.y
      << ") for a robot of radius " << robot_radius_m << " m (" << expanded << " cells reachable)";
  return msg.str();
}

// The path's cells, start to goal, read back from the goal through A*'s parents (padded indices).
std::vector<CellIndex> trace_back(const std::vector<std::uint32_t>& parent, int padded_width, std::uint32_t si,
                                  std::uint32_t gi) {
  const auto pw = static_cast<std::uint32_t>(padded_width);
  std::vector<CellIndex> cells;
  for (std::uint32_t i = gi;; i = parent[i]) {
    cells.push_back({static_cast<int>(i % pw) - 1, static_cast<int>(i / pw) - 1});
    if (i == si) break;
  }
  std::reverse(cells.begin(), cells.end());
  return cells;
}

double cells_length(const std::vector<CellIndex>& k) {
  double len = 0.0;
  for (std::size_t i = 1; i < k.size(); ++i) len += std::hypot(k[i].x - k[i - 1].x, k[i].y - k[i - 1].y);
  return len;
}

// String pulling: extend each straight leg while the next path cell stays visible. Done from
// both ends, the shorter result kept: the greedy pull depends on its direction. With a
// clearance to keep a leg keeps it, or at least the least clearance of the cells it
// replaces: a shortcut does not undo the way A* took around a corner.
std::vector<CellIndex> pull_string(const PathPlanner& planner, const std::vector<CellIndex>& cells, double keep_clearance_m) {
  const bool keep_clear = keep_clearance_m > planner.options().robot_radius_m;
  const auto pull = [&](const std::vector<CellIndex>& path) {
    std::vector<CellIndex> k{path[0]};
    std::size_t i = 0;
    while (i + 1 < path.size()) {
      std::size_t j = i + 1;
      double least = keep_clear ? std::min({keep_clearance_m, planner.clearance_m(path[i]), planner.clearance_m(path[j])}) : 0.0;
      while (j + 1 < path.size()) {
        const double with_next = keep_clear ? std::min(least, planner.clearance_m(path[j + 1])) : 0.0;
        if (!planner.line_of_sight(path[i], path[j + 1], with_next)) break;
        least = with_next;
        ++j;
      }
      k.push_back(path[j]);
      i = j;
    }
    return k;
  };
  std::vector<CellIndex> kept = pull(cells);
  const std::vector<CellIndex> reversed(cells.rbegin(), cells.rend());
  const std::vector<CellIndex> back = pull(reversed);
  if (cells_length(back) < cells_length(kept) - 1e-9) kept.assign(back.rbegin(), back.rend());
  return kept;
}

}  // namespace

PlannedPath PathPlanner::plan(CellIndex start, CellIndex goal, double keep_clearance_m) {
  PlannedPath out;
  if (refuse_ends(*this, start, goal, out)) return out;
  if (++search_id_ == 0) {  // wrapped: invalidate every stamp
    std::fill(stamp_.begin(), stamp_.end(), 0);
    search_id_ = 1;
  }
  const int pw = padded_width_;
  // Ties on f go to the node nearer the goal, which keeps A* from widening on open floors.
  const auto worse = [](const Node& a, const Node& b) { return a.f > b.f || (a.f == b.f && a.h > b.h); };
  std::vector<Node> heap_storage;
  heap_storage.reserve(4096);
  std::priority_queue<Node, std::vector<Node>, decltype(worse)> open(worse, std::move(heap_storage));
  const auto si = static_cast<std::uint32_t>(padded_index(start.x, start.y));
  const auto gi = static_cast<std::uint32_t>(padded_index(goal.x, goal.y));
  stamp_[si] = search_id_;
  g_[si] = 0.0F;
  closed_[si] = 0;
  parent_[si] = si;
  open.push({octile(si, pw, goal), octile(si, pw, goal), si});
  // straight moves first; diagonal k uses straight moves kSide[k][0..1] as its two sides
  const std::int32_t steps[8] = {1, -1, pw, -pw, pw + 1, -pw + 1, pw - 1, -pw - 1};
  static constexpr int kSide[8][2] = {{0, 0}, {0, 0}, {0, 0}, {0, 0}, {0, 2}, {0, 3}, {1, 2}, {1, 3}};
  const std::uint8_t* cell_open = open_cell_.data();
  // Steps onto cells nearer than the clearance kept cost up to 1 + kClearanceWeight times more.
  const bool keep_clear = keep_clearance_m > options_.robot_radius_m;
  const auto keep = static_cast<float>(keep_clearance_m);
  const float per_m = keep_clear ? kClearanceWeight / static_cast<float>(keep_clearance_m - options_.robot_radius_m) : 0.0F;
  const float* clearance = clearance_.data();
  bool found = false;
  while (!open.empty()) {
    const Node n = open.top();
    open.pop();
    if (closed_[n.i] != 0) continue;
    closed_[n.i] = 1;
    ++out.expanded;
    if (n.i == gi) {
      found = true;
      break;
    }
    const float gn = g_[n.i];
    for (int k = 0; k < 8; ++k) {
      const auto ni = static_cast<std::uint32_t>(static_cast<std::int32_t>(n.i) + steps[k]);
      if (cell_open[ni] == 0) continue;
      if (k >= 4) {  // no corner cutting
        const auto s0 = static_cast<std::uint32_t>(static_cast<std::int32_t>(n.i) + steps[kSide[k][0]]);
        const auto s1 = static_cast<std::uint32_t>(static_cast<std::int32_t>(n.i) + steps[kSide[k][1]]);
        if (cell_open[s0] == 0 || cell_open[s1] == 0) continue;
      }
      const float penalty = keep_clear ? std::min(kClearanceWeight, std::max(0.0F, keep - clearance[ni]) * per_m) : 0.0F;
      const float ng = gn + (k >= 4 ? kSqrt2 : 1.0F) * (1.0F + penalty);
      if (stamp_[ni] != search_id_) {
        stamp_[ni] = search_id_;
        closed_[ni] = 0;
      } else if (closed_[ni] != 0 || ng >= g_[ni]) {
        continue;
      }
      g_[ni] = ng;
      parent_[ni] = n.i;
      const float h = octile(ni, pw, goal);
      open.push({ng + h, h, ni});
    }
  }
  if (!found) {
    out.status = PlanStatus::unreachable;
    out.message = unreachable_message(start, goal, options_.robot_radius_m, out.expanded);
    return out;
  }
  out.cells = trace_back(parent_, pw, si, gi);
  const std::vector<CellIndex> kept = options_.shortcut ? pull_string(*this, out.cells, keep_clearance_m) : out.cells;
  out.waypoints.reserve(kept.size());
  for (const CellIndex& c : kept) out.waypoints.push_back(grid_.cell_center(c));
  out.length_m = polyline_length_m(out.waypoints);
  out.status = PlanStatus::ok;
  return out;
}

}  // namespace tripodal::navi
