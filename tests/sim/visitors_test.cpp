// Visitors walking in the simulator (moving obstacles on seeded trajectories), the simulated
// joints and LED buttons: the world syntax with located errors, determinism per seed, what the
// laser and bumpers see, collisions with a visitor, giving way, joint limits and speed.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "sim_test_util.hpp"
#include "tripodal/behaviors/gesture_behaviors.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace tripodal::sim;
using namespace tripodal::sim::test;
using Catch::Matchers::Contains;

namespace {

const std::string kWorlds = std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/";

std::string error_of(const std::string& text) { return world_error_of(text); }

const std::string kHead = "map: " + kWorlds + "exhibit_hall_map.yaml\nstart_pose: [1.5, 4.0, 0.0]\n";

// A 6 m x 4 m room, the robot at (1, 2) facing +x, one visitor walking across in front of it.
World crossing_world() {
  World w = room_world(120, 80, {1.0, 2.0, 0.0});
  Visitor v;
  v.name = "walker";
  v.path = {{3.0, 0.5}, {3.0, 3.5}};
  v.speed_min_m_s = 0.6;
  v.speed_max_m_s = 1.2;
  v.pause_min_s = 0.0;
  v.pause_max_s = 2.0;
  w.visitors.push_back(v);
  return w;
}

std::vector<navi::Point2D> walk(std::uint64_t seed, double seconds) {
  Simulator sim(crossing_world(), differential_base(), seed);
  std::vector<navi::Point2D> track;
  for (int i = 0; i < static_cast<int>(seconds * 10); ++i) {
    sim.step(std::chrono::milliseconds(100));
    track.push_back(sim.visitors()[0].position);
  }
  return track;
}

}  // namespace

TEST_CASE("visitors: the world file's syntax, and its errors located", "[sim][visitors][world]") {
  TempDir dir("visitors_ok");
  write_file(dir / "world.yaml", kHead + R"(robot:
  joints: [{name: neck, min_deg: -45, max_deg: 30, speed_deg_s: 60, initial_deg: 5}]
  buttons: [hello, help]
visitors:
  - name: ann
    path: [[3.0, 1.5], [10.0, 1.5], [10.0, 4.9], [3.0, 4.9]]
    speed_m_s: [0.5, 0.9]
    pause_s: 2
    loop: true
    start_s: 4
  - name: bob
    path: [[9.0, 3.0]]
    follow_robot: true
    follow_gap_m: 1.2
)");
  const World w = load_world(dir / "world.yaml");
  REQUIRE(w.visitors.size() == 2);
  CHECK(w.visitors[0].name == "ann");
  CHECK(w.visitors[0].path.size() == 4);
  CHECK(w.visitors[0].loop);
  CHECK(w.visitors[0].speed_min_m_s == 0.5);
  CHECK(w.visitors[0].speed_max_m_s == 0.9);
  CHECK(w.visitors[0].pause_min_s == 2.0);
  CHECK(w.visitors[0].pause_max_s == 2.0);
  CHECK(w.visitors[0].start == time_from_seconds(4.0));
  CHECK(w.visitors[1].path.size() == 1);
  CHECK(w.visitors[1].follow_robot);
  CHECK(w.visitors[1].follow_gap_m == 1.2);
  REQUIRE(w.robot.joints.size() == 1);
  CHECK(w.robot.joints[0].min_rad == Approx(-45.0 * std::numbers::pi / 180.0));
  CHECK(w.robot.joints[0].initial_rad == Approx(5.0 * std::numbers::pi / 180.0));
  REQUIRE(w.robot.buttons.size() == 2);
  CHECK(w.robot.buttons[1].name == "help");

  // Every problem at once, each at its line.
  const std::string e = error_of(kHead + R"(robot:
  joints: [{name: neck, min_deg: 30, max_deg: -30}]
  buttons: [a, a]
visitors:
  - name: ann
    path: [[3.0, 3.0], [3.0]]
    speed_m_s: [0.9, 0.5]
  - name: ann
    path: [[3.0, 3.0]]
    walk: fast
)");
  CHECK_THAT(e, Contains("world.yaml:4:47: error: joint 'neck': expected min_deg < max_deg, got 30 and -30"));
  CHECK_THAT(e, Contains("world.yaml:5:16: error: duplicate button name 'a'"));
  CHECK_THAT(e, Contains("world.yaml:8:24: error: visitor 'ann'.path waypoint: expected [x, y]"));
  CHECK_THAT(e, Contains("world.yaml:9:16: error: visitor 'ann'.speed_m_s: expected 0 < min <= max, got [0.9, 0.5]"));
  CHECK_THAT(e, Contains("world.yaml:10:11: error: duplicate visitor name 'ann'"));
  CHECK_THAT(e, Contains("world.yaml:12:5: error: unknown key 'walk' in a visitors entry"));
  // A path through a wall, once the file is otherwise right.
  CHECK_THAT(error_of(kHead + "visitors:\n  - name: wall\n    path: [[1.0, 3.0], [-0.3, 3.0]]\n"),
             Contains(":4:") && Contains("visitor 'wall'") && Contains("overlaps an occupied cell or leaves the map"));
}

