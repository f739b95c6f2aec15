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

namespace {

OccupancyGrid filled(int w, int h, Occupancy state) {
  OccupancyGrid g(w, h, 0.05);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) g.set_state({x, y}, state);
  }
  return g;
}

}  // namespace

TEST_CASE("bad floor plans are planned or refused with a message, never a hang") {
  CoverageOptions o;
  o.cleaning_width_m = 0.64;
  o.robot_radius_m = 0.3;
  SECTION("no free space: nothing to clean, answered at once on an office floor's grid") {
    // free_cell_near once searched squares of every size around the start, the cube of the side.
    const OccupancyGrid g = filled(1400, 800, Occupancy::occupied);
    const FloorCoverage f = plan_floor(g, segment_rooms(g).rooms, o, {35.0, 20.0});
    CHECK(f.order.empty());
    CHECK(f.coverage() == 1.0);
  }
  SECTION("all free space, no wall drawn: one room, cleaned") {
    const OccupancyGrid g = filled(120, 100, Occupancy::free);
    const FloorCoverage f = plan_floor(g, segment_rooms(g).rooms, o, {0.5, 0.5});
    REQUIRE(f.order.size() == 1);
    CHECK(f.coverage() >= 0.99);
  }
  SECTION("a room smaller than the robot: no way for the robot into it, reported, the rest planned") {
    // a 4 x 4 m room and, off its right wall through a 0.4 m opening, a 0.4 x 0.4 m niche given
    // as a room of its own: free cells no footprint reaches
    OccupancyGrid g = filled(92, 82, Occupancy::occupied);
    SectionSet rooms;
    rooms.label.assign(g.size(), -1);
    const auto add_room = [&](int x0, int y0, int x1, int y1) {
      Section s;
      s.id = static_cast<int>(rooms.sections.size());
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          g.set_state({x, y}, Occupancy::free);
          s.cells.push_back(g.index({x, y}));
          rooms.label[g.index({x, y})] = s.id;
        }
      }
      std::sort(s.cells.begin(), s.cells.end());
      s.min = {x0, y0};
      s.max = {x1, y1};
      s.area_m2 = static_cast<double>(s.cells.size()) * 0.05 * 0.05;
      s.centroid = {(x0 + x1 + 1) * 0.025, (y0 + y1 + 1) * 0.025};
      rooms.sections.push_back(std::move(s));
    };
    add_room(1, 1, 80, 80);
    add_room(81, 37, 88, 44);
    const FloorCoverage f = plan_floor(g, rooms, o, {0.5, 0.5});
    REQUIRE(f.order.size() == 1);
    CHECK(f.unreachable == std::vector<int>{1});
    CHECK(f.coverage() >= 0.99);
  }
  SECTION("a one-pixel gap in a wall is no way into the room behind it") {
    // The closet of the flat behind a wall with a 5 cm gap: free cells touch through it, but no
    // robot passes; the tour once reached the closet through the gap and "linked" through the wall.
    OccupancyGrid g = flat();
    g.set_state({303, 70}, Occupancy::free);
    const RoomSegmentation seg = segment_rooms(g);
    const FloorCoverage f = plan_floor(g, seg.rooms, o, {0.5, 0.5});
    CHECK(f.order.size() == 3);
    for (const int room : f.order) CHECK(seg.rooms.sections[static_cast<std::size_t>(room)].centroid.x_m < 15.0);
    CHECK(f.unreachable.size() == 2);
    CHECK(f.coverage() >= 0.99);
  }
  SECTION("rooms of another map are refused with the sizes") {
    const OccupancyGrid g = flat();
    const OccupancyGrid other = filled(120, 100, Occupancy::free);
    CHECK_THROWS_WITH(plan_floor(g, segment_rooms(other).rooms, o, {0.5, 0.5}),
                      Catch::Contains("rooms of another map") && Catch::Contains("12000 cells"));
  }
}
