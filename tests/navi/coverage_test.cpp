#include "tripodal/navi/coverage.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "navi_test_util.hpp"
#include "tripodal/navi/map_io.hpp"

using namespace tripodal;
using namespace tripodal::navi;

namespace {

void put_block(OccupancyGrid& g, int x0, int y0, int x1, int y1) {
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) g.set_state({x, y}, Occupancy::occupied);
  }
}

// Every path vertex is on a cell the robot may stand on (within the simplification tolerance).
void check_path_clear(const CoverageResult& r, const OccupancyGrid& g, double robot_radius_m) {
  const DistanceField f(g);
  for (const Point2D& p : r.path) {
    const auto c = g.world_to_cell(p);
    REQUIRE(c.has_value());
    CHECK(f.clearance_m(g.index(*c)) >= robot_radius_m - g.resolution_m());
  }
}

}  // namespace

TEST_CASE("CleanedCells: discs and swaths", "[navi][coverage]") {
  const OccupancyGrid g(100, 100, 0.01, {}, Occupancy::free);
  CleanedCells c(g);
  c.mark_disc({0.5, 0.5}, 0.1);
  // about pi r^2 / cell area = 314 cells
  CHECK(static_cast<double>(c.count()) == Approx(std::numbers::pi * 100.0).epsilon(0.03));
  CHECK(c.cleaned(CellIndex{50, 50}));
  CHECK(c.cleaned(CellIndex{59, 50}));
  CHECK_FALSE(c.cleaned(CellIndex{61, 50}));
  c.clear();
  CHECK(c.count() == 0);
  c.mark_segment({0.2, 0.5}, {0.8, 0.5}, 0.05);
  // a 0.6 x 0.1 rectangle plus two half discs
  CHECK(static_cast<double>(c.count()) == Approx(600.0 + std::numbers::pi * 25.0).epsilon(0.05));
  CHECK(c.cleaned(CellIndex{50, 54}));
  CHECK_FALSE(c.cleaned(CellIndex{50, 56}));
  // outside the grid and non-finite input: nothing, no crash
  c.mark_disc({-5.0, -5.0}, 0.1);
  c.mark_disc({std::nan(""), 0.0}, 0.1);
  const std::vector<std::size_t> cells{g.index({50, 50}), g.index({0, 0})};
  CHECK(c.coverage(cells) == Approx(0.5));
  CHECK(c.coverage({}) == 1.0);
}

TEST_CASE("path_stats: length, turns over the threshold, total heading change", "[navi][coverage]") {
  const std::vector<Point2D> square{{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}};
  const PathStats s = path_stats(square, 0.5);
  CHECK(s.length_m == Approx(4.0));
  CHECK(s.turns == 3);
  CHECK(s.total_turn_rad == Approx(3 * std::numbers::pi / 2));
  // gentle bends under the threshold are not turns; a repeated point is ignored
  const std::vector<Point2D> bend{{0, 0}, {1, 0}, {1, 0}, {2, 0.2}, {3, 0.6}};
  const PathStats b = path_stats(bend, 0.5);
  CHECK(b.turns == 0);
  CHECK(b.total_turn_rad > 0.3);
  const std::vector<Point2D> uturn{{0, 0}, {1, 0}, {0, 0}};
  CHECK(path_stats(uturn, 0.5).turns == 1);
}

