#include "tripodal/navi/regions.hpp"

#include <catch2/catch.hpp>
#include <filesystem>
#include <random>

#include "navi_test_util.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/navi/path_planner.hpp"
#include "tripodal/navi/section_splitter.hpp"

using namespace tripodal;
using namespace tripodal::navi;

TEST_CASE("regions: rooms and nodes load", "[navi][regions]") {
  const RegionMap m = parse_regions(
      "rooms:\n"
      "  - name: 3211\n"
      "    rectangle: [0, 0, 4, 2]\n"
      "  - name: L\n"
      "    polygon: [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]\n"
      "nodes:\n"
      "  - name: door\n"
      "    pose: [1.5, 0.5, 1.57]\n"
      "    description: the main door\n"
      "  - name: desk\n"
      "    pose: [3, 1]\n",
      "r.yaml");
  REQUIRE(m.rooms.size() == 2);
  const Region* r = m.room("3211");
  REQUIRE(r != nullptr);
  CHECK(r->area_m2() == Approx(8.0));
  CHECK(r->contains({3.9, 1.9}));
  CHECK_FALSE(r->contains({4.1, 1.0}));
  CHECK(r->where.str() == "r.yaml:2:5");
  const Region* l = m.room("L");
  REQUIRE(l != nullptr);
  CHECK(l->area_m2() == Approx(3.0));
  CHECK(l->contains({0.5, 1.5}));
  CHECK_FALSE(l->contains({1.5, 1.5}));  // the notch of the L
  CHECK(m.room("9999") == nullptr);
  CHECK(m.room_names() == std::vector<std::string>{"3211", "L"});
  const MapNode* door = m.node("door");
  REQUIRE(door != nullptr);
  CHECK(door->pose == Pose2D{1.5, 0.5, 1.57});
  CHECK(door->description == "the main door");
  CHECK(m.node("desk")->pose.theta_rad == 0.0);
  CHECK(parse_regions("", "empty.yaml").rooms.empty());
}

