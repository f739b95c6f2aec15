#include "tripodal/navi/section_splitter.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <set>

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
