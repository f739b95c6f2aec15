#include "tripodal/sim/world.hpp"

#include <catch2/catch.hpp>

#include <numbers>
#include <string>

#include "sim_test_util.hpp"
#include "tripodal/sim/simulator.hpp"

using namespace tripodal;
using namespace tripodal::sim;
using namespace tripodal::sim::test;

namespace {

const std::string kWorlds = std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/";
const std::string kMap = kWorlds + "workspace_map.yaml";
const std::string kRegions = kWorlds + "workspace_regions.yaml";

std::string error_of(const std::string& text) { return world_error_of(text); }

std::string head() { return "map: " + kMap + "\nregions: " + kRegions + "\nstart_pose: [0.8, 0.8, 0.0]\n"; }

}  // namespace

TEST_CASE("load_world: the demo workspace", "[sim][world]") {
  const World w = load_world(kWorlds + "workspace.yaml");
  CHECK(w.grid.width() == 216);
  CHECK(w.grid.height() == 656);
  CHECK(w.grid.resolution_m() == 0.05);
  CHECK(w.start_pose == Pose2D{0.8, 0.8, 0.0});
  CHECK(w.seed == 1);
  CHECK(w.regions.room("3211") != nullptr);
  CHECK(w.robot.laser.beams == 1450);
  CHECK(w.robot.laser.rate_hz == 5.5);
  CHECK(w.robot.laser.range_max_m == 12.0);
  CHECK(w.robot.cliff.positions.size() == 3);
  CHECK(w.obstacles.empty());
  CHECK(w.faults.localization_loss.empty());

  const World f = load_world(kWorlds + "workspace_faults.yaml");
  REQUIRE(f.obstacles.size() == 1);
  CHECK(f.obstacles[0].name == "cart");
  CHECK(f.obstacles[0].appear == time_from_seconds(30.0));
  CHECK(f.obstacles[0].disappear == time_from_seconds(400.0));
  CHECK(f.obstacles[0].polygon.size() == 4);
  REQUIRE(f.faults.localization_loss.size() == 1);
  CHECK(f.faults.localization_loss[0] == navi::LocalizationFault{time_from_seconds(60.0), time_from_seconds(64.0)});
  REQUIRE(f.faults.kidnappings.size() == 1);
  CHECK(f.faults.kidnappings[0].at == time_from_seconds(150.0));
  CHECK(f.faults.kidnappings[0].to == Pose2D{3.5, 2.0, 2.0});
  REQUIRE(f.faults.dead_sensors.size() == 1);
  CHECK(f.faults.dead_sensors[0].sensor == SensorKind::laser);
  CHECK(f.faults.dead_sensors[0].start == time_from_seconds(90.0));
  CHECK(f.faults.dead_sensors[0].end == time_from_seconds(92.0));

  // The workspace's scan from the start pose: every beam inside 12 m returns off the walls.
  Simulator sim(w, omni3_base(), w.seed);
  const LaserScan& scan = sim.laser().latest();
  REQUIRE(scan.ranges_m.size() == 1450);
  std::size_t returns = 0;
  for (float r : scan.ranges_m) returns += std::isfinite(r) ? 1 : 0;
  CHECK(returns > 700);
}

TEST_CASE("parse_world: every section of the schema", "[sim][world]") {
  const World w = parse_world(head() + R"(seed: 42
robot:
  radius_m: 0.3
  max_substep_s: 0.002
  laser:
    preset: sick_180
    name: scanner
    beams: 181
    range_max_m: 8
    mount: [0.2, 0.0, 0.1]
  odometry: {noise_ratio: 0.03, scale_error_stddev: 0.01, rate_hz: 50}
  gyro: {enabled: false, bias_rad_s: -0.001}
  bumpers: {sectors: 8, contact_margin_m: 0.01}
  cliff: {positions: [[0.3, 0.0]]}
  battery: {initial: 0.5, capacity_ah: 30, voltage_empty_v: 20, voltage_full_v: 29, drain_per_m: 0.001}
drops:
  - region: "2111"
  - name: ramp
    rectangle: [8, 30, 9, 31]
obstacles:
  - name: box
    polygon: [[2, 2], [3, 2], [2.5, 3]]
    appear_s: 12.5
faults:
  localization_loss:
    - {start_s: 10, end_s: 20}
  dead_sensors:
    - {sensor: bumpers, start_s: 1, end_s: 2}
)",
                              kWorlds + "inline.yaml");
  CHECK(w.seed == 42);
  CHECK(w.robot.radius_m == 0.3);
  CHECK(w.robot.max_substep == std::chrono::milliseconds(2));
  CHECK(w.robot.laser.name == "scanner");
  CHECK(w.robot.laser.beams == 181);
  CHECK(w.robot.laser.range_max_m == 8.0);
  CHECK(w.robot.laser.angle_increment() == Approx(std::numbers::pi / 180.0));
  CHECK(w.robot.laser.rate_hz == 37.5);  // from the preset
  CHECK(w.robot.laser.mount == Pose2D{0.2, 0.0, 0.1});
  CHECK(w.robot.odometry.noise_ratio == 0.03);
  CHECK(w.robot.odometry.rate_hz == 50.0);
  CHECK_FALSE(w.robot.gyro.enabled);
  CHECK(w.robot.gyro.bias_rad_s == -0.001);
  CHECK(w.robot.bumpers.sectors == 8);
  CHECK(w.robot.cliff.positions.size() == 1);
  CHECK(w.robot.battery.initial == 0.5);
  CHECK(w.robot.battery.voltage_full_v == 29.0);
  REQUIRE(w.drops.size() == 2);
  CHECK(w.drops[0].name == "2111");
  CHECK(w.drops[1].polygon.size() == 4);
  REQUIRE(w.obstacles.size() == 1);
  CHECK(w.obstacles[0].appear == Time{std::chrono::milliseconds(12500)});
  CHECK_FALSE(w.obstacles[0].disappear.has_value());
  REQUIRE(w.faults.localization_loss.size() == 1);
  CHECK(w.faults.localization_loss[0].end == time_from_seconds(20.0));
  CHECK(w.faults.dead_sensors.at(0).sensor == SensorKind::bumpers);
}

