// Room segmentation (include/tripodal/navi/room_segmentation.hpp) on plans whose rooms are known:
// each method finds them and the doors between them, and plans with no room in them give none.
#include "tripodal/navi/room_segmentation.hpp"

#include <catch2/catch.hpp>
#include <set>

using namespace tripodal::navi;

namespace {

constexpr double kRes = 0.05;

// A plan of `w` x `h` cells, walls around, free inside.
OccupancyGrid box(int w, int h) {
  OccupancyGrid g(w, h, kRes);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x)
      g.set_state({x, y}, x == 0 || y == 0 || x == w - 1 || y == h - 1 ? Occupancy::occupied : Occupancy::free);
  }
  return g;
}

void wall_x(OccupancyGrid& g, int x, int y0, int y1) {
  for (int y = y0; y <= y1; ++y) g.set_state({x, y}, Occupancy::occupied);
}
void wall_y(OccupancyGrid& g, int y, int x0, int x1) {
  for (int x = x0; x <= x1; ++x) g.set_state({x, y}, Occupancy::occupied);
}

// Three rooms in a row, 5 x 5 m, 5 x 5 m and 5 x 7 m, joined by 0.9 m doors: a flat without a
// corridor (85 m2: more than one room may be).
OccupancyGrid three_rooms() {
  OccupancyGrid g = box(2 + 100 + 1 + 100 + 1 + 140, 2 + 100);
  wall_x(g, 101, 0, 101);
  wall_x(g, 202, 0, 101);
  for (int y = 46; y < 64; ++y) {  // the doors: 18 cells = 0.9 m
    g.set_state({101, y}, Occupancy::free);
    g.set_state({202, y}, Occupancy::free);
  }
  return g;
}

int room_at(const RoomSegmentation& s, const OccupancyGrid& g, int x, int y) {
  return s.rooms.label[g.index({x, y})];
}

}  // namespace

TEST_CASE("every method finds the three rooms of a flat and the two doors between them") {
  const OccupancyGrid g = three_rooms();
  for (const auto method :
       {RoomSegmentationMethod::morphological, RoomSegmentationMethod::distance_transform, RoomSegmentationMethod::voronoi}) {
    INFO(to_string(method));
    RoomSegmentationOptions o;
    o.method = method;
    const RoomSegmentation s = segment_rooms(g, o);
    REQUIRE(s.rooms.sections.size() == 3);
    // Each room's middle is in a room of its own, and every free cell is in some room.
    const int a = room_at(s, g, 50, 50), b = room_at(s, g, 151, 50), c = room_at(s, g, 270, 50);
    CHECK(std::set<int>{a, b, c}.size() == 3);
    CHECK(room_at(s, g, 5, 5) == a);
    CHECK(room_at(s, g, 190, 95) == b);
    CHECK(room_at(s, g, 340, 95) == c);
    std::size_t free = 0, labelled = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
      free += g.state(i) == Occupancy::free ? 1 : 0;
      labelled += s.rooms.label[i] >= 0 ? 1 : 0;
    }
    CHECK(labelled == free);
    // Areas as built, within the door's few cells.
    CHECK(s.rooms.sections[static_cast<std::size_t>(c)].area_m2 == Approx(35.0).margin(0.2));
    // The doors: one between each pair of neighbours, where the openings are, about 0.9 m wide.
    REQUIRE(s.doors.size() == 2);
    for (const Door& d : s.doors) {
      CHECK(d.centre.y_m == Approx(55 * kRes).margin(0.1));
      CHECK(d.width_m == Approx(0.9).margin(0.15));
      const bool first = (d.room_a == std::min(a, b) && d.room_b == std::max(a, b));
      const bool second = (d.room_a == std::min(b, c) && d.room_b == std::max(b, c));
      CHECK((first || second));
      CHECK(d.centre.x_m == Approx((first ? 101 : 202) * kRes).margin(0.15));
    }
  }
}

TEST_CASE("a hall larger than the room limit is cut at its narrowing, and small nooks join their room") {
  // A 12 x 6 m hall narrowed to 0.8 m in the middle by two wall stubs, with a 0.5 x 0.5 m nook.
  OccupancyGrid g = box(242, 122);
  wall_x(g, 120, 0, 52);
  wall_x(g, 120, 69, 121);
  wall_y(g, 110, 200, 241);  // the nook: 10 x 10 cells behind a stub, open at one side
  wall_x(g, 200, 100, 110);
  for (const auto method :
       {RoomSegmentationMethod::morphological, RoomSegmentationMethod::distance_transform, RoomSegmentationMethod::voronoi}) {
    INFO(to_string(method));
    RoomSegmentationOptions o;
    o.method = method;
    const RoomSegmentation s = segment_rooms(g, o);
    CHECK(s.rooms.sections.size() == 2);
    for (const Section& r : s.rooms.sections) CHECK(r.area_m2 >= o.room_min_area_m2);
    CHECK(room_at(s, g, 60, 60) != room_at(s, g, 180, 60));
  }
}

