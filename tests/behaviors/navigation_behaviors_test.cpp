// BhAutoMove, BhCleaning, BhCleaningTwoWheel and BhGlobalLocalization driven on the ideal wheel
// hardware double through the real omni and differential controllers: the controller's
// odometry is the robot's pose (a perfect localizer), the behaviors' commands go through the
// controller's limits and kinematics.
#include "tripodal/behaviors/navigation_behaviors.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/sim/ray_caster.hpp"

using namespace tripodal;
using namespace std::chrono_literals;
using navi::Occupancy;
using navi::OccupancyGrid;
using navi::Point2D;

namespace {

// A w x h metre room (5 cm cells) with a one-cell wall, and optionally a square pillar.
OccupancyGrid room(double w_m, double h_m, bool pillar) {
  const int w = static_cast<int>(std::lround(w_m / 0.05)), h = static_cast<int>(std::lround(h_m / 0.05));
  OccupancyGrid g(w, h, 0.05, Pose2D{}, Occupancy::free);
  for (int x = 0; x < w; ++x) {
    g.set_state({x, 0}, Occupancy::occupied);
    g.set_state({x, h - 1}, Occupancy::occupied);
  }
  for (int y = 0; y < h; ++y) {
    g.set_state({0, y}, Occupancy::occupied);
    g.set_state({w - 1, y}, Occupancy::occupied);
  }
  if (pillar) {
    // 0.6 m x 1.6 m, standing from the bottom wall's side in the middle of the room
    for (int y = h / 2 - 16; y < h / 2 + 16; ++y) {
      for (int x = w / 2 - 6; x < w / 2 + 6; ++x) g.set_state({x, y}, Occupancy::occupied);
    }
  }
  return g;
}

navi::RegionMap regions_for(double w_m, double h_m) {
  navi::RegionMap r;
  r.rooms.push_back(navi::Region{"101", {{0, 0}, {w_m, 0}, {w_m, h_m}, {0, h_m}}, {}});
  r.nodes.push_back(navi::MapNode{"door", Pose2D{w_m - 0.6, h_m / 2, 0.0}, "", {}});
  return r;
}

ControllerConfig controller_config(bool omni) {
  ControllerConfig c;
  c.period = 10ms;
  c.limits.vx = AxisLimits{0.8, 1.5, {}, {}};
  c.limits.vy = AxisLimits{0.8, 1.5, {}, {}};
  c.limits.wz = AxisLimits{2.0, 4.0, {}, {}};
  if (omni) {
    c.type = "omni";
    const double angles[] = {std::numbers::pi / 3, std::numbers::pi, 5 * std::numbers::pi / 3};
    c.holonomic = omni_base(0.05, 0.22, angles);
  } else {
    c.type = "differential";
    c.differential = {0.42, 0.09};
  }
  return c;
}

// A robot on the ideal wheels: behaviors at 20 Hz, the controller at 100 Hz.
struct Rig {
  NaviWorkspace ws;
  IdealWheelHardware hw;
  std::unique_ptr<CController> controller;
  LaserResource laser{"laser", 500ms};
  ResourceTable table;
  NavigationData navi;
  BehaviorContext ctx;
  Time now{0};
  navi::CleanedCells truth_cleaned;  // from the controller's pose, independent of the behavior
  std::vector<Pose2D> trajectory;
  double max_turn_rate = 0.0;

