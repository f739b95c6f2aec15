#include "tripodal/navi/floor_coverage.hpp"

#include <chrono>
#include <cstdlib>
#include <deque>
#include <limits>
#include <stdexcept>
#include <string>

namespace tripodal::navi {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Breadth-first search over the cells where the robot's centre may be (4-connected; the path
// planner's traversable cells, not merely free ones: a one-pixel gap in a wall once let the tour
// into the room behind it) from `from` to the first cell of a section not cleaned yet; the
// visited marks are a generation stamp, so each search costs only what it explores.
class NearestRoom {
 public:
  NearestRoom(const OccupancyGrid& grid, const SectionSet& rooms, const PathPlanner& planner)
      : grid_(grid), rooms_(rooms), planner_(planner), stamp_(grid.size(), 0), dist_(grid.size(), 0) {}

  struct Found {
    int room = -1;
    std::size_t cell = 0;
    double way_m = 0.0;
  };

  Found search(std::size_t from, const std::vector<std::uint8_t>& cleaned) {
    ++generation_;
    std::deque<std::size_t> queue{from};
    stamp_[from] = generation_;
    dist_[from] = 0;
    const int w = grid_.width(), h = grid_.height();
    while (!queue.empty()) {
      const std::size_t i = queue.front();
      queue.pop_front();
      const int room = rooms_.label[i];
      if (room >= 0 && cleaned[static_cast<std::size_t>(room)] == 0) {
        return {room, i, static_cast<double>(dist_[i]) * grid_.resolution_m()};
      }
      const int x = static_cast<int>(i % static_cast<std::size_t>(w)), y = static_cast<int>(i / static_cast<std::size_t>(w));
      const std::size_t next[4] = {x > 0 ? i - 1 : i, x + 1 < w ? i + 1 : i, y > 0 ? i - static_cast<std::size_t>(w) : i,
                                   y + 1 < h ? i + static_cast<std::size_t>(w) : i};
      for (const std::size_t n : next) {
        if (stamp_[n] == generation_ || !planner_.traversable(grid_.cell(n))) continue;
        stamp_[n] = generation_;
        dist_[n] = dist_[i] + 1;
        queue.push_back(n);
      }
    }
    return {};
  }

 private:
  const OccupancyGrid& grid_;
  const SectionSet& rooms_;
  const PathPlanner& planner_;
  std::vector<std::uint32_t> stamp_;
  std::vector<std::uint32_t> dist_;
  std::uint32_t generation_ = 0;
};

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();

// The cell nearest p where the robot may stand: p's own cell, else the first of a growing square
// ring around it. Only the ring's cells are visited: a map with no free cell once cost the cube of
// its side (seconds on an office floor's grid); plan_floor asks only when there is such a cell.
std::size_t free_cell_near(const OccupancyGrid& grid, const PathPlanner& planner, Point2D p) {
  const auto c = grid.world_to_cell(p);
  const CellIndex at = c ? *c : CellIndex{0, 0};
  const auto free_at = [&](int x, int y) {
    const CellIndex n{at.x + x, at.y + y};
    return planner.traversable(n) ? grid.index(n) : kNone;
  };
  for (int r = 0; r <= std::max(grid.width(), grid.height()); ++r) {
    for (int dy = -r; dy <= r; ++dy) {
      // the ring's top and bottom rows whole, its sides' two cells in between (row-major order)
      const int step = std::abs(dy) == r ? 1 : std::max(1, 2 * r);
      for (int dx = -r; dx <= r; dx += step) {
        if (const std::size_t i = free_at(dx, dy); i != kNone) return i;
      }
    }
  }
  return kNone;
}

}  // namespace

FloorCoverage plan_floor(const OccupancyGrid& grid, const SectionSet& rooms, const CoverageOptions& options, Point2D start,
                         FloorPattern pattern) {
  FloorCoverage out;
  if (!rooms.sections.empty() && rooms.label.size() != grid.size()) {
    throw std::invalid_argument("plan_floor: the rooms label " + std::to_string(rooms.label.size()) + " cells, the map has " +
                                std::to_string(grid.size()) + " (" + std::to_string(grid.width()) + " x " +
                                std::to_string(grid.height()) + "): rooms of another map");
  }
  const auto t_setup = Clock::now();
  CoveragePlanner cp(grid, options);
  NearestRoom nearest(grid, rooms, cp.planner());
  out.tour_ms += ms_since(t_setup);
  std::vector<std::uint8_t> cleaned(rooms.sections.size(), 0);
  bool any = false;  // a cell where the robot may stand (none on a map of walls)
  for (std::size_t i = 0; i < grid.size() && !any; ++i) any = cp.planner().traversable(grid.cell(i));
  std::size_t at = any ? free_cell_near(grid, cp.planner(), start) : kNone;
  Point2D here = start;
  while (at != kNone) {
    const auto t_tour = Clock::now();
    const NearestRoom::Found next = nearest.search(at, cleaned);
    out.tour_ms += ms_since(t_tour);
    if (next.room < 0) break;
    const Section& s = rooms.sections[static_cast<std::size_t>(next.room)];
    const Point2D entrance = grid.cell_center(grid.cell(next.cell));
    const auto t_room = Clock::now();
    CoverageResult r = pattern == FloorPattern::balloon         ? cp.balloon(s, entrance)
                       : pattern == FloorPattern::boustrophedon ? cp.boustrophedon(s, entrance)
                                                                : cp.hybrid(s, entrance);
    out.rooms_ms += ms_since(t_room);
    cleaned[static_cast<std::size_t>(next.room)] = 1;
    double link = next.way_m;
    if (!r.path.empty()) {
      const auto t_link = Clock::now();
      const PlannedPath way = cp.planner().plan(here, r.path.front());
      out.tour_ms += ms_since(t_link);
      if (way.ok()) link = way.length_m;
      here = r.path.back();
      at = free_cell_near(grid, cp.planner(), here);
    } else {
      at = next.cell;  // a room the robot cannot clean: go on from its entrance
    }
    out.order.push_back(next.room);
    out.link_m.push_back(link);
    out.length_m += link + r.stats.length_m;
    out.turns += r.stats.turns;
    out.total_turn_rad += r.stats.total_turn_rad;
    out.reachable_cells += r.reachable_cells;
    out.covered_cells += r.covered_cells;
    out.rooms.push_back(std::move(r));
  }
  for (std::size_t k = 0; k < cleaned.size(); ++k) {
    if (cleaned[k] == 0) out.unreachable.push_back(static_cast<int>(k));
  }
  return out;
}

}  // namespace tripodal::navi