TEST_CASE("regions: every mistake of a file is reported with its place", "[navi][regions][errors]") {
  const std::string bad =
      "rooms:\n"
      "  - name: A\n"
      "    rectangle: [0, 0, 1]\n"
      "  - name: A\n"
      "    polygon: [[0, 0], [1, 1]]\n"
      "  - name: B\n"
      "    rectangle: [0, 0, 1, 1]\n"
      "    polygon: [[0, 0], [1, 0], [1, 1]]\n"
      "  - name: C\n"
      "    colour: red\n"
      "  - rectangle: [2, 2, 1, 1]\n"
      "nodes:\n"
      "  - name: n1\n"
      "    pose: [1, x]\n"
      "  - name: n2\n"
      "floors: 3\n";
  std::string what;
  try {
    (void)parse_regions(bad, "bad.yaml");
  } catch (const ConfigError& e) {
    what = e.what();
  }
  CHECK_THAT(what, Catch::Contains("bad.yaml:3:16: error: 'rectangle': expected [x_min, y_min, x_max, y_max]"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:4:11: error: duplicate room name 'A'"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:5:14: error: 'polygon': expected a list of at least 3 corners [x, y], got 2 corners"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:8:5: error: room 'B' has both a rectangle and a polygon"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:10:5: error: unknown key 'colour' in a room; expected one of: name, rectangle, polygon"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:9:5: error: room 'C' needs a 'rectangle' or a 'polygon'"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:11:5: error: a room: missing 'name'"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:11:16: error: 'rectangle' is empty"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:14:15: error: pose y: expected a number, got 'x'"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:15:5: error: node 'n2' needs a 'pose'"));
  CHECK_THAT(what, Catch::Contains("bad.yaml:16:1: error: unknown key 'floors' in the regions file; expected one of: rooms, nodes"));
  CHECK_THROWS_WITH(load_regions("/nonexistent/r.yaml"), Catch::Contains("/nonexistent/r.yaml: error: cannot read the file"));
  CHECK_THROWS_WITH(parse_regions("rooms: [a, {", "s.yaml"), Catch::Contains("s.yaml:"));
}

TEST_CASE("regions: restricting a map to a room", "[navi][regions]") {
  const OccupancyGrid g = test::room(40, 20, 0.1);  // 4 m x 2 m
  Region left{"left", {{0, 0}, {2, 0}, {2, 2}, {0, 2}}, {}};
  const std::vector<std::size_t> cells = cells_in_region(g, left);
  CHECK(cells.size() == 20U * 20U);
  const OccupancyGrid r = restrict_to_region(g, left);
  CHECK(r.state({10, 10}) == Occupancy::free);
  CHECK(r.state({30, 10}) == Occupancy::unknown);
  CHECK(r.state({39, 10}) == Occupancy::occupied);
  CHECK(r.count(Occupancy::free) == 19U * 18U);
}

TEST_CASE("the demo world: map, regions, splitter and planner agree", "[navi][regions][workspace]") {
  const std::filesystem::path dir = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs" / "worlds";
  const MapFile m = load_map(dir / "workspace_map.yaml");
  const RegionMap regions = load_regions(dir / "workspace_regions.yaml");
  for (const char* name : {"3211", "2111", "2133"}) REQUIRE(regions.room(name) != nullptr);
  CHECK(regions.room("3211")->area_m2() == Approx(320.0));
  // the whole workspace is room 3211: four sections, as in the paper's experiment
  const OccupancyGrid room = restrict_to_region(m.grid, *regions.room("3211"));
  CHECK(room.count(Occupancy::free) == m.grid.count(Occupancy::free));
  CHECK(CSectionSplitter().split(room).sections.size() == 4);
  // room 2111 alone holds one band of obstacles: one section
  CHECK(CSectionSplitter().split(restrict_to_region(m.grid, *regions.room("2111"))).sections.size() == 1);
  // every node is a place the robot (radius 0.25 m) can stand on and reach from the charger
  PathPlanner planner(m.grid, {});
  const MapNode* charger = regions.node("charger");
  REQUIRE(charger != nullptr);
  for (const MapNode& n : regions.nodes) {
    INFO("node " << n.name);
    const PlannedPath p = planner.plan(Point2D{charger->pose.x_m, charger->pose.y_m}, Point2D{n.pose.x_m, n.pose.y_m});
    CHECK(p.ok());
  }
}

TEST_CASE("regions: cells_in_region looks at the region's bounding box, with the whole map's answer", "[navi][regions]") {
  // The reference is the whole-map scan cells_in_region was: every cell's centre tested.
  const auto whole_map = [](const OccupancyGrid& g, const Region& r) {
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < g.size(); ++i) {
      if (r.contains(g.cell_center(g.cell(i)))) out.push_back(i);
    }
    return out;
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-3.0, 9.0), size(0.0, 2.5);
  for (const Pose2D origin : {Pose2D{0.0, 0.0, 0.0}, Pose2D{-1.3, 0.7, 0.0}, Pose2D{0.4, -0.2, 0.6}, Pose2D{2.0, 1.0, -2.5}}) {
    const OccupancyGrid g(61, 43, 0.1, origin, Occupancy::free);
    for (int k = 0; k < 300; ++k) {
      Region r{"r", {}, {}};
      const double x = coord(rng), y = coord(rng);
      const int corners = 3 + k % 5;
      for (int c = 0; c < corners; ++c) r.polygon.push_back({x + size(rng), y + size(rng)});
      CHECK(cells_in_region(g, r) == whole_map(g, r));
    }
    // On cell centres exactly, edges and corners of the map, a region larger than the map.
    for (const Region& r : {Region{"centres", {{0.05, 0.05}, {1.05, 0.05}, {1.05, 1.05}, {0.05, 1.05}}, {}},
                            Region{"all", {{-50, -50}, {50, -50}, {50, 50}, {-50, 50}}, {}},
                            Region{"outside", {{100, 100}, {101, 100}, {101, 101}}, {}},
                            Region{"far", {{-1e12, -1e12}, {1e12, -1e12}, {0, 1e12}}, {}}}) {
      CHECK(cells_in_region(g, r) == whole_map(g, r));
    }
  }
  CHECK(cells_in_region(OccupancyGrid(10, 10, 0.1), Region{"empty", {}, {}}).empty());
}