TEST_CASE("visitors: a seed gives one walk, another seed another", "[sim][visitors]") {
  const auto a = walk(7, 20.0), b = walk(7, 20.0), c = walk(8, 20.0);
  CHECK(a == b);
  CHECK(a != c);
  // Walking the path: x stays on the line, y covers the whole leg both ways.
  double y_min = 10.0, y_max = -10.0;
  for (const auto& p : a) {
    CHECK(p.x_m == Approx(3.0));
    y_min = std::min(y_min, p.y_m);
    y_max = std::max(y_max, p.y_m);
  }
  CHECK(y_min == Approx(0.5).margin(0.05));
  CHECK(y_max == Approx(3.5).margin(0.05));
}

TEST_CASE("visitors: the laser sees them, the footprint stops on them, the bumpers feel them", "[sim][visitors]") {
  World w = room_world(120, 80, {1.0, 2.0, 0.0});
  Visitor v;
  v.name = "stander";
  v.radius_m = 0.25;
  v.path = {{2.5, 2.0}};
  w.visitors.push_back(v);
  w.robot.laser = LaserConfig::sick_180();
  w.robot.laser.noise_stddev_m = 0.0;
  Simulator sim(w, differential_base(), 1);
  // The beam straight ahead (beam 180 of 361) returns from the visitor's near side, 1.25 m off.
  const LaserScan& scan = sim.laser().latest();
  CHECK(scan.ranges_m[180] == Approx(1.25).margin(1e-4));
  CHECK(scan.ranges_m[0] > 1.9f);  // to the right, the wall at 1.95 m, not the visitor

  // Driving straight at the visitor: the base stops against it, one collision, with its name.
  sim.command_twist({0.5, 0.0, 0.0});
  sim.step(std::chrono::seconds(4));
  CHECK(sim.blocked());
  CHECK(sim.pose().x_m == Approx(2.0).margin(0.01));
  CHECK(sim.collisions() == 1);
  CHECK(sim.visitor_collisions() == 1);
  REQUIRE_FALSE(sim.events().empty());
  CHECK_THAT(sim.events().back().detail, Contains("with stander"));
  CHECK(sim.min_visitor_clearance_m() == Approx(0.0).margin(0.01));
  sim.step(std::chrono::milliseconds(40));
  CHECK((sim.bumpers().latest().pressed_mask & 1U) != 0);  // the front sector
}

TEST_CASE("visitors: a walker gives way to the robot standing on its path", "[sim][visitors]") {
  World w = room_world(120, 80, {3.0, 2.0, 0.0});
  Visitor v;
  v.name = "walker";
  v.path = {{3.0, 0.5}, {3.0, 3.5}};
  v.speed_min_m_s = v.speed_max_m_s = 1.0;
  w.visitors.push_back(v);
  Simulator sim(w, differential_base(), 3);
  for (int i = 0; i < 100; ++i) sim.step(std::chrono::milliseconds(100));
  // It walked up to the robot and waits there; nobody touched anybody.
  CHECK(sim.visitors()[0].giving_way);
  CHECK(sim.collisions() == 0);
  CHECK(sim.min_visitor_clearance_m() >= v.give_way_m - 0.02);
}