  Rig(bool omni, OccupancyGrid grid, navi::RegionMap regions, Pose2D start, NaviWorkspaceOptions o = small_robot())
      : ws(std::move(grid), std::move(regions), o), hw(omni ? 3 : 2, 10ms), truth_cleaned(ws.grid()) {
    controller = default_controller_registry().create(controller_config(omni), hw);
    controller->reset_odometry(start);
    table.add(laser);
    ctx.period = 50ms;
    ctx.resources = &table;
    ctx.navi = &navi;
    ctx.base = controller->capabilities();
    publish();
  }
  static NaviWorkspaceOptions small_robot() {
    NaviWorkspaceOptions o;
    o.robot_radius_m = 0.2;
    o.cleaning_width_m = 0.45;  // the side brushes reach 2.5 cm beyond the body
    return o;
  }
  void publish() {
    navi.map_from_base = controller->odometry().pose;
    navi.pose_stamp = now;
    navi.localized = true;
    ctx.now = now;
  }
  // Steps `b` until it leaves running or max_s passes; returns the simulated seconds.
  double run(CBehavior& b, double max_s, const std::function<void()>& each = {}) {
    const Time start = now;
    while (b.running() && now - start < from_seconds(max_s)) {
      if (each) each();
      const auto cmd = b.step(ctx);
      for (int k = 0; k < 5; ++k) {
        controller->set_command(cmd.value_or(Twist2D{}), now);
        (void)controller->update(now);
        now += 10ms;
        const Pose2D p = controller->odometry().pose;
        if (!trajectory.empty()) {
          truth_cleaned.mark_segment({trajectory.back().x_m, trajectory.back().y_m}, {p.x_m, p.y_m}, ws.options().cleaning_width_m / 2);
        }
        trajectory.push_back(p);
        max_turn_rate = std::max(max_turn_rate, std::abs(controller->odometry().twist.wz_rad_s));
      }
      publish();
    }
    return to_seconds(now - start);
  }
  // The smallest clearance of the trajectory from physical obstacles.
  [[nodiscard]] double min_clearance() const {
    double best = 1e9;
    const auto& g = ws.grid();
    for (std::size_t k = 0; k < trajectory.size(); k += 10) {
      const Pose2D& p = trajectory[k];
      for (std::size_t i = 0; i < g.size(); ++i) {
        if (!g.is_occupied(g.cell(i))) continue;
        const Point2D c = g.cell_center(g.cell(i));
        best = std::min(best, std::hypot(c.x_m - p.x_m, c.y_m - p.y_m));
      }
    }
    return best;
  }
};

ParameterValues params(std::initializer_list<std::pair<const std::string, std::string>> kv) {
  ParameterValues v;
  for (const auto& [k, s] : kv) v.emplace(k, Value{s});
  return v;
}

// A scan (360 beams) with a return at `range_m` within +-half_width_rad of straight ahead.
LaserScan scan_with_obstacle_ahead(Time stamp, double range_m, double half_width_rad) {
  LaserScan s;
  s.stamp = stamp;
  s.angle_min_rad = -std::numbers::pi;
  s.angle_increment_rad = 2 * std::numbers::pi / 360;
  s.angle_max_rad = s.angle_min_rad + 359 * s.angle_increment_rad;
  s.range_min_m = 0.05;
  s.range_max_m = 12.0;
  s.ranges_m.assign(360, std::numeric_limits<float>::infinity());
  for (int i = 0; i < 360; ++i) {
    const double a = s.angle_min_rad + i * s.angle_increment_rad;
    if (std::abs(a) <= half_width_rad) s.ranges_m[static_cast<std::size_t>(i)] = static_cast<float>(range_m);
  }
  return s;
}

// The world as the laser sees it: the map plus boxes the map does not hold.
struct World {
  sim::SolidMap solid;
  sim::LaserModel lidar{sim::LaserConfig::rplidar_a1(), 5};
  std::vector<Point2D> box_cells;  // centres of the cells of the boxes
  explicit World(const OccupancyGrid& g) : solid(g) {}
  void box(const OccupancyGrid& g, double x0, double y0, double x1, double y1, bool solid_now = true) {
    for (int y = 0; y < g.height(); ++y) {
      for (int x = 0; x < g.width(); ++x) {
        const Point2D c = g.cell_center({x, y});
        if (c.x_m < x0 || c.x_m > x1 || c.y_m < y0 || c.y_m > y1) continue;
        solid.set_solid(x, y, solid_now);
        if (solid_now) box_cells.push_back(c);
      }
    }
    solid.refresh();
  }
  void scan_into(Rig& rig) {
    LaserScan scan;
    lidar.scan(solid, rig.controller->odometry().pose, rig.now, scan);
    rig.laser.publish(scan);
  }
  // Closest approach of the trajectory's centre to a box cell's centre.
  [[nodiscard]] double min_distance(const Rig& rig) const {
    double best = 1e9;
    for (const Pose2D& p : rig.trajectory) {
      for (const Point2D& c : box_cells) best = std::min(best, std::hypot(c.x_m - p.x_m, c.y_m - p.y_m));
    }
    return best;
  }
};

}  // namespace

