// The disinfection robot's safety reflexes end to end (issue 35, item 2): configs/robots/
// disinfection.yaml on the simulated board in the safety ward (configs/worlds/safety_ward.yaml), a
// room with a stairwell and a glass partition its map does not hold. Every sensor reading crosses
// the board's line; the cliff bits are the simulated firmware's judgments (ADC differences).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/board/board_monitor.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_board.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";

// Distance from p to the axis-aligned rectangle [x0, x1] x [y0, y1] (0 inside).
double to_rectangle(double px, double py, double x0, double y0, double x1, double y1) {
  const double dx = std::max({x0 - px, 0.0, px - x1});
  const double dy = std::max({y0 - py, 0.0, py - y1});
  return std::hypot(dx, dy);
}

// The disinfection robot in a ward world, its odometry at the world's start. The reflexes are
// under test, not the dose: the lanes as without a dose target (the dose plan's slow, close lanes
// are tests/app's tripodal_run_cli:disinfection_reaches_dose_2111).
// `profile`: the robot profile under configs/robots; the lidar one's scan-matching localizer starts
// at the world's start pose.
std::unique_ptr<Robot> ward_robot(const sim::World& world, const RobotPlugins& plugins, SimClock& clock,
                                  const std::string& profile = "disinfection.yaml",
                                  const std::vector<ParameterOverride>& overrides = {}) {
  RobotOptions ro;
  ro.parameters.push_back({"coverage", "dose_target_j_m2", "0"});
  ro.parameters.insert(ro.parameters.end(), overrides.begin(), overrides.end());
  if (profile == "disinfection_lidar.yaml") {
    ro.parameters.push_back({"localizer", "initial_x_m", std::to_string(world.start_pose.x_m)});
    ro.parameters.push_back({"localizer", "initial_y_m", std::to_string(world.start_pose.y_m)});
    ro.parameters.push_back({"localizer", "initial_theta_rad", std::to_string(world.start_pose.theta_rad)});
  }
  auto robot = Robot::assemble(load_robot_profile(kConfigs / "robots" / profile), plugins, clock, ro);
  if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(world.start_pose);
  return robot;
}

struct WardRun {
  std::uint64_t seed = 1;
  bool fell = false;
  std::uint64_t contacts = 0;  // every contact of the footprint (walls, glass)
  std::uint64_t glass_contacts = 0;
  int cliff_detections = 0;        // rising edges of the board's cliff bits
  double glass_clearance_m = 1e9;  // closest the footprint came to the glass
  double ledge_clearance_m = 1e9;  // closest a wheel came to the stairwell's edge
  TaskState state = TaskState::idle;
  std::string reason;
  double duration_s = 0.0;
};

