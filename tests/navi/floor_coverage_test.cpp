// A floor cleaned room by room (include/tripodal/navi/floor_coverage.hpp): every room reached
// through the doors, nearest first, its path begun where the robot came in, the links counted.
#include "tripodal/navi/floor_coverage.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "tripodal/navi/room_segmentation.hpp"

using namespace tripodal::navi;

namespace {

// Three 5 x 5 m rooms in a row joined by 0.9 m doors, and a closed 2 x 2 m closet behind the last.
OccupancyGrid flat() {
  const int w = 2 + 100 + 1 + 100 + 1 + 100 + 1 + 40, h = 102;
  OccupancyGrid g(w, h, 0.05);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x)
      g.set_state({x, y}, x == 0 || y == 0 || x == w - 1 || y == h - 1 ? Occupancy::occupied : Occupancy::free);
  }
  for (const int x : {101, 202, 303}) {
    for (int y = 0; y < h; ++y) g.set_state({x, y}, Occupancy::occupied);
  }
  for (const int x : {101, 202}) {
    for (int y = 46; y < 64; ++y) g.set_state({x, y}, Occupancy::free);
  }
  for (int x = 304; x < w; ++x) g.set_state({x, 41}, Occupancy::occupied);  // the closet: 2 m deep
  return g;
}

}  // namespace

TEST_CASE("a floor is cleaned room after room, nearest first, and a room no way leads to is reported") {
  const OccupancyGrid g = flat();
  const RoomSegmentation seg = segment_rooms(g);
  REQUIRE(seg.rooms.sections.size() == 5);  // three rooms, the closet's two parts
  CoverageOptions o;
  o.cleaning_width_m = 0.64;
  o.robot_radius_m = 0.3;
  // From the first room: the rooms in a row, left to right; the closet behind the wall unreachable.
  const FloorCoverage f = plan_floor(g, seg.rooms, o, {0.5, 0.5});
  REQUIRE(f.order.size() == 3);
  for (std::size_t k = 0; k + 1 < f.order.size(); ++k) {
    CHECK(seg.rooms.sections[static_cast<std::size_t>(f.order[k])].centroid.x_m <
          seg.rooms.sections[static_cast<std::size_t>(f.order[k + 1])].centroid.x_m);
  }
  CHECK(f.unreachable.size() == 2);
  CHECK(f.coverage() >= 0.99);
  // The first room is entered where the robot stands; the others through their door (a few metres).
  CHECK(f.link_m[0] < 0.5);
  CHECK(f.link_m[1] > 0.0);
  CHECK(f.link_m[1] < 8.0);
  // The total is the rooms' paths and the links.
  double sum = 0.0;
  for (std::size_t k = 0; k < f.order.size(); ++k) sum += f.rooms[k].stats.length_m + f.link_m[k];
  CHECK(f.length_m == Approx(sum));
  const double bound = static_cast<double>(f.reachable_cells) * 0.05 * 0.05 / o.cleaning_width_m;
  CHECK(f.length_m < 1.5 * bound);
  // Each room's path begins near where the robot came in, not at the room's far side.
  const Point2D first_end = f.rooms[0].path.back();
  const Point2D second_start = f.rooms[1].path.front();
  CHECK(std::hypot(first_end.x_m - second_start.x_m, first_end.y_m - second_start.y_m) < 8.0);
}

TEST_CASE("a floor with no room plans nothing") {
  OccupancyGrid g(20, 20, 0.05);
  const FloorCoverage f = plan_floor(g, segment_rooms(g).rooms, CoverageOptions{}, {0.5, 0.5});
  CHECK(f.order.empty());
  CHECK(f.length_m == 0.0);
  CHECK(f.coverage() == 1.0);
}
