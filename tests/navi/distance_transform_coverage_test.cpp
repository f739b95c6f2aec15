// Zelinsky's distance-transform coverage (include/tripodal/navi/distance_transform_coverage.hpp):
// it covers what the footprint can reach, farthest part first, and ends at its goal.
#include "tripodal/navi/distance_transform_coverage.hpp"

#include <catch2/catch.hpp>
#include <cmath>

using namespace tripodal::navi;

namespace {

OccupancyGrid room(int w, int h) {
  OccupancyGrid g(w, h, 0.05);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x)
      g.set_state({x, y}, x == 0 || y == 0 || x == w - 1 || y == h - 1 ? Occupancy::occupied : Occupancy::free);
  }
  return g;
}

Section whole(const OccupancyGrid& g) {
  std::vector<int> label(g.size(), -1);
  for (std::size_t i = 0; i < g.size(); ++i) label[i] = g.state(i) == Occupancy::free ? 0 : -1;
  return sections_of_labels(g, label).sections.at(0);
}

}  // namespace

TEST_CASE("distance-transform coverage covers a room with a pillar and returns to its goal") {
  OccupancyGrid g = room(122, 82);  // 6 x 4 m
  for (int y = 30; y < 50; ++y) {
    for (int x = 50; x < 70; ++x) g.set_state({x, y}, Occupancy::occupied);  // a 1 x 1 m pillar
  }
  const Section s = whole(g);
  CoverageOptions o;
  o.cleaning_width_m = 0.4;
  const Point2D start{0.4, 0.4};
  const CoverageResult r = distance_transform_coverage(g, s, o, start);
  REQUIRE(r.path.size() > 10);
  // Tool-sized cells do not line up with the walls: strips along them stay (no touch-up here).
  CHECK(r.coverage() >= 0.97);
  CHECK(r.reachable_cells > 0);
  // It ends where it started (the goal defaults to the start), having swept the far end first.
  CHECK(std::hypot(r.path.front().x_m - r.path.back().x_m, r.path.front().y_m - r.path.back().y_m) < 0.3);
  CHECK(std::hypot(r.path.front().x_m - start.x_m, r.path.front().y_m - start.y_m) < 0.3);
  // Near the bound: the room's reachable area over the tool width, a factor the sweep may exceed
  // only by its returns.
  const double bound = static_cast<double>(r.reachable_cells) * 0.05 * 0.05 / o.cleaning_width_m;
  CHECK(r.stats.length_m < 2.0 * bound);
  CHECK(r.stats.length_m > 0.9 * bound);
  // Every waypoint is a cell the robot can stand on: inside the room, off the pillar.
  for (const Point2D& p : r.path) {
    const auto c = g.world_to_cell(p);
    REQUIRE(c.has_value());
    CHECK(g.is_free(*c));
  }
}

TEST_CASE("distance-transform coverage of a section too narrow for the robot is empty") {
  const OccupancyGrid g = room(8, 60);  // 0.3 m wide: a 0.4 m tool does not fit
  CoverageOptions o;
  o.cleaning_width_m = 0.4;
  const CoverageResult r = distance_transform_coverage(g, whole(g), o);
  CHECK(r.path.empty());
  CHECK(r.reachable_cells == 0);
  CHECK(r.coverage() == 1.0);
  CHECK(distance_transform_coverage(g, Section{}, o).path.empty());
}
