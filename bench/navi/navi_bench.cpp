// Navigation benchmarks on the demo workspace (configs/worlds/workspace_map.yaml: 10.8 m x 32.8 m
// at 5 cm, 216 x 656 cells): distance field, A* planning, section splitting and ordering, and the
// three coverage generators per section and over the whole workspace (the planning-time budget of
// docs/coverage.md: a section under 20 ms, the workspace under 100 ms). Coverage runs report their
// path figures as counters.
#include <benchmark/benchmark.h>

#include <chrono>
#include <string>
#include <vector>

#include "instructions.hpp"
#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/distance_field.hpp"
#include "tripodal/navi/floor_coverage.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/navi/path_planner.hpp"
#include "tripodal/navi/room_segmentation.hpp"
#include "tripodal/navi/section_splitter.hpp"

using namespace tripodal::navi;

namespace {

const OccupancyGrid& workspace() {
  static const OccupancyGrid g = load_map(std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace_map.yaml").grid;
  return g;
}

const SectionSet& sections() {
  static const SectionSet s = CSectionSplitter().split(workspace());
  return s;
}

void BM_DistanceField(benchmark::State& state) {
  for (auto _ : state) {
    DistanceField f(workspace());
    benchmark::DoNotOptimize(f.distances_m().data());
  }
  state.counters["cells"] = static_cast<double>(workspace().size());
}
BENCHMARK(BM_DistanceField)->Unit(benchmark::kMillisecond);

// Corner to corner across all four obstacle bands (the longest plan in the workspace), and a
// short hop within a section.
void BM_AStar(benchmark::State& state) {
  PathPlanner planner(workspace(), {.robot_radius_m = 0.3});
  const bool long_plan = state.range(0) == 0;
  const Point2D start = long_plan ? Point2D{0.8, 0.8} : Point2D{1.0, 9.5};
  const Point2D goal = long_plan ? Point2D{9.0, 31.0} : Point2D{8.5, 13.5};
  PlannedPath p;
  for (auto _ : state) {
    p = planner.plan(start, goal);
    benchmark::DoNotOptimize(p.waypoints.data());
  }
  if (!p.ok()) state.SkipWithError(p.message.c_str());
  state.counters["length_m"] = p.length_m;
  state.counters["expanded"] = static_cast<double>(p.expanded);
  state.counters["waypoints"] = static_cast<double>(p.waypoints.size());
}
BENCHMARK(BM_AStar)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
// The instruction-count guard's twin (bench/instructions.yaml).
[[maybe_unused]] const bool kAStarTwin = tripodal::bench::register_instruction_twin("BM_AStar/short", BM_AStar, {1});

// A replan around what a laser saw: the long plan with a 1 m wall of 21 returns across its first
// leg (BhAutoMove / the cleaning detour call plan_around with the returns of one scan).
void BM_AStarAround(benchmark::State& state) {
  PathPlanner planner(workspace(), {.robot_radius_m = 0.3});
  std::vector<Point2D> seen;
  for (int k = 0; k <= 20; ++k) seen.push_back({1.5 + 0.05 * k, 2.0});
  PlannedPath p;
  for (auto _ : state) {
    p = planner.plan_around({0.8, 0.8}, {9.0, 31.0}, seen, 0.1);
    benchmark::DoNotOptimize(p.waypoints.data());
  }
  if (!p.ok()) state.SkipWithError(p.message.c_str());
  state.counters["length_m"] = p.length_m;
  state.counters["expanded"] = static_cast<double>(p.expanded);
}
BENCHMARK(BM_AStarAround)->Unit(benchmark::kMillisecond);

void BM_SectionSplitter(benchmark::State& state) {
  std::size_t n = 0;
  for (auto _ : state) {
    const SectionSet s = CSectionSplitter().split(workspace());
    n = s.sections.size();
    benchmark::DoNotOptimize(s.label.data());
  }
  state.counters["sections"] = static_cast<double>(n);
}
BENCHMARK(BM_SectionSplitter)->Unit(benchmark::kMillisecond);

// The planner's section order (nearest uncleaned next by grid path distance, four Dijkstra legs)
// from the charger in section A (arg 0) and from the upper left corner in section D (arg 1).
void BM_OrderSectionsNearestFirst(benchmark::State& state) {
  const std::vector<int> ids{0, 1, 2, 3};
  const Point2D from = state.range(0) == 0 ? Point2D{0.8, 0.8} : Point2D{0.8, 31.0};
  SectionOrder o;
  for (auto _ : state) {
    o = order_nearest_first(workspace(), sections(), ids, from);
    benchmark::DoNotOptimize(o.ids.data());
  }
  double total_m = 0.0;
  for (const double leg : o.legs_m) total_m += leg;
  state.counters["first"] = o.ids.empty() ? -1.0 : static_cast<double>(o.ids.front());
  state.counters["legs_m"] = total_m;
}
BENCHMARK(BM_OrderSectionsNearestFirst)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

enum class Pattern { balloon, boustrophedon, hybrid };

CoverageResult cover(CoveragePlanner& cp, const Section& s, Pattern p) {
  return p == Pattern::balloon ? cp.balloon(s) : p == Pattern::boustrophedon ? cp.boustrophedon(s) : cp.hybrid(s);
}

// PSR-2's cleaning tool (configs/robots/psr2.yaml): 0.64 m wide, body radius 0.3 m.
CoverageOptions psr2_options() {
  CoverageOptions o;
  o.cleaning_width_m = 0.64;
  o.robot_radius_m = 0.3;
  return o;
}

// One section (about 76 m2 each) at PSR-2's width. args: section index (0..3 = A..D), touch-up
// (1) or the passes alone (0).
template <Pattern kPattern>
void BM_Coverage(benchmark::State& state) {
  CoverageOptions o = psr2_options();
  o.touch_up = state.range(1) != 0;
  CoveragePlanner cp(workspace(), o);
  const Section& s = sections().sections.at(static_cast<std::size_t>(state.range(0)));
  CoverageResult r;
  for (auto _ : state) {
    r = cover(cp, s, kPattern);
    benchmark::DoNotOptimize(r.path.data());
  }
  state.SetLabel("section " + s.name + (o.touch_up ? "" : " passes only"));
  state.counters["coverage_pct"] = 100.0 * r.coverage();
  state.counters["length_m"] = r.stats.length_m;
  state.counters["turns"] = static_cast<double>(r.stats.turns);
  state.counters["turn_rad"] = r.stats.total_turn_rad;
  state.counters["passes"] = static_cast<double>(r.passes);
  state.counters["touch_ups"] = static_cast<double>(r.touch_ups);
  state.counters["area_m2"] = s.area_m2;
}
void BM_Balloon(benchmark::State& state) { BM_Coverage<Pattern::balloon>(state); }
void BM_Boustrophedon(benchmark::State& state) { BM_Coverage<Pattern::boustrophedon>(state); }
void BM_Hybrid(benchmark::State& state) { BM_Coverage<Pattern::hybrid>(state); }
BENCHMARK(BM_Balloon)->ArgsProduct({{0, 1, 2, 3}, {1, 0}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Boustrophedon)->ArgsProduct({{0, 1, 2, 3}, {1, 0}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Hybrid)->ArgsProduct({{0, 1, 2, 3}, {1, 0}})->Unit(benchmark::kMillisecond);

// The whole workspace (about 300 m2 of reachable floor): the planner built on the map (distance
// field, A* buffers) and every section's path. arg: 0 balloon, 1 boustrophedon, 2 hybrid.
void BM_CoverageWorkspace(benchmark::State& state) {
  const auto pattern = static_cast<Pattern>(state.range(0));
  double length_m = 0.0, reachable_m2 = 0.0;
  for (auto _ : state) {
    CoveragePlanner cp(workspace(), psr2_options());
    length_m = 0.0;
    reachable_m2 = 0.0;
    for (const Section& s : sections().sections) {
      const CoverageResult r = cover(cp, s, pattern);
      length_m += r.stats.length_m;
      reachable_m2 += static_cast<double>(r.reachable_cells) * 0.05 * 0.05;
      benchmark::DoNotOptimize(r.path.data());
    }
  }
  state.SetLabel(pattern == Pattern::balloon ? "balloon" : pattern == Pattern::boustrophedon ? "boustrophedon" : "hybrid");
  state.counters["length_m"] = length_m;
  state.counters["reachable_m2"] = reachable_m2;
}
BENCHMARK(BM_CoverageWorkspace)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// A generated office floor of 2,800 m2 (70 x 40 m at 5 cm, 1,400 x 800 cells; issue 39's "whole
// floor"): two 2 m corridors the length of the floor, rooms of 5 x 4 m on both sides of each and
// between them, each with a 0.9 m door onto its corridor.
const OccupancyGrid& office_floor() {
  static const OccupancyGrid g = [] {
    const int w = 1400, h = 800;
    OccupancyGrid f(w, h, 0.05);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x)
        f.set_state({x, y}, x == 0 || y == 0 || x == w - 1 || y == h - 1 ? Occupancy::occupied : Occupancy::free);
    }
    const auto wall_x = [&](int x, int y0, int y1) {
      for (int y = y0; y <= y1; ++y) f.set_state({x, y}, Occupancy::occupied);
    };
    const auto wall_y = [&](int y, int x0, int x1) {
      for (int x = x0; x <= x1; ++x) f.set_state({x, y}, Occupancy::occupied);
    };
    // Bands from the bottom: rooms 0-80, corridor 80-120, rooms 120-200 | 200-280, corridor
    // 280-320 ... : rows of rooms 4 m deep (80 cells) around 2 m corridors (40 cells).
    const std::vector<std::pair<int, int>> corridors = {{160, 200}, {600, 640}};
    for (const auto& [c0, c1] : corridors) {
      for (const int wall : {c0, c1}) {
        wall_y(wall, 1, w - 2);
        for (int x = 50; x < w - 50; x += 100) {  // a door per 5 m room, 0.9 m wide
          for (int d = 0; d < 18; ++d) f.set_state({x + d, wall}, Occupancy::free);
        }
      }
    }
    for (const int y : {80, 280, 400, 520, 720}) wall_y(y, 1, w - 2);  // rooms 4 m deep
    for (int x = 100; x < w - 1; x += 100) {                           // 5 m wide, between the corridors' walls
      wall_x(x, 1, 159);
      wall_x(x, 201, 599);
      wall_x(x, 641, h - 2);
    }
    // Doors between the stacked rooms and the rooms on the corridors (else they are closed cells).
    for (int x = 30; x < w - 50; x += 100) {
      for (const int y : {80, 280, 520, 720}) {
        for (int d = 0; d < 18; ++d) f.set_state({x + d, y}, Occupancy::free);
      }
      for (int d = 0; d < 18; ++d) f.set_state({x + d, 400}, Occupancy::free);
    }
    return f;
  }();
  return g;
}

// Rooms of the office floor. arg: RoomSegmentationMethod.
void BM_RoomSegmentation(benchmark::State& state) {
  RoomSegmentationOptions o;
  o.method = static_cast<RoomSegmentationMethod>(state.range(0));
  std::size_t rooms = 0, doors = 0;
  for (auto _ : state) {
    const RoomSegmentation r = segment_rooms(office_floor(), o);
    rooms = r.rooms.sections.size();
    doors = r.doors.size();
    benchmark::DoNotOptimize(r.rooms.label.data());
  }
  state.SetLabel(std::string(to_string(o.method)));
  state.counters["rooms"] = static_cast<double>(rooms);
  state.counters["doors"] = static_cast<double>(doors);
}
BENCHMARK(BM_RoomSegmentation)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The whole floor planned: rooms (morphological), then the tour (nearest room next through the
// doors, links by A*) with the hybrid's path in every room, from the floor's corner. Issue 39's
// budget: 1 s. Counters: the rooms' and the tour's shares of the planning (ms).
void BM_WholeFloorPlan(benchmark::State& state) {
  FloorCoverage f;
  double segmentation_ms = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const RoomSegmentation r = segment_rooms(office_floor());
    segmentation_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    f = plan_floor(office_floor(), r.rooms, psr2_options(), {1.0, 1.0});
    benchmark::DoNotOptimize(f.length_m);
  }
  const double reachable_m2 = static_cast<double>(f.reachable_cells) * 0.05 * 0.05;
  state.counters["rooms"] = static_cast<double>(f.order.size());
  state.counters["length_m"] = f.length_m;
  state.counters["reachable_m2"] = reachable_m2;
  state.counters["coverage_pct"] = 100.0 * f.coverage();
  state.counters["length_per_bound"] = reachable_m2 > 0 ? f.length_m / (reachable_m2 / 0.64) : 0.0;
  state.counters["segmentation_ms"] = segmentation_ms;
  state.counters["rooms_ms"] = f.rooms_ms;
  state.counters["tour_ms"] = f.tour_ms;
}
BENCHMARK(BM_WholeFloorPlan)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