TEST_CASE("plans with no room in them give no rooms, never a hang") {
  RoomSegmentationOptions o;
  for (const auto method :
       {RoomSegmentationMethod::morphological, RoomSegmentationMethod::distance_transform, RoomSegmentationMethod::voronoi}) {
    INFO(to_string(method));
    o.method = method;
    CHECK(segment_rooms(OccupancyGrid(), o).rooms.sections.empty());
    OccupancyGrid walls(50, 50, kRes);
    for (int y = 0; y < 50; ++y) {
      for (int x = 0; x < 50; ++x) walls.set_state({x, y}, Occupancy::occupied);
    }
    CHECK(segment_rooms(walls, o).rooms.sections.empty());
    // A room smaller than the minimum area (0.5 x 0.5 m): no core, no room.
    CHECK(segment_rooms(box(12, 12), o).rooms.sections.empty());
    // All free space, no wall at all (the border is the wall): one room per method's limits, and
    // every cell in a room.
    OccupancyGrid open(100, 100, kRes);
    for (int y = 0; y < 100; ++y) {
      for (int x = 0; x < 100; ++x) open.set_state({x, y}, Occupancy::free);
    }
    const RoomSegmentation s = segment_rooms(open, o);
    CHECK(s.rooms.sections.size() == 1);
    CHECK(s.doors.empty());
  }
  CHECK_THROWS_WITH(room_segmentation_method("watershed"), Catch::Contains("known: morphological, distance_transform, voronoi"));
  CHECK(room_segmentation_method("distance") == RoomSegmentationMethod::distance_transform);
}

TEST_CASE("the section splitter module takes a room segmentation method from its parameters") {
  const OccupancyGrid g = three_rooms();
  CSectionSplitter splitter;
  splitter.configure({{"method", tripodal::Value{std::string("morphological")}}});
  CHECK(splitter.split(g).sections.size() == 3);
  CHECK_THROWS_WITH(splitter.configure({{"method", tripodal::Value{std::string("watershed")}}}),
                    Catch::Contains("known: morphological, distance_transform, voronoi"));
  splitter.configure({{"method", tripodal::Value{std::string("splitter")}}});
  // The paper's splitter: no isolated obstacle, no virtual wall, one component.
  CHECK(splitter.split(g).sections.size() == 1);
}

TEST_CASE("bad floor plans: islands, one-pixel gaps, a door wider than its room, a room smaller than the robot") {
  for (const auto method :
       {RoomSegmentationMethod::morphological, RoomSegmentationMethod::distance_transform, RoomSegmentationMethod::voronoi}) {
    INFO(to_string(method));
    RoomSegmentationOptions o;
    o.method = method;
    // An unreachable island: a closed 3 x 3 m room inside a walled block of the flat. It is a room
    // of its own (the planner's tour reports it unreachable, floor_coverage_test), never merged
    // into a neighbour it does not touch.
    {
      OccupancyGrid g = three_rooms();
      wall_y(g, 20, 30, 92);
      wall_y(g, 82, 30, 92);
      wall_x(g, 30, 20, 82);
      wall_x(g, 92, 20, 82);
      const RoomSegmentation s = segment_rooms(g, o);
      const int island = room_at(s, g, 60, 50);
      REQUIRE(island >= 0);
      CHECK(island != room_at(s, g, 10, 10));
      for (const Door& d : s.doors) CHECK((d.room_a != island && d.room_b != island));
    }
    // A one-pixel gap in the wall between the first two rooms: not a door a robot passes, and the
    // rooms stay apart (or, if a method joins them, nothing hangs and every free cell is labelled).
    {
      OccupancyGrid g = three_rooms();
      g.set_state({101, 20}, Occupancy::free);
      const RoomSegmentation s = segment_rooms(g, o);
      CHECK(s.rooms.sections.size() >= 2);
      CHECK(room_at(s, g, 50, 50) >= 0);
    }
    // The wall between two rooms mostly open (a 4 m opening in a 5 m wall): one room or two, never
    // a sliver; every room at least the minimum area.
    {
      OccupancyGrid g = three_rooms();
      for (int y = 10; y < 90; ++y) g.set_state({101, y}, Occupancy::free);
      const RoomSegmentation s = segment_rooms(g, o);
      for (const Section& r : s.rooms.sections) CHECK(r.area_m2 >= o.room_min_area_m2);
      CHECK(room_at(s, g, 50, 50) >= 0);
    }
  }
}