TEST_CASE("Coverage: an empty room, balloon and boustrophedon both cover it", "[navi][coverage]") {
  const OccupancyGrid g = test::room(82, 62, 0.05);  // 4 m x 3 m inside
  const SectionSet sections = CSectionSplitter().split(g);
  REQUIRE(sections.sections.size() == 1);
  CoverageOptions o;
  o.cleaning_width_m = 0.4;
  CoveragePlanner cp(g, o);
  const CoverageResult b = cp.balloon(sections.sections[0], Point2D{0.5, 0.5});
  const CoverageResult p = cp.boustrophedon(sections.sections[0], Point2D{0.5, 0.5});
  for (const CoverageResult* r : {&b, &p}) {
    CHECK(r->coverage() >= 0.99);
    CHECK(r->reachable_cells > 0);
    CHECK(r->reachable_cells < sections.sections[0].cells.size());  // corners a disc cannot enter
    CHECK(r->reachable_cells > sections.sections[0].cells.size() * 95 / 100);
    check_path_clear(*r, g, 0.2);
  }
  // a 4 x 3 m room at 0.35 m spacing: rounds until the offsets meet in the middle
  CHECK(b.rounds >= 4);
  CHECK(b.rounds <= 5);
  // the first pass is tangent to the walls: its vertices are 0.2 m from them
  REQUIRE(b.path.size() > 2);
  // plowing across 3 m (lanes along the 4 m side) needs about 3 / 0.35 lanes, two turns each
  CHECK(p.passes >= 8);
  CHECK(p.stats.turns >= 2 * (p.passes - 1) - 2);
  INFO("balloon length " << b.stats.length_m << " turns " << b.stats.turns << "; plough length "
                         << p.stats.length_m << " turns " << p.stats.turns);
  // in a rectangle, every round of the spiral has 4 corners and every lane 2 ends: 2 D / spacing
  // turns either way (D the short side); the balloon saves the lane ends' U-turn travel
  CHECK(b.stats.turns <= p.stats.turns);
  CHECK(b.stats.length_m < p.stats.length_m);
}

TEST_CASE("Coverage: a room with an isolated obstacle", "[navi][coverage]") {
  OccupancyGrid g = test::room(102, 82, 0.05);
  put_block(g, 40, 30, 60, 45);
  const SectionSet sections = CSectionSplitter().split(g);
  REQUIRE(sections.sections.size() == 1);
  CoveragePlanner cp(g, {});
  const CoverageResult b = cp.balloon(sections.sections[0]);
  const CoverageResult p = cp.boustrophedon(sections.sections[0]);
  CHECK(b.coverage() >= 0.99);
  CHECK(p.coverage() >= 0.99);
  check_path_clear(b, g, 0.2);
  check_path_clear(p, g, 0.2);
  // the obstacle's contour is a pass of its own in the first rounds
  CHECK(b.passes > b.rounds);
}

TEST_CASE("Coverage: a bigger robot keeps its radius from walls, unreachable parts are not counted",
          "[navi][coverage]") {
  OccupancyGrid g = test::room(82, 62, 0.05);
  // a closet behind a 0.3 m doorway: the robot (radius 0.3 m) cannot get in
  put_block(g, 50, 1, 51, 60);
  for (int y = 28; y < 34; ++y) g.set_state({50, y}, Occupancy::free), g.set_state({51, y}, Occupancy::free);
  const SectionSet sections = CSectionSplitter().split(g);
  REQUIRE(sections.sections.size() == 1);
  CoverageOptions o;
  o.cleaning_width_m = 0.4;
  o.robot_radius_m = 0.3;
  CoveragePlanner cp(g, o);
  const CoverageResult b = cp.balloon(sections.sections[0]);
  CHECK(b.coverage() >= 0.99);
  // the closet right of x = 51 is not reachable: the reachable area is well below the section
  CHECK(b.reachable_cells < sections.sections[0].cells.size() * 70 / 100);
  check_path_clear(b, g, 0.3);
  for (const Point2D& pt : b.path) CHECK(pt.x_m < 51 * 0.05);
}