// "disinfect the room ward" in the safety ward, with the world's seed (and `edit` applied).
WardRun run_ward(std::uint64_t seed, double max_s, const std::function<void(sim::World&)>& edit = {},
                 const std::string& profile = "disinfection.yaml") {
  sim::World w = sim::load_world(kConfigs / "worlds/safety_ward.yaml");
  w.seed = seed;
  // The simulated board's sensors are exact and the localizer is the ground truth, so the seed
  // alone would change little: it also places the robot, within 0.3 m and 0.5 rad of the world's
  // start pose, so every seed drives its own coverage.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> offset(-0.3, 0.3), turn(-0.5, 0.5);
  w.start_pose = {w.start_pose.x_m + offset(rng), w.start_pose.y_m + offset(rng), w.start_pose.theta_rad + turn(rng)};
  if (edit) edit(w);
  const auto world = std::make_shared<const sim::World>(std::move(w));
  SimClock clock;
  RobotPlugins plugins = builtin_plugins(world);
  auto robot = ward_robot(*world, plugins, clock, profile);
  auto& hw = dynamic_cast<sim::SimBoardHardware&>(*robot->hardware());
  robot->run_for(100ms);
  const CommandAnswer answer = robot->command("disinfect the room ward");
  INFO(answer.text);
  REQUIRE(answer.accepted);

  WardRun out;
  out.seed = seed;
  const sim::Simulator& sim = hw.simulator();
  const Time start = clock.now();
  const Time end = start + from_seconds(max_s);
  std::uint32_t last_bits = 0;
  const double half = 0.21;  // the wheels' contact points, either side of the centre
  while (robot->planner().busy() && clock.now() < end && !sim.fallen()) {
    robot->run_for(10ms);
    const Pose2D& p = sim.pose();
    out.glass_clearance_m = std::min(out.glass_clearance_m, to_rectangle(p.x_m, p.y_m, 2.0, 2.4, 2.06, 4.0) - 0.25);
    for (const double side : {half, -half}) {
      const double wx = p.x_m - std::sin(p.theta_rad) * side, wy = p.y_m + std::cos(p.theta_rad) * side;
      out.ledge_clearance_m = std::min(out.ledge_clearance_m, to_rectangle(wx, wy, 3.5, 0.0, 5.0, 1.4));
    }
    const std::uint32_t bits =
        hw.board().link().has_drive() ? (hw.board().link().drive().sensors >> board::kCliffShift) & 0xFFU : 0U;
    if (bits != 0 && last_bits == 0) ++out.cliff_detections;
    last_bits = bits;
  }
  out.fell = sim.fallen();
  out.contacts = sim.collisions();
  out.glass_contacts = sim.sonar_only_collisions();
  out.state = robot->planner().report().state;
  out.reason = robot->planner().report().reason;
  out.duration_s = to_seconds(clock.now() - start);
  return out;
}

std::string describe(const WardRun& r) {
  return "seed " + std::to_string(r.seed) + ": " + (r.fell ? "FELL" : "no fall") + ", " + std::to_string(r.contacts) +
         " contacts (" + std::to_string(r.glass_contacts) + " glass), " + std::to_string(r.cliff_detections) +
         " cliff detections, closest wheel to the ledge " + std::to_string(r.ledge_clearance_m) + " m, footprint to the glass " +
         std::to_string(r.glass_clearance_m) + " m, task " + std::string(to_string(r.state)) +
         (r.reason.empty() ? "" : " (" + r.reason + ")") + " after " + std::to_string(r.duration_s) + " s";
}

// Straight at them, at 0.4 m/s (faster than the cleaning behavior drives): BhGoToPose on the
// behavior loop's input of BhAutoMove, a goal beyond the glass or down the stairwell, the robot's
// three reflexes active as its profile has them. It is stopped, backed off, held, and tries again
// when the hold ends, for 30 s: every approach must end short.
struct Approach {
  bool fell = false;
  std::uint64_t contacts = 0;
  int cliff_detections = 0;
  double glass_clearance_m = 1e9, ledge_clearance_m = 1e9;
  double max_x_m = -1e9;
};

Approach drive_at(Pose2D start, Pose2D goal, const std::function<void(sim::World&)>& edit = {},
                  const std::string& profile = "disinfection.yaml") {
  sim::World w = sim::load_world(kConfigs / "worlds/safety_ward.yaml");
  w.start_pose = start;
  if (edit) edit(w);
  const auto world = std::make_shared<const sim::World>(std::move(w));
  SimClock clock;
  RobotPlugins plugins = builtin_plugins(world);
  auto robot = ward_robot(*world, plugins, clock, profile);
  auto& hw = dynamic_cast<sim::SimBoardHardware&>(*robot->hardware());
  robot->run_for(300ms);  // SYNC, the first ultrasonic reading
  (void)robot->behavior_loop().activate(plugins.behaviors.create("BhGoToPose"),
                                        ParameterValues{{"goal_x_m", Value{goal.x_m}},
                                                        {"goal_y_m", Value{goal.y_m}},
                                                        {"goal_theta_rad", Value{goal.theta_rad}},
                                                        {"frame", Value{std::string("map")}},
                                                        {"max_speed_m_s", Value{0.4}}},
                                        "BhAutoMove");
  Approach out;
  const sim::Simulator& sim = hw.simulator();
  std::uint32_t last_bits = 0;
  for (int k = 0; k < 3000 && !sim.fallen(); ++k) {
    robot->run_for(10ms);
    const Pose2D& p = sim.pose();
    out.max_x_m = std::max(out.max_x_m, p.x_m);
    out.glass_clearance_m = std::min(out.glass_clearance_m, to_rectangle(p.x_m, p.y_m, 2.0, 2.4, 2.06, 4.0) - 0.25);
    for (const double side : {0.21, -0.21}) {
      out.ledge_clearance_m =
          std::min(out.ledge_clearance_m,
                   to_rectangle(p.x_m - std::sin(p.theta_rad) * side, p.y_m + std::cos(p.theta_rad) * side, 3.5, 0.0, 5.0, 1.4));
    }
    const std::uint32_t bits =
        hw.board().link().has_drive() ? (hw.board().link().drive().sensors >> board::kCliffShift) & 0xFFU : 0U;
    if (bits != 0 && last_bits == 0) ++out.cliff_detections;
    last_bits = bits;
  }
  out.fell = sim.fallen();
  out.contacts = sim.collisions();
  return out;
}

}  // namespace

