#include "tripodal/navi/section_splitter.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "navi_test_util.hpp"
#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/navi/regions.hpp"

using namespace tripodal;
using namespace tripodal::navi;

namespace {

void put_block(OccupancyGrid& g, int x0, int y0, int x1, int y1) {
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) g.set_state({x, y}, Occupancy::occupied);
  }
}

}  // namespace

TEST_CASE("CSectionSplitter: an empty room is one section", "[navi][splitter]") {
  const OccupancyGrid g = test::room(40, 60, 0.1);
  const SectionSet s = CSectionSplitter().split(g);
  REQUIRE(s.sections.size() == 1);
  CHECK(s.isolated_obstacles == 0);
  CHECK(s.virtual_wall_rows.empty());
  CHECK(s.sections[0].cells.size() == 38U * 58U);
  CHECK(s.sections[0].area_m2 == Approx(38 * 58 * 0.01));
  CHECK(s.sections[0].min == CellIndex{1, 1});
  CHECK(s.sections[0].max == CellIndex{38, 58});
  CHECK(s.sections[0].name == "A");
}

TEST_CASE("CSectionSplitter: a virtual wall in the middle of the gap between two obstacle bands", "[navi][splitter]") {
  OccupancyGrid g = test::room(50, 100, 0.1);  // 5 m x 10 m
  put_block(g, 20, 10, 25, 15);                // band rows 10..15
  put_block(g, 10, 70, 12, 74);                // band rows 70..74
  put_block(g, 30, 72, 33, 80);                // same band, rows 72..80
  // furniture on the left wall is not isolated and does not make a band
  put_block(g, 1, 40, 5, 45);
  const SectionSet s = CSectionSplitter().split(g);
  CHECK(s.isolated_obstacles == 3);
  SectionSplitterOptions wide;
  wide.min_gap_m = 6.0;  // the 5.4 m gap is not enough
  CHECK(CSectionSplitter(wide).split(g).sections.size() == 1);
  REQUIRE(s.virtual_wall_rows == std::vector<int>{(15 + 70) / 2});
  REQUIRE(s.sections.size() == 2);
  CHECK(s.sections[0].min.y == 1);
  CHECK(s.sections[0].max.y == 42);
  CHECK(s.sections[1].min.y == 43);
  CHECK(s.sections[1].max.y == 98);
  // every free cell is in exactly one section
  std::size_t labelled = 0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (g.state(i) == Occupancy::free) {
      CHECK(s.label[i] >= 0);
      ++labelled;
    } else {
      CHECK(s.label[i] == -1);
    }
  }
  CHECK(labelled == s.sections[0].cells.size() + s.sections[1].cells.size());
  CHECK(std::find(s.obstacle_rows.begin(), s.obstacle_rows.end(), 42) == s.obstacle_rows.end());
  CHECK(std::find(s.obstacle_rows.begin(), s.obstacle_rows.end(), 72) != s.obstacle_rows.end());
}

TEST_CASE("CSectionSplitter: walls that would leave thin strips are dropped", "[navi][splitter]") {
  OccupancyGrid g = test::room(50, 100, 0.1);
  put_block(g, 20, 10, 22, 12);
  put_block(g, 20, 20, 22, 22);  // gap 12..20: wall at 16, only 1.6 m above the floor: dropped
  put_block(g, 20, 60, 22, 62);  // wall at (22+60)/2 = 41
  SectionSplitterOptions o;
  o.min_gap_m = 0.1;
  o.min_section_height_m = 2.0;
  const SectionSet s = CSectionSplitter(o).split(g);
  CHECK(s.virtual_wall_rows == std::vector<int>{41});
  CHECK(s.sections.size() == 2);
  o.min_section_height_m = 1.0;
  const SectionSet t = CSectionSplitter(o).split(g);
  CHECK(t.virtual_wall_rows == std::vector<int>{16, 41});
  CHECK(t.sections.size() == 3);
}

TEST_CASE("CSectionSplitter: a sliver cut off by a virtual wall merges into its neighbour", "[navi][splitter]") {
  OccupancyGrid g = test::room(60, 100, 0.1);
  put_block(g, 20, 5, 22, 7);    // obstacle bands at rows 5..7 and 90..92: wall at row 48
  put_block(g, 20, 90, 22, 92);
  put_block(g, 1, 50, 58, 51);   // a partition wall across the room just above it
  SectionSplitterOptions o;
  o.min_section_height_m = 1.0;
  o.min_section_area_m2 = 1.0;
  const SectionSet s = CSectionSplitter(o).split(g);
  REQUIRE(s.virtual_wall_rows == std::vector<int>{48});
  // row 49 (58 cells, 0.58 m2) lies between the virtual wall and the partition: merged below
  REQUIRE(s.sections.size() == 2);
  CHECK(s.label[g.index({10, 49})] == s.label[g.index({10, 20})]);
  CHECK(s.label[g.index({10, 60})] != s.label[g.index({10, 20})]);
  CHECK(s.sections[0].max.y == 49);
  o.min_section_area_m2 = 0.5;  // now the sliver is large enough to stay on its own
  CHECK(CSectionSplitter(o).split(g).sections.size() == 3);
}