TEST_CASE("Coverage: the four sections of the demo workspace at 0.4 m", "[navi][coverage][workspace]") {
  const MapFile m = load_map(std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace_map.yaml");
  const SectionSet sections = CSectionSplitter().split(m.grid);
  REQUIRE(sections.sections.size() == 4);
  CoveragePlanner cp(m.grid, {});
  for (const Section& s : sections.sections) {
    const CoverageResult b = cp.balloon(s);
    const CoverageResult p = cp.boustrophedon(s);
    INFO("section " << s.name << ": balloon cov " << b.coverage() << " len " << b.stats.length_m << " turns "
                    << b.stats.turns << " touch-ups " << b.touch_ups << "; plough cov " << p.coverage() << " len "
                    << p.stats.length_m << " turns " << p.stats.turns << " touch-ups " << p.touch_ups);
    CHECK(b.coverage() >= 0.99);
    CHECK(p.coverage() >= 0.99);
    CHECK(b.reachable_cells == p.reachable_cells);
    WARN("section " << s.name << ": balloon cov " << b.coverage() << " len " << b.stats.length_m << " turns " << b.stats.turns << " (" << b.stats.total_turn_rad << " rad) touch-ups " << b.touch_ups << " rounds " << b.rounds << " passes " << b.passes << "; plough cov " << p.coverage() << " len " << p.stats.length_m << " turns " << p.stats.turns << " (" << p.stats.total_turn_rad << " rad) touch-ups " << p.touch_ups << " passes " << p.passes);
  }
}

TEST_CASE("Hybrid: the round around a box is one walk, entered from the tour where it passes by", "[navi][coverage]") {
  OccupancyGrid g = test::room(122, 82, 0.05);
  put_block(g, 50, 32, 70, 48);  // a 1 m x 0.8 m box in the middle
  const SectionSet sections = CSectionSplitter().split(g);
  REQUIRE(sections.sections.size() == 1);
  CoverageOptions o;  // PSR-2: the round keeps 0.32 m from the box
  o.cleaning_width_m = 0.64;
  o.robot_radius_m = 0.3;
  CoveragePlanner cp(g, o);
  const CoverageResult h = cp.hybrid(sections.sections[0]);
  CHECK(h.coverage() >= 0.99);
  check_path_clear(h, g, 0.3);
  // stretches of the path on the box's round (vertices 0.31-0.40 m from the box)
  const auto on_round = [&](Point2D p) {
    const double dx = std::max({50 * 0.05 - p.x_m, 0.0, p.x_m - 71 * 0.05});
    const double dy = std::max({32 * 0.05 - p.y_m, 0.0, p.y_m - 49 * 0.05});
    const double d = std::hypot(dx, dy);
    return d >= 0.31 && d <= 0.40;
  };
  int walks = 0;
  std::size_t run = 0, longest = 0;
  for (const Point2D& p : h.path) {
    run = on_round(p) ? run + 1 : 0;
    if (run == 8) ++walks;  // a walk along the round, not a lane end touching it
    longest = std::max(longest, run);
  }
  CHECK(walks == 1);
  // all the way round: about the perimeter in cells, 2 (21 + 17) sides and four rounded corners
  CHECK(longest >= 100);
}

TEST_CASE("Hybrid: the path ends near finish_near, for little more travel", "[navi][coverage]") {
  OccupancyGrid g = test::room(162, 82, 0.05);  // 8 m x 4 m
  const SectionSet sections = CSectionSplitter().split(g);
  REQUIRE(sections.sections.size() == 1);
  CoveragePlanner cp(g, {});
  const Point2D start{4.0, 2.0};
  const Point2D west{0.3, 2.0}, east{7.8, 2.0};
  const CoverageResult free_end = cp.hybrid(sections.sections[0], start);
  const CoverageResult to_west = cp.hybrid(sections.sections[0], start, west);
  const CoverageResult to_east = cp.hybrid(sections.sections[0], start, east);
  for (const CoverageResult* r : {&free_end, &to_west, &to_east}) CHECK(r->coverage() >= 0.99);
  CHECK(to_west.path.back().x_m < 2.0);
  CHECK(to_east.path.back().x_m > 6.0);
  // the end is chosen by length + the way on: each is the best of the three by that measure
  const auto cost = [](const CoverageResult& r, Point2D goal) {
    return r.stats.length_m + std::hypot(r.path.back().x_m - goal.x_m, r.path.back().y_m - goal.y_m);
  };
  CHECK(cost(to_west, west) <= cost(free_end, west) + 1e-6);
  CHECK(cost(to_west, west) <= cost(to_east, west) + 1e-6);
  CHECK(cost(to_east, east) <= cost(free_end, east) + 1e-6);
  CHECK(cost(to_east, east) <= cost(to_west, east) + 1e-6);
}

TEST_CASE("Hybrid: the demo workspace at PSR-2's width, near the physical bound", "[navi][coverage][workspace]") {
  const MapFile m = load_map(std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace_map.yaml");
  const SectionSet sections = CSectionSplitter().split(m.grid);
  CoverageOptions o;
  o.cleaning_width_m = 0.64;
  o.robot_radius_m = 0.3;
  CoveragePlanner cp(m.grid, o);
  double hybrid_m = 0.0, plough_m = 0.0, area_m2 = 0.0;
  std::size_t hybrid_turns = 0, plough_turns = 0;
  for (const Section& s : sections.sections) {
    const CoverageResult h = cp.hybrid(s);
    const CoverageResult p = cp.boustrophedon(s);
    CHECK(h.coverage() >= 0.995);
    hybrid_m += h.stats.length_m;
    plough_m += p.stats.length_m;
    hybrid_turns += h.stats.turns;
    plough_turns += p.stats.turns;
    area_m2 += static_cast<double>(h.reachable_cells) * m.grid.resolution_m() * m.grid.resolution_m();
  }
  const double bound_m = area_m2 / o.cleaning_width_m;
  INFO("hybrid " << hybrid_m << " m (" << hybrid_m / bound_m << " x the bound), " << hybrid_turns << " turns; plough "
                 << plough_m << " m, " << plough_turns << " turns");
  // docs/coverage.md: 606.2 m = 1.28 x the bound, 266 turns (boustrophedon: 640.8 m, 523 turns)
  CHECK(hybrid_m <= 1.30 * bound_m);
  CHECK(hybrid_m < plough_m);
  CHECK(hybrid_turns <= plough_turns);
}

// The demo's corner case (docs/coverage.md): lanes that end 0.1 m inside the round, beside a box,
// and links from such a lane end past the box's corner to the next lane. Planned on line of
// sight alone, a link cut by the corner at the robot radius and a cell (the differential base,
// turning while it drove, hit such a corner on the demo); with the link margin the links keep
// the clearance of the lane ends they join.
TEST_CASE("Hybrid: links keep a margin at box corners the lanes end beside", "[navi][coverage]") {
  OccupancyGrid g = test::room(119, 64, 0.05);  // 5.95 m x 3.2 m
  const std::vector<std::array<int, 4>> boxes{{53, 30, 61, 37}, {89, 33, 95, 44}};
  for (const auto& [x0, y0, x1, y1] : boxes) put_block(g, x0, y0, x1, y1);
  const SectionSet sections = CSectionSplitter().split(g);
  REQUIRE(sections.sections.size() == 1);
  // least distance of the path's straight legs (longer than two cells: links and lanes, not the
  // round's cell chains) to the boxes, sampled every 2 cm
  const auto least_to_boxes = [&](const std::vector<Point2D>& path) {
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t i = 1; i < path.size(); ++i) {
      const Point2D a = path[i - 1], b = path[i];
      if (std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) < 0.12) continue;
      const int steps = std::max(1, static_cast<int>(std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) / 0.02));
      for (int k = 0; k <= steps; ++k) {
        const double t = static_cast<double>(k) / steps;
        const double x = a.x_m + t * (b.x_m - a.x_m), y = a.y_m + t * (b.y_m - a.y_m);
        for (const auto& [x0, y0, x1, y1] : boxes) {
          const double dx = std::max({x0 * 0.05 - x, 0.0, x - (x1 + 1) * 0.05});
          const double dy = std::max({y0 * 0.05 - y, 0.0, y - (y1 + 1) * 0.05});
          least = std::min(least, std::hypot(dx, dy));
        }
      }
    }
    return least;
  };
  CoverageOptions o;
  o.cleaning_width_m = 0.64;
  o.robot_radius_m = 0.3;
  o.lane_inset_m = 0.1;
  o.link_margin_m = 0.0;
  CoveragePlanner bare(g, o);
  o.link_margin_m = 0.1;
  CoveragePlanner kept(g, o);
  const CoverageResult a = bare.hybrid(sections.sections[0], Point2D{0.5, 0.5});
  const CoverageResult b = kept.hybrid(sections.sections[0], Point2D{0.5, 0.5});
  INFO("bare " << least_to_boxes(a.path) << " m, " << a.stats.length_m << " m; kept " << least_to_boxes(b.path) << " m, "
               << b.stats.length_m << " m");
  CHECK(least_to_boxes(a.path) < 0.32);   // a leg grazes a corner: the body (0.25 m) has 6 cm to spare
  CHECK(least_to_boxes(b.path) >= 0.41);  // the lane ends' 0.42 m, less the cell quantisation
  CHECK(b.coverage() >= 0.99);
  CHECK(b.stats.length_m <= 1.02 * a.stats.length_m);
  check_path_clear(b, g, 0.3);
  // the defaults: lanes 0.1 m inside the round, links 5 cm beyond the robot radius where they can
  CoverageOptions d;
  d.cleaning_width_m = 0.64;
  d.robot_radius_m = 0.3;
  const CoverageResult c = CoveragePlanner(g, d).hybrid(sections.sections[0], Point2D{0.5, 0.5});
  INFO("defaults " << least_to_boxes(c.path) << " m, " << c.stats.length_m << " m");
  CHECK(least_to_boxes(c.path) >= 0.35);
  CHECK(c.coverage() >= 0.99);
}

