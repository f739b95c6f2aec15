#include "tripodal/navi/occupancy_grid.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "navi_test_util.hpp"

using namespace tripodal;
using namespace tripodal::navi;

TEST_CASE("OccupancyGrid: size, fill, states and values", "[navi][grid]") {
  OccupancyGrid g(4, 3, 0.1, {}, Occupancy::free);
  CHECK(g.width() == 4);
  CHECK(g.height() == 3);
  CHECK(g.size() == 12);
  CHECK(g.width_m() == Approx(0.4));
  CHECK(g.count(Occupancy::free) == 12);
  g.set_state({1, 2}, Occupancy::occupied);
  g.set_state({3, 0}, Occupancy::unknown);
  CHECK(g.state({1, 2}) == Occupancy::occupied);
  CHECK(g.value({1, 2}) == 100);
  CHECK(g.value({3, 0}) == -1);
  CHECK(g.index({1, 2}) == 9);
  CHECK(g.cell(9) == CellIndex{1, 2});
  CHECK(g.count(Occupancy::occupied) == 1);
  CHECK(g.count(Occupancy::unknown) == 1);
  // outside the grid reads as unknown
  CHECK(g.state({-1, 0}) == Occupancy::unknown);
  CHECK(g.state({4, 0}) == Occupancy::unknown);
  // scale-mode probabilities are neither free nor occupied
  g.set_value({0, 0}, 42);
  CHECK(g.state({0, 0}) == Occupancy::unknown);
  CHECK(g.value({0, 0}) == 42);
  g.set_value({0, 0}, -7);
  CHECK(g.value({0, 0}) == -1);
}

TEST_CASE("OccupancyGrid: bad construction arguments", "[navi][grid]") {
  CHECK_THROWS_WITH(OccupancyGrid(-1, 3, 0.1), Catch::Contains("must not be negative"));
  CHECK_THROWS_WITH(OccupancyGrid(1, 3, 0.0), Catch::Contains("resolution must be positive"));
  CHECK_THROWS_WITH(OccupancyGrid(1, 3, std::nan("")), Catch::Contains("resolution must be positive"));
}

TEST_CASE("OccupancyGrid: world <-> cell without rotation", "[navi][grid]") {
  const OccupancyGrid g(10, 20, 0.05, Pose2D{-1.0, 2.0, 0.0});
  CHECK(g.cell_at({-1.0, 2.0}) == CellIndex{0, 0});
  CHECK(g.cell_at({-0.951, 2.049}) == CellIndex{0, 0});
  CHECK(g.cell_at({-0.949, 2.051}) == CellIndex{1, 1});
  CHECK_FALSE(g.world_to_cell({-1.001, 2.5}).has_value());
  CHECK_FALSE(g.world_to_cell({-0.5, 3.0}).has_value());  // y = 3.0 is the top edge, outside
  CHECK(g.world_to_cell({-0.501, 2.999}) == CellIndex{9, 19});
  CHECK_FALSE(g.world_to_cell({std::nan(""), 2.5}).has_value());
  const Point2D c = g.cell_center({3, 7});
  CHECK(c.x_m == Approx(-1.0 + 0.175));
  CHECK(c.y_m == Approx(2.0 + 0.375));
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 10; ++x) CHECK(g.cell_at(g.cell_center({x, y})) == CellIndex{x, y});
  }
}

TEST_CASE("OccupancyGrid: world <-> cell with a rotated origin", "[navi][grid]") {
  // grid +x points along map +y
  const OccupancyGrid g(10, 10, 0.5, Pose2D{1.0, 1.0, std::numbers::pi / 2});
  const Point2D c = g.cell_center({0, 0});
  CHECK(c.x_m == Approx(0.75));
  CHECK(c.y_m == Approx(1.25));
  CHECK(g.cell_at({0.75, 2.25}) == CellIndex{2, 0});
  CHECK(g.cell_at({-0.25, 1.25}) == CellIndex{0, 2});
  CHECK_FALSE(g.world_to_cell({1.25, 1.25}).has_value());
}

TEST_CASE("OccupancyGrid: art helper puts the first row on top", "[navi][grid]") {
  const OccupancyGrid g = test::grid_from_art({"#..", "..?"});
  CHECK(g.state({0, 1}) == Occupancy::occupied);
  CHECK(g.state({2, 0}) == Occupancy::unknown);
  CHECK(g.state({0, 0}) == Occupancy::free);
}