TEST_CASE("safety ward: driven straight at the glass, the ultrasonic stops the robot short of it", "[board][safety]") {
  const Approach a = drive_at({0.8, 3.2, 0.0}, {3.5, 3.2, 0.0});
  WARN("straight at the glass: closest " << a.glass_clearance_m << " m, " << a.contacts << " contacts");
  CHECK(a.contacts == 0);
  CHECK(a.glass_clearance_m > 0.0);
  CHECK(a.glass_clearance_m < 0.3);  // it did drive up to it
}

TEST_CASE("safety ward: driven straight down the stairwell, the cliff sensors stop it every time", "[board][safety]") {
  const Approach a = drive_at({2.3, 0.7, 0.0}, {4.5, 0.7, 0.0});
  WARN("straight at the ledge: " << a.cliff_detections << " detections, closest wheel " << a.ledge_clearance_m << " m");
  CHECK_FALSE(a.fell);
  CHECK(a.cliff_detections >= 2);  // stopped, backed off, held, tried again, stopped again
  CHECK(a.ledge_clearance_m > 0.0);
  // Obliquely (30 degrees off the edge's normal), the side sensors see it first.
  const Approach b = drive_at({2.3, 0.35, 0.5236}, {4.5, 1.6, 0.5236});
  WARN("obliquely at the ledge: " << b.cliff_detections << " detections, closest wheel " << b.ledge_clearance_m << " m");
  CHECK_FALSE(b.fell);
  CHECK(b.cliff_detections >= 1);
}

TEST_CASE(
    "safety ward: the front cliff sensor stuck at 'floor', driven straight down the stairwell, the others "
    "stop it",
    "[board][safety][faults]") {
  const auto stuck = [](sim::World& w) { w.faults.stuck_cliff.push_back({0, false, {}}); };
  const Approach a = drive_at({2.3, 0.7, 0.0}, {4.5, 0.7, 0.0}, stuck);
  WARN("front cliff sensor stuck at floor, straight at the ledge: " << a.cliff_detections << " detections, closest wheel "
                                                                    << a.ledge_clearance_m << " m");
  CHECK_FALSE(a.fell);
  CHECK(a.cliff_detections >= 1);
  CHECK(a.ledge_clearance_m > 0.0);
  // The same robot driven at the glass: the cliff fault changes nothing there.
  const Approach g = drive_at({0.8, 3.2, 0.0}, {3.5, 3.2, 0.0}, stuck);
  CHECK(g.contacts == 0);
}

TEST_CASE(
    "safety ward: the disinfection robot never falls down the stairwell and never touches the glass, seeds "
    "1-10",
    "[board][safety]") {
  int falls = 0;
  std::uint64_t contacts = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const WardRun r = run_ward(seed, 900.0);
    WARN(describe(r));
    falls += r.fell ? 1 : 0;
    contacts += r.contacts;
    CHECK_FALSE(r.fell);
    CHECK(r.contacts == 0);
    CHECK(r.cliff_detections > 0);  // the reflex was needed: the coverage drives to the ledge
    CHECK(r.ledge_clearance_m > 0.0);
    CHECK(r.glass_clearance_m > 0.0);
  }
  WARN("safety ward, seeds 1-10: " << falls << " falls, " << contacts << " contacts");
}