TEST_CASE("parse_world: malformed world files give located errors", "[sim][world][errors]") {
  SECTION("YAML syntax") {
    CHECK_THAT(error_of("map: [a, b\nstart_pose: 1\n"), Catch::Contains("world.yaml:"));
  }
  SECTION("not a map at all") {
    CHECK_THAT(error_of("- 1\n- 2\n"), Catch::Contains("world.yaml:1:1") && Catch::Contains("the world file: expected a map, got a list"));
  }
  SECTION("unknown key and missing map, both reported") {
    const std::string e = error_of("mapp: x.yaml\nstart_pose: [1, 1]\n");
    CHECK_THAT(e, Catch::Contains("world.yaml:1:1: error: unknown key 'mapp'") && Catch::Contains("expected one of: map"));
    CHECK_THAT(e, Catch::Contains("needs map"));
  }
  SECTION("map file not found") {
    CHECK_THAT(error_of("map: nowhere.yaml\nstart_pose: [1, 1]\n"),
               Catch::Contains("world.yaml:1:6") && Catch::Contains("map file 'nowhere.yaml' not found"));
  }
  SECTION("an error inside the map file is located there") {
    TempDir dir("badmap");
    write_file(dir / "map.yaml", "image: workspace_map.pgm\nresolution: -1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.2\n");
    write_file(dir / "world.yaml", "map: map.yaml\nstart_pose: [1, 1]\n");
    CHECK_THROWS_WITH(load_world(dir / "world.yaml"), Catch::Contains("map.yaml:2:"));
  }
  SECTION("start pose") {
    CHECK_THAT(error_of("map: " + kMap + "\nstart_pose: [1]\n"),
               Catch::Contains("world.yaml:2:13") && Catch::Contains("start_pose: expected [x, y] or [x, y, theta]"));
    CHECK_THAT(error_of("map: " + kMap + "\nstart_pose: [1, x]\n"), Catch::Contains("start_pose: expected a number, got 'x'"));
    CHECK_THAT(error_of("map: " + kMap + "\n"), Catch::Contains("needs start_pose"));
    CHECK_THAT(error_of("map: " + kMap + "\nstart_pose: [-5, 1]\n"), Catch::Contains("start_pose is outside the map"));
    // (0.8, 0.1): free cell, but the wall at y < 0 is closer than the footprint radius.
    CHECK_THAT(error_of("map: " + kMap + "\nstart_pose: [0.8, 0.1]\n"),
               Catch::Contains("world.yaml:2:13") && Catch::Contains("overlaps an occupied cell"));
  }
  SECTION("robot and sensors") {
    const std::string e = error_of(head() + "robot:\n  radius_m: 0\n  laser: {beams: 0, preset: velodyne}\n  bumpers: {sectors: 40}\n  battery: {initial: 2}\n  sonar: {}\n");
    CHECK_THAT(e, Catch::Contains("world.yaml:5:13: error: robot.radius_m: expected a number > 0, got 0"));
    CHECK_THAT(e, Catch::Contains("world.yaml:6:") && Catch::Contains("beams must be a whole number from 1 to 100000, got 0"));
    CHECK_THAT(e, Catch::Contains("unknown robot.laser.preset 'velodyne', expected rplidar_a1 or sick_180"));
    CHECK_THAT(e, Catch::Contains("world.yaml:7:") && Catch::Contains("sectors must be a whole number from 1 to 32"));
    CHECK_THAT(e, Catch::Contains("world.yaml:8:") && Catch::Contains("expected 0..1, got 2"));
    CHECK_THAT(e, Catch::Contains("world.yaml:9:3: error: unknown key 'sonar' in robot"));
  }
  SECTION("laser geometry") {
    CHECK_THAT(error_of(head() + "robot:\n  laser: {angle_min_deg: 10, angle_max_deg: -10}\n"),
               Catch::Contains("expected angle_min_deg < angle_max_deg"));
    CHECK_THAT(error_of(head() + "robot:\n  laser: {range_min_m: 5, range_max_m: 4}\n"),
               Catch::Contains("expected range_min_m < range_max_m"));
  }
  SECTION("fault schedule") {
    const std::string e = error_of(head() + R"(faults:
  localization_loss: "20-10"
  dead_sensors:
    - {sensor: sonar, start_s: 1, end_s: 2}
    - {sensor: laser, start_s: 5, end_s: 3}
    - {sensor: laser, start_s: 5}
)");
    CHECK_THAT(e, Catch::Contains("world.yaml:5:22") && Catch::Contains("bad localization fault '20-10'"));
    CHECK_THAT(e, Catch::Contains("world.yaml:7:") && Catch::Contains("unknown sensor 'sonar', expected one of laser"));
    CHECK_THAT(e, Catch::Contains("world.yaml:8:") && Catch::Contains("expected 0 <= start_s < end_s, got 5 and 3"));
    CHECK_THAT(e, Catch::Contains("world.yaml:9:") && Catch::Contains("needs start_s and end_s"));
    CHECK_THAT(error_of(head() + "faults:\n  localization_loss: {a: 1}\n"),
               Catch::Contains("world.yaml:5:22") && Catch::Contains("or a list of {start_s, end_s}"));
    CHECK_THAT(error_of(head() + "faults:\n  sensor_loss: []\n"), Catch::Contains("unknown key 'sensor_loss' in faults"));
  }
  SECTION("drops and obstacles") {
    const std::string e = error_of(head() + R"(drops:
  - region: "9999"
  - rectangle: [1, 1, 0, 2]
  - {name: both, rectangle: [1, 1, 2, 2], polygon: [[0, 0], [1, 0], [1, 1]]}
obstacles:
  - name: box
  - name: box
    polygon: [[0, 0], [1, 0]]
  - name: late
    rectangle: [1, 1, 2, 2]
    appear_s: 10
    disappear_s: 5
)");
    CHECK_THAT(e, Catch::Contains("world.yaml:5:13: error: unknown region '9999'"));
    CHECK_THAT(e, Catch::Contains("world.yaml:6:16") && Catch::Contains("rectangle is empty"));
    CHECK_THAT(e, Catch::Contains("world.yaml:7:") && Catch::Contains("exactly one of rectangle, polygon or region"));
    CHECK_THAT(e, Catch::Contains("world.yaml:9:") && Catch::Contains("obstacle 'box' needs rectangle"));
    CHECK_THAT(e, Catch::Contains("world.yaml:10:") && Catch::Contains("duplicate obstacle name 'box'"));
    CHECK_THAT(e, Catch::Contains("world.yaml:11:") && Catch::Contains("at least 3 [x, y] corners"));
    CHECK_THAT(e, Catch::Contains("world.yaml:15:") && Catch::Contains("disappear_s must be later than appear_s"));
  }
  SECTION("cannot open") {
    CHECK_THROWS_WITH(load_world("/nonexistent/world.yaml"), Catch::Contains("/nonexistent/world.yaml") &&
                                                                  Catch::Contains("cannot read the file"));
  }
}

