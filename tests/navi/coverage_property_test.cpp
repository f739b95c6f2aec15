// Property tests of the coverage planners in the Fields2Cover manner: on 1,000 seeded random
// grids (rooms with boxes, pillars and walls with doorways), whatever the layout, the path covers
// every reachable cell, joins its consecutive points by collision-free segments, never stands
// inside an inflated obstacle, is at least as long as the physical bound, and is the same for the
// same seed.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <sstream>
#include <string>

#include "navi_test_util.hpp"
#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/distance_field.hpp"
#include "tripodal/navi/section_splitter.hpp"

using namespace tripodal;
using namespace tripodal::navi;

namespace {

struct RandomCase {
  OccupancyGrid grid;
  CoverageOptions options;
  std::string description;
};

// A room of 1-3.5 m a side at 5 cm with 0-5 boxes, and sometimes an inner wall with a doorway.
RandomCase random_case(unsigned seed) {
  std::mt19937 rng(seed);
  const auto uni = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const int w = uni(20, 70), h = uni(20, 70);
  RandomCase c{test::room(w, h, 0.05), {}, {}};
  std::ostringstream d;
  d << "seed " << seed << ": " << w << " x " << h << " cells";
  const int boxes = uni(0, 5);
  for (int b = 0; b < boxes; ++b) {
    const int bw = uni(1, 10), bh = uni(1, 10);
    const int bx = uni(1, std::max(1, w - bw - 1)), by = uni(1, std::max(1, h - bh - 1));
    for (int y = by; y < std::min(h - 1, by + bh); ++y) {
      for (int x = bx; x < std::min(w - 1, bx + bw); ++x) c.grid.set_state({x, y}, Occupancy::occupied);
    }
    d << ", box " << bx << "," << by << " " << bw << "x" << bh;
  }
  if (uni(0, 3) == 0 && w > 30) {
    const int wx = uni(10, w - 10), door = uni(1, h - 14);
    for (int y = 1; y < h - 1; ++y) {
      if (y < door || y >= door + 12) c.grid.set_state({wx, y}, Occupancy::occupied);
    }
    d << ", wall x=" << wx << " door y=" << door;
  }
  c.options.cleaning_width_m = 0.05 * uni(4, 10);
  c.options.robot_radius_m = uni(0, 1) == 0 ? 0.0 : c.options.cleaning_width_m / 2.0 + 0.05 * uni(0, 2);
  d << ", width " << c.options.cleaning_width_m << " m, radius " << c.options.robot_radius_m << " m";
  c.description = d.str();
  return c;
}

}  // namespace

TEST_CASE("Coverage properties on 1,000 seeded random grids (hybrid)", "[navi][coverage][property]") {
  std::size_t sections_checked = 0;
  for (unsigned seed = 1; seed <= 1000; ++seed) {
    const RandomCase c = random_case(seed);
    INFO(c.description);
    const SectionSet sections = CSectionSplitter().split(c.grid);
    CoveragePlanner cp(c.grid, c.options);
    const double radius = cp.options().robot_radius_m;
    const DistanceField field(c.grid);
    for (const Section& s : sections.sections) {
      INFO("section " << s.name);
      const CoverageResult r = cp.hybrid(s);
      if (r.reachable_cells == 0) continue;
      ++sections_checked;
      // every reachable cell covered
      REQUIRE(r.covered_cells == r.reachable_cells);
      // no point inside an inflated obstacle, consecutive points joined by free segments
      for (std::size_t i = 0; i < r.path.size(); ++i) {
        const auto cell = c.grid.world_to_cell(r.path[i]);
        REQUIRE(cell.has_value());
        INFO("point " << i << " at " << r.path[i].x_m << ", " << r.path[i].y_m << " from "
                      << (i > 0 ? r.path[i - 1].x_m : 0.0) << ", " << (i > 0 ? r.path[i - 1].y_m : 0.0));
        REQUIRE(field.clearance_m(c.grid.index(*cell)) >= radius - 1e-6);
        if (i > 0) {
          const auto prev = c.grid.world_to_cell(r.path[i - 1]);
          REQUIRE(cp.planner().line_of_sight(*prev, *cell));
        }
      }
      // at least the physical bound: under the cell-centre measure a disc of width w sweeps a
      // strip w + one cell wide, plus its two end caps
      const double res = c.grid.resolution_m();
      const double swath = cp.options().cleaning_width_m + res;
      const double area = static_cast<double>(r.covered_cells) * res * res;
      const double caps = 3.14159265358979 * swath * swath / 4.0;
      REQUIRE(r.stats.length_m * swath + caps >= area);
      // the same seed, the same path (every fourth grid: the check doubles the time)
      if (seed % 4 != 0) continue;
      CoveragePlanner again(c.grid, c.options);
      const CoverageResult r2 = again.hybrid(s);
      REQUIRE(r2.path.size() == r.path.size());
      for (std::size_t i = 0; i < r.path.size(); ++i) {
        REQUIRE(r2.path[i].x_m == r.path[i].x_m);
        REQUIRE(r2.path[i].y_m == r.path[i].y_m);
      }
    }
  }
  // some sections are too narrow for the footprint: most are not
  CHECK(sections_checked >= 800);
}