// Injected fault: the front cliff sensor stuck at the floor's reading. The four others still see
// the stairwell before a wheel reaches it; the glass, which the cliff sensors have nothing to do
// with, is still never touched (the ultrasonic cones, the bump switches behind them).
TEST_CASE("safety ward: with the front cliff sensor stuck at 'floor' the other sensors still stop it",
          "[board][safety][faults]") {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const WardRun r = run_ward(seed, 900.0, [](sim::World& w) { w.faults.stuck_cliff.push_back({0, false, {}}); });
    WARN("front cliff sensor stuck at floor, " << describe(r));
    CHECK_FALSE(r.fell);
    CHECK(r.glass_contacts == 0);
    CHECK(r.contacts == 0);
    CHECK(r.cliff_detections > 0);
  }
}

namespace {

// The glass as the simulator holds it: the 0.05 m grid's cells whose centres lie inside the world
// file's [2.0, 2.06] x [2.4, 4.0], so its east face is at x = 2.05.
double gap_to_glass(const Pose2D& p) {
  return to_rectangle(p.x_m, p.y_m, 2.0, 2.4, 2.05, 4.0) - 0.25;
}

struct SideBump {
  bool bumped = false;            // a side switch pressed (the board's bump bits)
  double gap_at_bump_m = 1e9;     // the body's gap to the glass then
  double gap_after_back_m = 0.0;  // ... the most while the reflex backed off (the 1.5 s after)
  int pressed_while_backing = 0;  // control periods the side switch stayed pressed in those 1.5 s
  double min_gap_m = 1e9;
  std::uint64_t contacts = 0;
  int side_bumps = 0;          // side switch presses (rising edges) in all
  double past_glass_s = -1.0;  // when the body was past the glass's lower end (-1: not in 30 s)
};

// Driven along the glass's east face toward its lower end, converging on it by 0.07 rad (the
// glass on the robot's right, beside it, outside the ultrasonic cones), with BhGoToPose as in
// drive_at but at 0.15 m/s (beside the glass the sonar does not slow it, and a bump switch with a
// 5 mm margin stops the robot short of a touch only from a walking pace; faster, the bump is a
// touch by nature): the right bump switch is pressed at the side. What happens in the 1.5 s after, and
// whether the robot gets past the glass's lower end within 30 s.
SideBump drive_along_glass(const std::vector<ParameterOverride>& overrides = {}) {
  sim::World w = sim::load_world(kConfigs / "worlds/safety_ward.yaml");
  const double gx = 2.22, gy = 1.8;  // the goal, below the glass's lower end
  w.start_pose = {2.36, 3.6, std::atan2(gy - 3.6, gx - 2.36)};
  const auto world = std::make_shared<const sim::World>(std::move(w));
  SimClock clock;
  RobotPlugins plugins = builtin_plugins(world);
  auto robot = ward_robot(*world, plugins, clock, "disinfection.yaml", overrides);
  auto& hw = dynamic_cast<sim::SimBoardHardware&>(*robot->hardware());
  robot->run_for(300ms);
  (void)robot->behavior_loop().activate(plugins.behaviors.create("BhGoToPose"),
                                        ParameterValues{{"goal_x_m", Value{gx}},
                                                        {"goal_y_m", Value{gy}},
                                                        {"goal_theta_rad", Value{-std::numbers::pi / 2}},
                                                        {"frame", Value{std::string("map")}},
                                                        {"max_speed_m_s", Value{0.15}}},
                                        "BhAutoMove");
  SideBump out;
  const sim::Simulator& sim = hw.simulator();
  Time bump_at{};
  const Time start = clock.now();
  bool was_side = false;
  for (int k = 0; k < 3000 && out.past_glass_s < 0.0; ++k) {
    robot->run_for(10ms);
    const double gap = gap_to_glass(sim.pose());
    out.min_gap_m = std::min(out.min_gap_m, gap);
    const std::uint32_t bumps = hw.board().link().has_drive() ? hw.board().link().drive().sensors & 0xFFU : 0U;
    const bool side = (bumps & 0xAU) != 0;  // sector 1 (left) or 3 (right) of the four
    out.side_bumps += side && !was_side ? 1 : 0;
    was_side = side;
    if (side && !out.bumped) {
      out.bumped = true;
      bump_at = clock.now();
      out.gap_at_bump_m = gap;
    }
    if (out.bumped && clock.now() > bump_at && clock.now() - bump_at <= 1500ms) {
      out.pressed_while_backing += side ? 1 : 0;
      out.gap_after_back_m = std::max(out.gap_after_back_m, gap);
    }
    if (sim.pose().y_m < 2.4 - 0.25) out.past_glass_s = to_seconds(clock.now() - start);
  }
  out.contacts = sim.collisions();
  return out;
}

}  // namespace