// A room at an angle to the grid (a wing of a pentagonal building, as ipa's office_e): lanes on
// the grid's rows or columns end in staircases along its walls and left wedges that the touch-up
// visited one by one from the path's end, across the room (office_e: 1.68x the bound). The
// hybrid now lays lanes along the walls and visits what is left from the leg passing nearest.
TEST_CASE("Hybrid: a room slanted to the grid is ploughed along its walls, near the bound", "[navi][coverage]") {
  for (const double angle_deg : {30.0, 72.0}) {
    INFO("room at " << angle_deg << " degrees");
    const double a = angle_deg * std::numbers::pi / 180.0;
    OccupancyGrid g(200, 200, 0.05);
    for (int y = 0; y < 200; ++y) {
      for (int x = 0; x < 200; ++x) {
        const double px = (x + 0.5) * 0.05 - 5.0, py = (y + 0.5) * 0.05 - 5.0;
        const double u = px * std::cos(a) + py * std::sin(a), v = -px * std::sin(a) + py * std::cos(a);
        g.set_state({x, y}, std::abs(u) < 3.5 && std::abs(v) < 2.0 ? Occupancy::free : Occupancy::occupied);
      }
    }
    const SectionSet sections = CSectionSplitter().split(g);
    REQUIRE(sections.sections.size() == 1);
    CoverageOptions o;
    o.cleaning_width_m = 0.64;
    o.robot_radius_m = 0.3;
    CoveragePlanner cp(g, o);
    const CoverageResult r = cp.hybrid(sections.sections[0]);
    CHECK(r.coverage() == 1.0);
    const double bound_m = static_cast<double>(r.reachable_cells) * 0.05 * 0.05 / o.cleaning_width_m;
    INFO(r.stats.length_m << " m, " << r.stats.length_m / bound_m << " x the bound, " << r.stats.turns << " turns, "
                          << r.touch_ups << " touch-ups");
    // before: 1.41x at 30 degrees (rows and columns only, touch-ups from the path's end); now 1.30x
    CHECK(r.stats.length_m <= 1.32 * bound_m);
    // the long legs (lanes) run along or across the walls
    std::size_t lanes = 0, along = 0;
    for (std::size_t k = 1; k < r.path.size(); ++k) {
      const double dx = r.path[k].x_m - r.path[k - 1].x_m, dy = r.path[k].y_m - r.path[k - 1].y_m;
      if (std::hypot(dx, dy) < 1.5) continue;
      ++lanes;
      const double off = std::remainder(std::atan2(dy, dx) - a, std::numbers::pi / 2.0);
      along += std::abs(off) < 3.0 * std::numbers::pi / 180.0 ? 1 : 0;
    }
    CHECK(lanes >= 5);
    CHECK(along >= lanes * 9 / 10);
  }
}