TEST_CASE("parse_world: kidnappings, in time order, refused with their location where the robot cannot be", "[sim][world]") {
  TempDir dir("world_kidnap");
  write_file(dir / "world.yaml", head() + "faults:\n  kidnap:\n    - {at_s: 90, to: [2.5, 6.0, 2.0]}\n"
                                          "    - {at_s: 30, to: [7.0, 2.0]}\n");
  const World w = load_world(dir / "world.yaml");
  REQUIRE(w.faults.kidnappings.size() == 2);
  CHECK(w.faults.kidnappings[0].at == time_from_seconds(30.0));
  CHECK(w.faults.kidnappings[0].to == Pose2D{7.0, 2.0, 0.0});
  CHECK(w.faults.kidnappings[1].at == time_from_seconds(90.0));
  CHECK(w.faults.kidnappings[1].where.line == 6);

  // Into a wall (the obstacle at x 4.2-5.6, y 4.2-4.8), at a negative time, without a pose.
  CHECK_THAT(error_of(head() + "faults:\n  kidnap:\n    - {at_s: 10, to: [4.9, 4.5, 0.0]}\n"),
             Catch::Contains("world.yaml:6:7: error: kidnap.to: there the robot's footprint"));
  const std::string e = error_of(head() + "faults:\n  kidnap:\n    - {at_s: 10, to: [2.5, 6.0]}\n"
                                          "    - {at_s: -1, to: [2.5, 6.0]}\n    - {at_s: 5}\n    - {at: 5, to: [1, 1]}\n");
  CHECK_THAT(e, Catch::Contains("world.yaml:7:14: error: kidnap.at_s must be >= 0"));
  CHECK_THAT(e, Catch::Contains("world.yaml:8:7: error: a kidnap entry needs at_s"));
  CHECK_THAT(e, Catch::Contains("world.yaml:9:"));
  CHECK_THAT(e, !Catch::Contains("world.yaml:6:"));
  CHECK_THAT(error_of(head() + "faults:\n  kidnap: {at_s: 1}\n"), Catch::Contains("faults.kidnap must be a list"));
}