TEST_CASE("CSectionSplitter: a free speck inside a thick wall is dropped, unknown is not free", "[navi][splitter]") {
  OccupancyGrid g = test::room(30, 30, 0.1);
  put_block(g, 10, 10, 14, 14);
  g.set_state({12, 12}, Occupancy::free);  // a one-cell hole inside the obstacle
  g.set_state({5, 5}, Occupancy::unknown);
  const SectionSet s = CSectionSplitter().split(g);
  REQUIRE(s.sections.size() == 1);
  CHECK(s.label[g.index({12, 12})] == -1);
  CHECK(s.label[g.index({5, 5})] == -1);
  CHECK(s.isolated_obstacles == 1);
}

TEST_CASE("CSectionSplitter: the demo workspace splits into four large sections", "[navi][splitter][workspace]") {
  const MapFile m = load_map(std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace_map.yaml");
  REQUIRE(m.grid.width() == 216);
  REQUIRE(m.grid.height() == 656);
  CHECK(m.grid.width_m() == Approx(10.8));
  CHECK(m.grid.height_m() == Approx(32.8));
  const SectionSet s = CSectionSplitter().split(m.grid);
  CHECK(s.isolated_obstacles == 11);
  for (const Section& sec : s.sections) UNSCOPED_INFO(sec.name << " " << sec.area_m2 << " x " << sec.min.x << ".." << sec.max.x << " y " << sec.min.y << ".." << sec.max.y);
  for (int r : s.virtual_wall_rows) UNSCOPED_INFO("wall " << r);
  REQUIRE(s.sections.size() == 4);
  REQUIRE(s.virtual_wall_rows.size() == 3);
  double total = 0.0;
  for (const Section& sec : s.sections) {
    INFO("section " << sec.name << " area " << sec.area_m2 << " rows " << sec.min.y << ".." << sec.max.y);
    CHECK(sec.area_m2 > 60.0);
    CHECK(sec.area_m2 < 90.0);
    CHECK((sec.max.y - sec.min.y + 1) * 0.05 > 7.0);
    CHECK((sec.max.x - sec.min.x + 1) * 0.05 == Approx(10.0));
    total += sec.area_m2;
  }
  CHECK(total == Approx(static_cast<double>(m.grid.count(Occupancy::free)) * 0.0025));
  // the walls are in the gaps between the bands of obstacles, around y = 7.75, 15.75, 23.75 m
  const double expected_y[3] = {7.75, 15.75, 23.75};
  for (std::size_t k = 0; k < 3; ++k) {
    const double y = m.grid.cell_center({0, s.virtual_wall_rows[k]}).y_m;
    CHECK(std::abs(y - expected_y[k]) < 0.3);
  }
  CHECK(s.sections[0].name == "A");
  CHECK(s.sections[3].name == "D");
}

namespace {

struct Box {
  const char* name;
  int x0, y0, x1, y1;  // inclusive
};

// Sections drawn by hand: the free cells of each box, in the order given (ids 0, 1, ...).
SectionSet sections_in_boxes(const OccupancyGrid& g, const std::vector<Box>& boxes) {
  SectionSet s;
  s.label.assign(g.size(), -1);
  for (const Box& b : boxes) {
    Section sec;
    sec.id = static_cast<int>(s.sections.size());
    sec.name = b.name;
    double sx = 0.0, sy = 0.0;
    for (int y = b.y0; y <= b.y1; ++y) {
      for (int x = b.x0; x <= b.x1; ++x) {
        if (!g.is_free({x, y})) continue;
        sec.cells.push_back(g.index({x, y}));
        s.label[g.index({x, y})] = sec.id;
        sx += g.cell_center({x, y}).x_m;
        sy += g.cell_center({x, y}).y_m;
      }
    }
    std::sort(sec.cells.begin(), sec.cells.end());
    sec.centroid = {sx / static_cast<double>(sec.cells.size()), sy / static_cast<double>(sec.cells.size())};
    s.sections.push_back(std::move(sec));
  }
  return s;
}

}  // namespace

TEST_CASE("order_nearest_first: the demo workspace from a start in section A and from a start in section D",
          "[navi][splitter][order][workspace]") {
  const MapFile m = load_map(std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace_map.yaml");
  const SectionSet s = CSectionSplitter().split(m.grid);
  REQUIRE(s.sections.size() == 4);
  const std::vector<std::string> scan{"A", "B", "C", "D"};
  // the charger, lower left corner (configs/worlds/workspace.yaml): the scan order
  CHECK(order_nearest_first(m.grid, s, scan, {0.8, 0.8}) == scan);
  // the upper left corner, in section D (configs/worlds/workspace_start_d.yaml): D first, then back down
  CHECK(order_nearest_first(m.grid, s, scan, {0.8, 31.0}) == std::vector<std::string>{"D", "C", "B", "A"});
  // only some sections asked for, in any order; the legs are path lengths
  const std::vector<int> ids{3, 0};
  const SectionOrder o = order_nearest_first(m.grid, s, ids, {0.8, 0.8});
  REQUIRE(o.ids == std::vector<int>{0, 3});
  CHECK(o.legs_m[0] == 0.0);  // the start is in A
  CHECK(o.legs_m[1] > 10.0);  // from A's centre (about y = 3.9 m) to D's first row (about y = 23.8 m)
  CHECK(o.legs_m[1] < 25.0);
  // a name that is no section keeps its place at the end
  const std::vector<std::string> with_unknown{"Z", "B", "A"};
  CHECK(order_nearest_first(m.grid, s, with_unknown, {0.8, 31.0}) == std::vector<std::string>{"B", "A", "Z"});
}

TEST_CASE("CSectionSplitter answers sections(room) nearest first from the localized pose, in scan order without one",
          "[navi][splitter][order][workspace]") {
  // The question the planner asks when it makes the plan (paper, section 5.1): the sequencing loop
  // passes the robot's NavigationData, and the answer's order is the order of the PrCleaning steps.
  const std::string worlds = std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/";
  const MapFile m = load_map(worlds + "workspace_map.yaml");
  const RegionMap regions = load_regions(worlds + "workspace_regions.yaml");
  CSectionSplitter splitter;
  splitter.split_map(m.grid, regions);
  NavigationData at_charger;  // configs/worlds/workspace.yaml
  at_charger.localized = true;
  at_charger.map_from_base = {0.8, 0.8, 0.0};
  NavigationData in_d = at_charger;  // configs/worlds/workspace_start_d.yaml
  in_d.map_from_base = {0.8, 31.0, 0.0};
  const auto a = splitter.answer("sections", "3211", at_charger);
  REQUIRE(a);
  REQUIRE(a->ok);
  CHECK(a->items == std::vector<std::string>{"A", "B", "C", "D"});
  const auto d = splitter.answer("sections", "3211", in_d);
  REQUIRE(d);
  CHECK(d->items == std::vector<std::string>{"D", "C", "B", "A"});
  // room 2133 is the top of the hall: only D
  CHECK(splitter.answer("sections", "2133", at_charger)->items == std::vector<std::string>{"D"});
  // a pose the localizer does not trust orders nothing: scan order
  NavigationData lost = in_d;
  lost.localized = false;
  CHECK(splitter.answer("sections", "3211", lost)->items == std::vector<std::string>{"A", "B", "C", "D"});
  // errors and other questions are untouched
  const auto bad = splitter.answer("sections", "9999", in_d);
  REQUIRE(bad);
  CHECK_FALSE(bad->ok);
  CHECK_THAT(bad->error, Catch::Contains("unknown room '9999'"));
  CHECK_FALSE(splitter.answer("rooms", "3211", in_d));
}

TEST_CASE("order_nearest_first: path distance, not straight-line: a section behind a wall is not near",
          "[navi][splitter][order]") {
  // 1 m cells. The robot stands at (6, 3); section R (x 8..10, y 5..8) is 2.8 m away in a
  // straight line but 8 m by the opening in the wall at the bottom; section F (x 1..3, y 7..8) is
  // 5 m away in a straight line and 5.2 m by path.
  const OccupancyGrid g = test::grid_from_art(
      {
          "############",
          "#......#...#",
          "#......#...#",
          "#......#...#",
          "#......#...#",
          "#......#...#",
          "#......#...#",
          "#......#...#",
          "#..........#",
          "############",
      },
      1.0);
  const SectionSet s = sections_in_boxes(g, {{"R", 8, 5, 10, 8}, {"F", 1, 7, 3, 8}});
  const Point2D start = g.cell_center({6, 3});
  const std::vector<int> ids{0, 1};
  const SectionOrder o = order_nearest_first(g, s, ids, start);
  REQUIRE(o.ids == std::vector<int>{1, 0});  // F, then R
  CHECK(o.legs_m[0] == Approx(3.0 * std::sqrt(2.0) + 1.0));  // three diagonal steps and one up to (3, 7)
  // from F's centre (2, 7.5 -> cell (2, 7)) down to the opening and up again into R
  CHECK(o.legs_m[1] > 10.0);

  SECTION("a start on a wall starts from the nearest free cell") {
    // 0.3 m right of the centre of the wall cell (7, 3): the free cell (8, 3) is nearer than (6, 3)
    CHECK(order_nearest_first(g, s, ids, {7.8, 3.5}).ids == std::vector<int>{0, 1});
  }
  SECTION("a section no path reaches comes last, with an infinite leg") {
    OccupancyGrid closed = g;
    for (int x = 8; x <= 10; ++x) closed.set_state({x, 1}, Occupancy::occupied);
    closed.set_state({7, 1}, Occupancy::occupied);
    const SectionSet cs = sections_in_boxes(closed, {{"R", 8, 5, 10, 8}, {"F", 1, 7, 3, 8}});
    const SectionOrder co = order_nearest_first(closed, cs, ids, start);
    REQUIRE(co.ids == std::vector<int>{1, 0});
    CHECK(std::isinf(co.legs_m[1]));
  }
  SECTION("unknown ids and repeats are ignored") {
    const std::vector<int> odd{7, 0, 0, -1};
    CHECK(order_nearest_first(g, s, odd, start).ids == std::vector<int>{0});
  }
}