TEST_CASE("NaviWorkspace: sections of a room, goal names, bad names", "[behaviors][navigation]") {
  NaviWorkspace ws(room(6.0, 4.0, true), regions_for(6.0, 4.0), Rig::small_robot());
  const auto sec = ws.sections_of_room("101");
  REQUIRE(sec.ok);
  REQUIRE_FALSE(sec.names.empty());
  CHECK(sec.names.front() == "A");
  const auto bad = ws.sections_of_room("999");
  CHECK_FALSE(bad.ok);
  CHECK_THAT(bad.error, Catch::Contains("unknown room '999'") && Catch::Contains("101"));
  const auto door = ws.resolve_goal("door", {1, 1});
  REQUIRE(door);
  CHECK(door->x_m == Approx(5.4));
  const auto entry = ws.resolve_goal("A.entry", {1, 1});
  REQUIRE(entry);
  // the entry is the first point of the balloon path: on round 0, tangent to the walls
  CHECK(ws.planner().traversable(ws.grid().cell_at(*entry)));
  CHECK_FALSE(ws.resolve_goal("Z.entry", {1, 1}));
  CHECK_FALSE(ws.resolve_goal("nowhere", {1, 1}));
}

TEST_CASE("BhAutoMove drives around an obstacle to a named goal, omni and differential", "[behaviors][navigation]") {
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    Rig rig(omni, room(6.0, 4.0, true), regions_for(6.0, 4.0), Pose2D{0.6, 2.0, 0.0});
    BhAutoMove b(rig.ws);
    b.activate(params({{"goal", "door"}}), rig.ctx);
    REQUIRE(b.running());
    REQUIRE(b.path().size() >= 3);  // the straight line crosses the pillar: corners around it
    const double t = rig.run(b, 120.0);
    CHECK(b.status() == BehaviorStatus::succeeded);
    const Pose2D end = rig.controller->odometry().pose;
    CHECK(std::hypot(end.x_m - 5.4, end.y_m - 2.0) <= 0.1);
    CHECK(rig.min_clearance() >= 0.2 - 0.03);  // the body never touched the pillar or a wall
    CHECK(t < 40.0);
    if (omni) CHECK(std::abs(end.theta_rad) < 0.05);  // translated, kept its heading
  }
}

TEST_CASE("BhAutoMove fails with a reason for an unknown or unreachable goal", "[behaviors][navigation]") {
  navi::RegionMap regions = regions_for(6.0, 4.0);
  regions.nodes.push_back(navi::MapNode{"inside_pillar", Pose2D{3.0, 2.0, 0.0}, "", {}});
  Rig rig(true, room(6.0, 4.0, true), regions, Pose2D{0.6, 2.0, 0.0});
  BhAutoMove b(rig.ws);
  b.activate(params({{"goal", "kitchen"}}), rig.ctx);
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "unknown goal");
  b.activate(params({{"goal", "inside_pillar"}}), rig.ctx);
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "no path to the goal");
  REQUIRE_THROWS_WITH(b.activate(params({{"goal", "door"}, {"max_speed_m_s", "-1"}}), rig.ctx, SourceLocation{"PrAutoMove.xml", 9, 5}),
                      Catch::Contains("PrAutoMove.xml:9:5: error: BhAutoMove: parameter 'max_speed_m_s'"));
}

TEST_CASE("BhAutoMove stops before an obstacle the laser sees and fails when blocked too long", "[behaviors][navigation]") {
  Rig rig(true, room(6.0, 4.0, false), regions_for(6.0, 4.0), Pose2D{0.6, 2.0, 0.0});
  BhAutoMove b(rig.ws);
  // Without planning around it (replan_after_s 0): the obstacle moves with the robot here.
  b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "3"}, {"replan_after_s", "0"}}), rig.ctx);
  REQUIRE(b.running());
  // Something not on the map 0.24 m ahead of the body's centre: 4 cm from the footprint.
  const double t = rig.run(b, 20.0, [&] { rig.laser.publish(scan_with_obstacle_ahead(rig.now, 0.24, 0.3)); });
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "path blocked");
  CHECK(t > 3.0);
  CHECK(t < 4.5);
  CHECK(rig.controller->odometry().pose.x_m < 0.7);  // it did not drive into it
  // Without the obstacle the same goal is reached.
  b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "3"}}), rig.ctx);
  (void)rig.run(b, 60.0, [&] { rig.laser.publish(scan_with_obstacle_ahead(rig.now, 20.0, 0.3)); });
  CHECK(b.status() == BehaviorStatus::succeeded);
}