TEST_CASE("load_world: the safety ward, its stairwell and glass partition", "[sim][world][safety]") {
  const World w = load_world(kWorlds + "safety_ward.yaml");
  REQUIRE(w.drops.size() == 1);
  CHECK(w.drops[0].name == "stairwell");
  CHECK(w.drops[0].depth_m == 0.17);
  REQUIRE(w.sonar_only.size() == 1);
  CHECK(w.sonar_only[0].name == "glass_partition");
  CHECK(w.sonar_only[0].polygon.size() == 4);
  CHECK(w.robot.cliff.positions.size() == 5);
  // Neither is in the map the robot plans on: a lidar-built map shows free floor there.
  CHECK(w.grid.is_free(w.grid.cell_at({4.2, 0.7})));
  CHECK(w.grid.is_free(w.grid.cell_at({2.03, 3.0})));
}

TEST_CASE("parse_world: malformed drops, sonar_only and stuck_cliff entries give located errors",
          "[sim][world][errors][safety]") {
  const std::string e = error_of(head() + R"(drops:
  - {name: stairs, rectangle: [1, 1, 2, 2], depth_m: -0.2}
  - {name: step, rectangle: [1, 1, 2, 2], depth_m: deep}
  - {name: ramp, rectangle: [1, 1, 2, 2], slope: 3}
sonar_only:
  - {name: glass, rectangle: [2, 2, 1, 3]}
  - {name: glass, rectangle: [3, 3, 4, 4]}
  - {name: table}
  - {name: pane, polygon: [[0, 0], [1, 0]]}
  - {name: door, rectangle: [0.5, 0.5, 1.0, 1.0]}
faults:
  stuck_cliff:
    - {index: 7, reads: floor}
    - {index: -1, reads: floor}
    - {index: 0, reads: sometimes}
    - {reads: drop}
)");
  CHECK_THAT(e, Catch::Contains("world.yaml:5:") && Catch::Contains("depth_m must be > 0"));
  CHECK_THAT(e, Catch::Contains("world.yaml:6:") && Catch::Contains("depth_m"));
  CHECK_THAT(e, Catch::Contains("world.yaml:7:") && Catch::Contains("unknown key 'slope' in a drops entry"));
  CHECK_THAT(e, Catch::Contains("world.yaml:9:") && Catch::Contains("rectangle is empty"));
  CHECK_THAT(e, Catch::Contains("world.yaml:10:") && Catch::Contains("duplicate sonar_only name 'glass'"));
  CHECK_THAT(e, Catch::Contains("world.yaml:11:") && Catch::Contains("sonar_only 'table' needs rectangle"));
  CHECK_THAT(e, Catch::Contains("world.yaml:12:") && Catch::Contains("at least 3 [x, y] corners"));
  CHECK_THAT(e, Catch::Contains("world.yaml:17:") && Catch::Contains("non-negative whole number"));
  CHECK_THAT(e, Catch::Contains("world.yaml:18:") && Catch::Contains("stuck_cliff.reads must be floor or drop"));
  CHECK_THAT(e, Catch::Contains("world.yaml:19:") && Catch::Contains("needs index"));
  CHECK_THAT(error_of(head() + "sonar_only: {name: glass}\n"),
             Catch::Contains("world.yaml:4:13") && Catch::Contains("sonar_only must be a list"));
  // Checked once the rest is valid: a sensor the robot does not have, a glass pane on the start.
  const std::string late = error_of(head() + R"(sonar_only:
  - {name: door, rectangle: [0.5, 0.5, 1.0, 1.0]}
faults:
  stuck_cliff:
    - {index: 3, reads: floor}
)");
  CHECK_THAT(late, Catch::Contains("world.yaml:5:5") && Catch::Contains("sonar_only 'door' covers start_pose"));
  CHECK_THAT(late,
             Catch::Contains("world.yaml:8:7") && Catch::Contains("stuck_cliff.index 3 names no cliff sensor: the robot has 3"));
}