TEST_CASE("joints: limits, speed, the state a JointResource shows, the position channel the hardware exports", "[sim][joints]") {
  World w = room_world(60, 60, {1.5, 1.5, 0.0});
  w.robot.joints.push_back({"neck", -0.5, 0.8, 1.0, 0.0, 50.0, {}});
  w.robot.buttons.push_back({"hello", {}});
  SimHardware hw(w, differential_base(), 1);
  ResourceTable table;
  hw.add_resources(table);
  auto* joint = dynamic_cast<JointResource*>(table.find("neck"));
  REQUIRE(joint != nullptr);
  CHECK(joint->latest().max_rad == 0.8);

  CommandChannels& channels = hw.command_channels();
  REQUIRE(channels.find("neck") == std::size_t{0});
  CHECK(channels.spec(0).type == ChannelType::joint_position);
  CHECK(channels.spec(0).hold);
  channels.set(0, ChannelValue::of(0.6));  // as the behavior loop writes it
  hw.advance_to(time_from_seconds(0.3));  // 1 rad/s: 0.3 rad in 0.3 s
  CHECK(joint->latest().position_rad == Approx(0.3).margin(1e-6));
  CHECK(joint->latest().velocity_rad_s == Approx(1.0));
  hw.advance_to(time_from_seconds(1.0));
  CHECK(joint->latest().position_rad == 0.6);
  CHECK(joint->latest().velocity_rad_s == 0.0);

  // Beyond the limit: clamped, flagged.
  CHECK_FALSE(hw.simulator().command_joint(0, 2.0));
  CHECK(hw.simulator().joints()[0].at_limit);
  hw.advance_to(time_from_seconds(2.0));
  CHECK(joint->latest().position_rad == 0.8);
  CHECK_FALSE(hw.simulator().command_joint(3, 0.0));

  // LED buttons: a press is an event and queued once.
  CHECK(hw.simulator().press_button("hello"));
  CHECK_FALSE(hw.simulator().press_button("nope"));
  CHECK(hw.simulator().events().back().kind == SimEvent::Kind::button_pressed);
  CHECK(hw.simulator().take_button_presses() == std::vector<std::string>{"hello"});
  CHECK(hw.simulator().take_button_presses().empty());
  CHECK(hw.simulator().set_led("hello", true));
  CHECK(hw.simulator().led("hello"));
  CHECK_FALSE(hw.simulator().set_led("nope", true));
}

TEST_CASE("visitors: a guided visitor follows the robot along its trail and keeps its gap", "[sim][visitors]") {
  World w = room_world(120, 80, {1.0, 2.0, 0.0});
  Visitor g;
  g.name = "guest";
  g.path = {{0.4, 2.0}};
  g.follow_robot = true;
  g.follow_gap_m = 0.5;
  g.speed_min_m_s = g.speed_max_m_s = 0.8;
  w.visitors.push_back(g);
  Simulator sim(w, differential_base(), 1);
  // An L-shaped drive: 3 m along x, a quarter turn, 1 m along y.
  sim.command_twist({0.5, 0.0, 0.0});
  sim.step(std::chrono::seconds(6));
  sim.command_twist({0.0, 0.0, std::numbers::pi / 4.0});
  sim.step(std::chrono::seconds(2));
  sim.command_twist({0.5, 0.0, 0.0});
  sim.step(std::chrono::seconds(2));
  sim.command_twist({});
  sim.step(std::chrono::seconds(3));
  const navi::Point2D p = sim.visitors()[0].position;
  const double gap = std::hypot(p.x_m - sim.pose().x_m, p.y_m - sim.pose().y_m) - 0.5;
  CHECK(gap == Approx(0.5).margin(0.05));
  // Behind the robot on its trail, at the corner (trail points are 0.2 m apart: it cuts the corner
  // by at most that), not on the straight line through the room.
  CHECK(p.x_m > 3.75);
  CHECK(p.x_m < 4.05);
  CHECK(p.y_m < sim.pose().y_m - 0.6);
  CHECK(sim.collisions() == 0);
}