TEST_CASE("BhAutoMove plans around a box the map does not hold, omni and differential", "[behaviors][navigation]") {
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    Rig rig(omni, room(6.0, 4.0, false), regions_for(6.0, 4.0), Pose2D{0.6, 2.0, 0.0});
    World world(rig.ws.grid());
    world.box(rig.ws.grid(), 2.75, 1.5, 3.25, 2.5);  // across the straight line to the door
    BhAutoMove b(rig.ws);
    b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "20"}}), rig.ctx);
    REQUIRE(b.path().size() == 2);  // the map is empty: straight at first
    const double t = rig.run(b, 120.0, [&] { world.scan_into(rig); });
    CHECK(b.status() == BehaviorStatus::succeeded);
    CHECK(b.replans() >= 1);
    CHECK(b.path().size() >= 3);  // the last plan has corners around the box
    // The body (radius 0.2 m) never entered the box: centre to cell centre >= 0.2 + half a cell - slack.
    CHECK(world.min_distance(rig) >= 0.2);
    CHECK(t < 60.0);
  }
}

TEST_CASE("BhAutoMove with no way around waits for blocked_timeout_s, or goes on when the way clears",
          "[behaviors][navigation]") {
  Rig rig(true, room(6.0, 4.0, false), regions_for(6.0, 4.0), Pose2D{0.6, 2.0, 0.0});
  World world(rig.ws.grid());
  world.box(rig.ws.grid(), 2.75, 0.0, 3.25, 4.0);  // wall to wall
  BhAutoMove b(rig.ws);
  b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "6"}, {"replan_after_s", "1"}}), rig.ctx);
  const double t = rig.run(b, 60.0, [&] { world.scan_into(rig); });
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "path blocked");
  CHECK(b.replans() >= 2);  // tried again while waiting
  // About 9 s to drive up to the box and stop (slowing from 0.4 m of clearance), then 6 s.
  CHECK(t > 6.0 + 6.0);
  CHECK(t < 6.0 + 14.0);
  CHECK(world.min_distance(rig) >= 0.2);
  // The same, but the obstacle goes away after 4 s of waiting (a cart pushed on): it arrives.
  b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "6"}, {"replan_after_s", "1"}}), rig.ctx);
  const Time start = rig.now;
  bool gone = false;
  (void)rig.run(b, 60.0, [&] {
    if (!gone && rig.now - start > 4s) {
      world.box(rig.ws.grid(), 2.75, 0.0, 3.25, 4.0, false);
      gone = true;
    }
    world.scan_into(rig);
  });
  CHECK(gone);
  CHECK(b.status() == BehaviorStatus::succeeded);
}

TEST_CASE("BhAutoMove is not stopped by the laser returns of walls and pillars the map holds", "[behaviors][navigation]") {
  Rig rig(true, room(6.0, 4.0, true), regions_for(6.0, 4.0), Pose2D{0.6, 2.0, 0.0});
  const sim::SolidMap solid(rig.ws.grid());
  sim::LaserModel lidar(sim::LaserConfig::rplidar_a1(), 5);
  BhAutoMove b(rig.ws);
  b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "2"}}), rig.ctx);
  LaserScan scan;
  (void)rig.run(b, 60.0, [&] {
    lidar.scan(solid, rig.controller->odometry().pose, rig.now, scan);
    rig.laser.publish(scan);
  });
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(rig.min_clearance() >= 0.2 - 0.03);
}

TEST_CASE("BhAutoMove pauses while the robot is not localized", "[behaviors][navigation]") {
  Rig rig(false, room(6.0, 4.0, false), regions_for(6.0, 4.0), Pose2D{0.6, 2.0, 0.0});
  BhAutoMove b(rig.ws);
  b.activate(params({{"goal", "door"}}), rig.ctx);
  rig.navi.localized = false;
  const auto cmd = b.step(rig.ctx);
  REQUIRE(cmd);
  CHECK(*cmd == Twist2D{});
  CHECK(b.running());
}