// Driving beside the glass, a switch on the side pressed: straight back (the reflex as it was)
// slides the body along the glass, millimetres clear of it. Backing along an arc away from the side
// moves it off: more than 4 cm clear within 1.5 s of the bump (straight: under 2 cm).
TEST_CASE("safety ward: a side bump beside the glass backs the robot off the glass, not along it", "[board][safety]") {
  const SideBump b = drive_along_glass();
  WARN("side bump beside the glass: gap " << b.gap_at_bump_m * 1000.0 << " mm at the bump, at most "
                                          << b.gap_after_back_m * 1000.0 << " mm in the 1.5 s after, the switch pressed "
                                          << b.pressed_while_backing << " periods of 150, closest " << b.min_gap_m * 1000.0
                                          << " mm, " << b.contacts << " contacts; " << b.side_bumps
                                          << " side bumps, past the glass after " << b.past_glass_s << " s");
  REQUIRE(b.bumped);
  CHECK(b.gap_at_bump_m < 0.006);  // the switch's 5 mm margin
  CHECK(b.contacts == 0);
  CHECK(b.min_gap_m > 0.0);
  CHECK(b.gap_after_back_m > 0.04);
  // The way on, along the glass, is not held: past its end (straight back and a hold until the
  // robot turned 1 rad, as before, it stood there until BhGoToPose's goal was given up).
  CHECK(b.past_glass_s > 0.0);
  // The reflex as it was, straight back (an arc of 0 rad): along the glass.
  const SideBump straight = drive_along_glass({{"BhBumperGuard", "side_turn_rad", "0"}});
  WARN("backed straight: gap " << straight.gap_at_bump_m * 1000.0 << " mm at the bump, at most "
                               << straight.gap_after_back_m * 1000.0 << " mm in the 1.5 s after, the switch pressed "
                               << straight.pressed_while_backing << " periods");
  REQUIRE(straight.bumped);
  CHECK(straight.gap_after_back_m < 0.02);
}

// Issue 35's closing note: the lidar profile had no safety reflexes, so its robot drove down the
// stairwell its lidar looks over. Now the same guards as disinfection.yaml's stop it short.
TEST_CASE("safety ward: the lidar profile's robot, driven straight down the stairwell, does not fall", "[board][safety]") {
  const Approach a = drive_at({2.3, 0.7, 0.0}, {4.5, 0.7, 0.0}, {}, "disinfection_lidar.yaml");
  WARN("lidar profile straight at the ledge: " << a.cliff_detections << " detections, closest wheel " << a.ledge_clearance_m
                                               << " m, " << (a.fell ? "FELL" : "no fall"));
  CHECK_FALSE(a.fell);
  CHECK(a.cliff_detections >= 1);
  CHECK(a.ledge_clearance_m > 0.0);
  // And at the glass its lidar sees through: the ultrasonic stops it short.
  const Approach g = drive_at({0.8, 3.2, 0.0}, {3.5, 3.2, 0.0}, {}, "disinfection_lidar.yaml");
  WARN("lidar profile straight at the glass: closest " << g.glass_clearance_m << " m, " << g.contacts << " contacts");
  CHECK(g.contacts == 0);
  CHECK(g.glass_clearance_m > 0.0);
}