// Jinny's neck through the robot: BhNeckGesture writes the joint's position channel, the behavior
// loop fuses it, the simulated hardware applies it; after the gesture the channel holds.
TEST_CASE("Jinny's neck is driven through its command channel by the behavior loop", "[sim][joints][channels]") {
  const auto world = std::make_shared<const World>(load_world(kWorlds + "exhibit_hall.yaml"));
  SimClock clock;
  RobotPlugins plugins = builtin_plugins(world);
  RobotProfile profile = load_robot_profile(std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/jinny.yaml");
  // Its hardware, base and behaviors; not the guide application's HRI, nor the tasks that ask it.
  profile.hri.clear();
  profile.tasks.clear();
  profile.processes.clear();
  profile.recovery.clear();
  std::unique_ptr<Robot> robot = Robot::assemble(profile, plugins, clock);
  auto& hw = dynamic_cast<SimHardware&>(*robot->hardware());
  REQUIRE(hw.command_channels().find("neck").has_value());
  ControlLoop& loop = robot->behavior_loop();
  const ChannelId neck = *loop.coordinator().find_channel("neck");

  loop.activate(plugins.behaviors.create("BhNeckGesture"), {{"angle_deg", Value{30.0}}}, "BhNeckGesture");
  robot->run_for(std::chrono::milliseconds(100));
  CHECK(loop.coordinator().channel_output(neck).writer == "BhNeckGesture");
  robot->run_for(std::chrono::seconds(1));  // 60 deg/s: there in 0.5 s
  CHECK(hw.simulator().joints()[0].position_rad == Approx(30.0 * std::numbers::pi / 180.0));
  CHECK_FALSE(robot->behavior_active("BhNeckGesture"));  // not through the supervisor
  loop.deactivate(std::string_view("BhNeckGesture"));
  robot->run_for(std::chrono::seconds(1));
  CHECK_FALSE(loop.coordinator().channel_output(neck).live);
  CHECK(hw.simulator().joints()[0].position_rad == Approx(30.0 * std::numbers::pi / 180.0));  // held
}

// Other robots of a shared world (tripodal sim-server --robots N): discs the laser sees, the
// footprint stops against and the bumpers feel, counted apart from walls; and where N robots start.
TEST_CASE("sim: another robot of a shared world is seen by the laser, stops the body and presses a bumper") {
  World w = room_world(120, 80, {1.0, 2.0, 0.0});  // 6 m x 4 m, facing +x
  w.robot.laser = LaserConfig::sick_180();
  w.robot.laser.noise_stddev_m = 0.0;
  Simulator sim(w, omni3_base(), 1);
  const auto ahead = [&] {
    const LaserScan& s = sim.laser().latest();
    return s.ranges_m[s.ranges_m.size() / 2];  // the beam straight ahead (180 degrees, 361 beams)
  };
  sim.step(std::chrono::milliseconds(100));
  CHECK(ahead() == Approx(6.0 - 0.05 - 1.0).margin(0.06));  // the far wall
  const OtherBody other{{2.5, 2.0}, 0.25, 7};
  sim.set_other_bodies(std::span<const OtherBody>(&other, 1));
  sim.step(std::chrono::milliseconds(100));
  CHECK(ahead() == Approx(1.25).margin(0.01));  // its near side
  CHECK(sim.min_robot_clearance_m() == Approx(1.0).margin(1e-9));
  sim.command_twist({0.5, 0.0, 0.0});
  sim.step(std::chrono::seconds(4));
  CHECK(sim.pose().x_m == Approx(2.0).margin(0.01));  // touching: two radii between the centres
  CHECK(sim.collisions() == 1);
  CHECK(sim.robot_collisions() == 1);
  CHECK(sim.events().back().detail.find("with robot 7") != std::string::npos);
  CHECK(sim.bumpers().latest().pressed_mask != 0U);
  // Gone: the way is free again.
  sim.set_other_bodies({});
  sim.step(std::chrono::seconds(1));
  CHECK(sim.pose().x_m > 2.3);
  CHECK(sim.robot_collisions() == 1);
}

TEST_CASE("sim: the start poses of a shared world are free, apart, and refused when the map has no room") {
  const World w = room_world(120, 80, {1.0, 2.0, 0.0});
  const std::vector<Pose2D> p = fleet_start_poses(w, 6);
  REQUIRE(p.size() == 6);
  CHECK(p[0].x_m == 1.0);
  CHECK(p[0].y_m == 2.0);
  const SolidMap solid(w.grid);
  for (std::size_t i = 0; i < p.size(); ++i) {
    CHECK_FALSE(solid.disc_overlaps({p[i].x_m, p[i].y_m}, w.robot.radius_m));
    for (std::size_t j = 0; j < i; ++j)
      CHECK(std::hypot(p[i].x_m - p[j].x_m, p[i].y_m - p[j].y_m) >= 2 * w.robot.radius_m + 0.4 - 1e-9);
  }
  const World tiny = room_world(24, 24, {0.6, 0.6, 0.0});  // 1.2 m square: one robot only
  CHECK_THROWS_WITH(fleet_start_poses(tiny, 2), Contains("no room for 2 robots"));
}