TEST_CASE("BhCleaning covers a section with the balloon path on the omni base, keeping its heading",
          "[behaviors][navigation][cleaning]") {
  Rig rig(true, room(5.0, 4.0, true), regions_for(5.0, 4.0), Pose2D{0.3, 0.3, 0.0});
  BhCleaning b(rig.ws);
  b.activate(params({{"section", "A"}}), rig.ctx);
  REQUIRE(b.running());
  const auto& prog = rig.ws.all_progress().at("A");
  CHECK(prog.plan.rounds >= 3);
  const double t = rig.run(b, 600.0);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(prog.finished);
  CHECK(b.section_coverage() >= 0.99);
  // Coverage of the reachable free cells measured on the true trajectory.
  const navi::Section& s = *rig.ws.section("A");
  navi::CleanedCells reach(rig.ws.grid());
  reach.mark_path(prog.plan.path, rig.ws.options().cleaning_width_m / 2);
  std::vector<std::size_t> reachable;
  for (auto i : s.cells) {
    if (reach.cleaned(i)) reachable.push_back(i);
  }
  CHECK(rig.truth_cleaned.coverage(reachable) >= 0.98);
  CHECK(rig.max_turn_rate < 0.2);  // an omni base never needs to turn
  CHECK(rig.min_clearance() >= 0.2 - 0.04);
  CHECK(t < 300.0);
}

TEST_CASE("BhCleaningTwoWheel covers the section on the differential base", "[behaviors][navigation][cleaning]") {
  Rig rig(false, room(5.0, 4.0, true), regions_for(5.0, 4.0), Pose2D{0.3, 0.3, 0.0});
  BhCleaningTwoWheel b(rig.ws);
  b.activate(params({{"section", "A"}}), rig.ctx);
  REQUIRE(b.running());
  (void)rig.run(b, 900.0);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(b.section_coverage() >= 0.98);
  CHECK(rig.max_turn_rate > 0.5);  // steering by heading
}

TEST_CASE("A cleaning behavior blocked by a box the map does not hold detours around it and finishes",
          "[behaviors][navigation][cleaning]") {
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    Rig rig(omni, room(5.0, 4.0, false), regions_for(5.0, 4.0), Pose2D{0.3, 0.3, 0.0});
    World world(rig.ws.grid());
    world.box(rig.ws.grid(), 2.2, 0.05, 2.8, 0.6);  // against the bottom wall, on the first rounds
    std::unique_ptr<CBehavior> b;
    if (omni) b = std::make_unique<BhCleaning>(rig.ws);
    else b = std::make_unique<BhCleaningTwoWheel>(rig.ws);
    b->activate(params({{"section", "A"}, {"blocked_timeout_s", "20"}}), rig.ctx);
    REQUIRE(b->running());
    (void)rig.run(*b, 900.0, [&] { world.scan_into(rig); });
    CHECK(b->status() == BehaviorStatus::succeeded);
    CHECK(world.min_distance(rig) >= 0.2);
    // What the box hides is lost, the rest of the section is cleaned (the box and the ring
    // around it where the body cannot go are about 5 % of the section).
    CHECK(dynamic_cast<CCleaningBehavior&>(*b).section_coverage() >= 0.85);
  }
  // Without replanning the same run ends in "path blocked".
  Rig rig(true, room(5.0, 4.0, false), regions_for(5.0, 4.0), Pose2D{0.3, 0.3, 0.0});
  World world(rig.ws.grid());
  world.box(rig.ws.grid(), 2.2, 0.05, 2.8, 0.6);
  BhCleaning b(rig.ws);
  b.activate(params({{"section", "A"}, {"blocked_timeout_s", "5"}, {"replan_after_s", "0"}}), rig.ctx);
  (void)rig.run(b, 900.0, [&] { world.scan_into(rig); });
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "path blocked");
}

TEST_CASE("Cleaning behaviors refuse what they cannot do", "[behaviors][navigation][cleaning]") {
  Rig rig(false, room(5.0, 4.0, false), regions_for(5.0, 4.0), Pose2D{0.3, 0.3, 0.0});
  BhCleaning omni_only(rig.ws);
  omni_only.activate(params({{"section", "A"}}), rig.ctx);
  CHECK(omni_only.status() == BehaviorStatus::failed);
  CHECK(omni_only.failure_reason() == "BhCleaning needs an omni-directional base");
  BhCleaningTwoWheel b(rig.ws);
  b.activate(params({{"section", "Q"}}), rig.ctx);
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "unknown section");
  REQUIRE_THROWS_WITH(b.activate(params({{"section", "A"}, {"speed", "1"}}), rig.ctx, SourceLocation{"PrCleaning.xml", 20, 6}),
                      Catch::Contains("PrCleaning.xml:20:6: error: BhCleaningTwoWheel: unknown parameter 'speed'"));
}

TEST_CASE("A cleaning interrupted and activated again resumes where it paused", "[behaviors][navigation][cleaning]") {
  Rig rig(true, room(5.0, 4.0, false), regions_for(5.0, 4.0), Pose2D{0.3, 0.3, 0.0});
  BhCleaning b(rig.ws);
  b.activate(params({{"section", "A"}}), rig.ctx);
  (void)rig.run(b, 30.0);
  REQUIRE(b.running());
  const auto& prog = rig.ws.all_progress().at("A");
  const double done = prog.done_m;
  CHECK(done > 5.0);
  // Lost: the behavior stands still and marks nothing.
  rig.navi.localized = false;
  const std::size_t cleaned = rig.ws.cleaned().count();
  for (int k = 0; k < 10; ++k) {
    const auto cmd = b.step(rig.ctx);
    REQUIRE(cmd);
    CHECK(*cmd == Twist2D{});
  }
  CHECK(rig.ws.cleaned().count() == cleaned);
  b.deactivate();
  rig.navi.localized = true;
  b.activate(params({{"section", "A"}}), rig.ctx);
  CHECK(prog.done_m == Approx(done));
  const double t = rig.run(b, 600.0);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(b.section_coverage() >= 0.99);
  // the remaining part only: well under the whole path's duration at 0.3 m/s
  CHECK(t < (prog.plan.stats.length_m - done) / 0.3 * 1.6 + 5.0);
}

TEST_CASE("BhGlobalLocalization turns until the localizer accepts a fix, or gives up", "[behaviors][navigation]") {
  Rig rig(true, room(5.0, 4.0, false), regions_for(5.0, 4.0), Pose2D{1.0, 1.0, 0.0});
  int attempts = 0;
  rig.ws.set_relocalizer([&](Time now) {
    ++attempts;
    return to_seconds(now) >= 5.0;
  });
  BhGlobalLocalization b(rig.ws);
  b.activate(ParameterValues{}, rig.ctx);
  const double t = rig.run(b, 60.0);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(t == Approx(6.0).margin(0.06));  // attempts every 2 s: 2, 4 fail, 6 succeeds
  CHECK(attempts == 3);
  CHECK(std::abs(rig.controller->odometry().pose.theta_rad) > 0.5);  // it turned meanwhile
  rig.ws.set_relocalizer([](Time) { return false; });
  b.activate(params({{"timeout_s", "5"}}), rig.ctx);
  (void)rig.run(b, 60.0);
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "no position found");
}

TEST_CASE("register_navigation_behaviors registers the four behaviors by name", "[behaviors][navigation]") {
  NaviWorkspace ws(room(5.0, 4.0, false), regions_for(5.0, 4.0), Rig::small_robot());
  BehaviorRegistry reg;
  register_navigation_behaviors(reg, ws);
  CHECK(reg.names() == std::vector<std::string>{"BhAutoMove", "BhCleaning", "BhCleaningTwoWheel", "BhGlobalLocalization"});
  for (const auto& n : reg.names()) {
    auto b = reg.create(n);
    CHECK(b->name() == n);
    for (const auto& p : b->manifest().parameters) CHECK_FALSE(p.description.empty());
  }
  REQUIRE_THROWS_WITH(reg.create("BhClean"), Catch::Contains("unknown behavior type 'BhClean'; known: BhAutoMove, BhCleaning, "
                                                             "BhCleaningTwoWheel, BhGlobalLocalization; did you mean 'BhCleaning'?"));
}
