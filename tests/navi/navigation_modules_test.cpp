// The sequencing layer's navigation modules (GridMaps, SectionSplitter, GroundTruthLocalizer, PathPlanner,
// CoveragePlanner) serving the path-following behaviors: first the pieces on their own (published
// paths, replanning, goal names, coverage resume), then a whole small robot on the simulator, its
// process supervisor running a one-place net that binds the behavior under test, with the modules
// planning, replanning and recording in closed loop.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "navi_test_util.hpp"
#include "tripodal/behaviors/navigation_behaviors.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;
using namespace std::chrono_literals;
using navi::Occupancy;
using navi::OccupancyGrid;
using navi::Point2D;

namespace {

const std::filesystem::path kRobots = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs/robots";

// The simulated body, and the planning footprint: 5 cm more (a cell of the map), as the repo's
// profiles do, so that a path tangent to the inflated walls keeps the body off them.
constexpr double kRadius_m = 0.2;
constexpr double kPlanningRadius_m = 0.25;
constexpr double kCleaningWidth_m = 0.45;  // the side brushes reach 2.5 cm beyond the body

// A w x h metre room (5 cm cells) with a one-cell wall, and optionally a 0.6 m x 1.6 m pillar in
// its middle.
OccupancyGrid room(double w_m, double h_m, bool pillar) {
  const int w = static_cast<int>(std::lround(w_m / 0.05)), h = static_cast<int>(std::lround(h_m / 0.05));
  OccupancyGrid g = navi::test::room(w, h);
  if (pillar) {
    for (int y = h / 2 - 16; y < h / 2 + 16; ++y) {
      for (int x = w / 2 - 6; x < w / 2 + 6; ++x) g.set_state({x, y}, Occupancy::occupied);
    }
  }
  return g;
}

// Room "101" is the whole map; the node "door" stands before its right wall.
navi::RegionMap regions_for(double w_m, double h_m) {
  navi::RegionMap r;
  r.rooms.push_back(navi::Region{"101", {{0, 0}, {w_m, 0}, {w_m, h_m}, {0, h_m}}, {}});
  r.nodes.push_back(navi::MapNode{"door", Pose2D{w_m - 0.6, h_m / 2, 0.0}, "", {}});
  return r;
}

// A box the map does not hold, present from the start; gone_s: when it is taken away.
struct Box {
  double x0_m, y0_m, x1_m, y1_m;
  std::optional<double> gone_s;
};

sim::World world(double w_m, double h_m, bool pillar, Pose2D start, const std::vector<Box>& boxes = {}) {
  sim::World w;
  w.grid = room(w_m, h_m, pillar);
  w.regions = regions_for(w_m, h_m);
  w.start_pose = start;
  w.robot.radius_m = kRadius_m;
  w.robot.laser.noise_stddev_m = 0.0;
  w.robot.odometry.noise_ratio = 0.0;
  w.robot.gyro.noise_stddev_rad_s = 0.0;
  for (const Box& b : boxes) {
    sim::DynamicObstacle o;
    o.name = "box" + std::to_string(w.obstacles.size());
    o.polygon = {{b.x0_m, b.y0_m}, {b.x1_m, b.y0_m}, {b.x1_m, b.y1_m}, {b.x0_m, b.y1_m}};
    if (b.gone_s) o.disappear = time_from_seconds(*b.gone_s);
    w.obstacles.push_back(std::move(o));
  }
  return w;
}

// ---------------------------------------------------------------------------------------------
// The modules on their own, wired as a robot wires them.

struct Modules final : public ModuleDirectory {
  std::unique_ptr<navi::CGridMaps> maps = std::make_unique<navi::CGridMaps>();
  std::unique_ptr<navi::CSectionSplitter> splitter = std::make_unique<navi::CSectionSplitter>();
  std::unique_ptr<navi::CCoveragePlanner> coverage = std::make_unique<navi::CCoveragePlanner>();
  std::unique_ptr<navi::CPathPlanner> planner = std::make_unique<navi::CPathPlanner>();
  NavigationData navigation;
  std::uint32_t path_ids = 0;

  Modules(double w_m, double h_m, bool pillar, const std::vector<navi::MapNode>& more_nodes = {}) {
    navi::RegionMap regions = regions_for(w_m, h_m);
    regions.nodes.insert(regions.nodes.end(), more_nodes.begin(), more_nodes.end());
    maps->set_map(room(w_m, h_m, pillar), std::move(regions));
    maps->configure({{"robot_radius_m", Value{kPlanningRadius_m}}});
    splitter->configure();
    coverage->configure({{"cleaning_width_m", Value{kCleaningWidth_m}}});
    planner->configure();
    ModuleContext c = context(Time{});
    for (CModule* m : all()) m->start(c);
    navigation.localized = true;
  }
  [[nodiscard]] std::vector<CModule*> all() const override {
    return {maps.get(), splitter.get(), coverage.get(), planner.get()};
  }
  ModuleContext context(Time now, const NavigationFeedback& feedback = {}) {
    ModuleContext c;
    c.now = now;
    c.navigation = &navigation;
    c.modules = this;
    c.path_ids = &path_ids;
    c.feedback = feedback;
    return c;
  }
  // What the robot does when its supervisor (de)activates a behavior, and every sequencing period.
  void activated(const ModuleManifest& behavior, const ParameterValues& params, Time now) {
    const BehaviorActivation a{behavior.name, params, now, &behavior};
    ModuleContext c = context(now);
    for (CModule* m : all()) m->behavior_activated(a, c);
  }
  void deactivated(std::string_view behavior, Time now) {
    ModuleContext c = context(now);
    for (CModule* m : all()) m->behavior_deactivated(behavior, c);
  }
  void update(Time now, const NavigationFeedback& feedback) {
    ModuleContext c = context(now, feedback);
    for (CModule* m : all()) m->update(c);
  }
};

}  // namespace

namespace {

// ---------------------------------------------------------------------------------------------
// A whole small robot on the simulator: the sim hardware in a world built here, the omni or
// differential base of the repo's reactive configurations, the five navigation modules, and one
// process per task: a net whose one place binds the behavior with the task's parameters, and
// whose success is the behavior's ".done". A failure of the behavior fails the process with its
// reason ("behavior BhAutoMove failed: path blocked").

struct Task {
  std::string behavior;
  std::vector<std::pair<std::string, std::string>> params;
};

std::string task_net(const std::string& id, const Task& t) {
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  xml += "<net id=\"" + id + "\" level=\"low\" version=\"1\" description=\"one behavior\">\n";
  xml += "  <place id=\"P0\" tokens=\"1\"/>\n";
  xml += "  <place id=\"P1\">\n";
  xml += "    <behavior name=\"" + t.behavior + "\">\n";
  for (const auto& [k, v] : t.params) xml += "      <param name=\"" + k + "\" value=\"" + v + "\"/>\n";
  xml += "    </behavior>\n";
  xml += "  </place>\n";
  xml += "  <place id=\"P2\" outcome=\"success\"/>\n";
  xml += "  <transition id=\"t0\"/>\n";
  xml += "  <transition id=\"t1\" event=\"" + t.behavior + ".done\"/>\n";
  xml += "  <arc source=\"P0\" target=\"t0\"/>\n";
  xml += "  <arc source=\"t0\" target=\"P1\"/>\n";
  xml += "  <arc source=\"P1\" target=\"t1\"/>\n";
  xml += "  <arc source=\"t1\" target=\"P2\"/>\n";
  return xml + "</net>\n";
}

// `localizer`: more parameters of the GroundTruthLocalizer (", faults: 0-5"). The nets of the tasks are
// `folder`/task<i>.xml.
std::string profile(bool omni, const std::string& localizer, const std::filesystem::path& folder,
                    std::size_t tasks) {
  std::string y = "robot: {name: navtest}\n";
  y += "hardware: {type: sim}\n";
  y += "controllers:\n";
  if (omni) {
    y += "  - {name: base, type: omni, parameters: {config: ../reactive/psr_omni.yaml}}\n";
  } else {
    y += "  - {name: base, type: differential, parameters: {config: ../reactive/jinny_differential.yaml}}\n";
  }
  y += "loops:\n";
  y += "  - {name: motion, period_s: 0.01, controller: base}\n";
  y += "navigation:\n";
  y += "  - {name: maps, type: GridMaps, parameters: {robot_radius_m: 0.25}}\n";
  y += "  - {name: localizer, type: GroundTruthLocalizer, parameters: {noise_xy_m: 0, noise_theta_rad: 0" + localizer + "}}\n";
  y += "  - {name: section_splitter, type: SectionSplitter}\n";
  y += "  - {name: path_planner, type: PathPlanner}\n";
  y += "  - {name: coverage, type: CoveragePlanner, parameters: {cleaning_width_m: 0.45}}\n";
  y += "behaviors: [BhAutoMove, BhCleaning, BhCleaningTwoWheel, BhGlobalLocalization]\n";
  if (tasks > 0) y += "processes:\n";
  for (std::size_t i = 0; i < tasks; ++i) {
    const std::string id = "task" + std::to_string(i);
    y += "  - {name: " + id + ", net: " + (folder / (id + ".xml")).string() + "}\n";
  }
  return y;
}

struct RunOutcome {
  bool finished = false;  ///< the process ended within the time given
  bool success = false;
  std::string message;  ///< the fault message
  double duration_s = 0.0;
};

class NavRobot {
 public:
  NavRobot(bool omni, const sim::World& w, std::vector<Task> tasks, const std::string& localizer = {})
      : tasks_(std::move(tasks)), box_cells_(box_cells(w)) {
    register_all(plugins_, std::make_shared<const sim::World>(w));
    for (std::size_t i = 0; i < tasks_.size(); ++i) {
      const std::string id = "task" + std::to_string(i);
      navi::test::write_file(nets_ / (id + ".xml"), task_net(id, tasks_[i]));
    }
    robot_ =
        Robot::assemble(load_robot_profile_from_string(profile(omni, localizer, nets_.path(), tasks_.size()),
                                                       "navtest.yaml", kRobots),
                        plugins_, clock_);
    for (std::size_t i = 0; i < w.grid.size(); ++i) {
      if (w.grid.is_occupied(w.grid.cell(i))) wall_cells_.push_back(w.grid.cell_center(w.grid.cell(i)));
    }
    robot_->run_until(clock_.now());  // the localizer's first estimate
  }

  // Runs task `task` under a new run id until its process ends or max_s passes (the process then
  // keeps running: last_run() names it). `each` is called every 10 ms.
  RunOutcome run(std::size_t task, double max_s, const std::function<void()>& each = {}) {
    last_run_ = "run" + std::to_string(runs_++);
    const CProcess* process = robot_->processes().find("task" + std::to_string(task));
    REQUIRE(process != nullptr);
    std::string error;
    REQUIRE(robot_->supervisor().start(last_run_, *process, {}, &error));
    const Time start = clock_.now();
    while (robot_->supervisor().running(last_run_) && clock_.now() - start < from_seconds(max_s)) {
      robot_->run_for(10ms);
      record();
      if (each) each();
    }
    RunOutcome out;
    out.duration_s = to_seconds(clock_.now() - start);
    UNSCOPED_INFO("run " << last_run_ << ": " << out.duration_s << " s, at (" << sim().pose().x_m << ", "
                         << sim().pose().y_m << ", " << sim().pose().theta_rad << "), " << sim().collisions()
                         << " collisions");
    for (const ProcessResult& r : robot_->supervisor().take_results()) {
      if (r.run != last_run_) continue;
      out.finished = true;
      out.success = r.success;
      out.message = r.message;
      UNSCOPED_INFO("process " << r.process << (r.success ? " succeeded" : " failed: " + r.message));
    }
    return out;
  }
  void run_for(double s) {
    const Time end = clock_.now() + from_seconds(s);
    while (clock_.now() < end) {
      robot_->run_for(10ms);
      record();
    }
  }

  [[nodiscard]] Robot& robot() { return *robot_; }
  [[nodiscard]] sim::Simulator& sim() {
    return dynamic_cast<sim::SimHardware&>(*robot_->hardware()).simulator();
  }
  [[nodiscard]] navi::CPathPlanner& path_planner() { return *robot_->module<navi::CPathPlanner>(); }
  [[nodiscard]] navi::CCoveragePlanner& coverage() { return *robot_->module<navi::CCoveragePlanner>(); }
  [[nodiscard]] const navi::Section& section(std::string_view name) {
    const navi::Section* s = robot_->module<navi::CSectionSplitter>()->section(name);
    REQUIRE(s != nullptr);
    return *s;
  }
  [[nodiscard]] const std::string& last_run() const noexcept { return last_run_; }
  [[nodiscard]] double now_s() const { return to_seconds(clock_.now()); }
  [[nodiscard]] const std::vector<Pose2D>& trajectory() const noexcept { return trajectory_; }
  [[nodiscard]] double max_turn_rate() const noexcept { return max_turn_rate_; }

  // The smallest distance from the true trajectory's centre to the centre of a wall cell, or of a
  // cell of the boxes the map does not hold.
  [[nodiscard]] double wall_clearance() const { return clearance(wall_cells_); }
  [[nodiscard]] double box_clearance() const { return clearance(box_cells_); }

 private:
  static std::vector<Point2D> box_cells(const sim::World& w) {
    std::vector<Point2D> out;
    for (const sim::DynamicObstacle& o : w.obstacles) {
      const double x0 = o.polygon[0].x_m, y0 = o.polygon[0].y_m, x1 = o.polygon[2].x_m, y1 = o.polygon[2].y_m;
      for (std::size_t i = 0; i < w.grid.size(); ++i) {
        const Point2D c = w.grid.cell_center(w.grid.cell(i));
        if (c.x_m >= x0 && c.x_m <= x1 && c.y_m >= y0 && c.y_m <= y1) out.push_back(c);
      }
    }
    return out;
  }
  void record() {
    trajectory_.push_back(sim().pose());
    max_turn_rate_ = std::max(max_turn_rate_, std::abs(sim().velocity().wz_rad_s));
  }
  [[nodiscard]] double clearance(const std::vector<Point2D>& cells) const {
    double best = 1e9;
    for (std::size_t k = 0; k < trajectory_.size(); k += 5) {
      for (const Point2D& c : cells)
        best = std::min(best, std::hypot(c.x_m - trajectory_[k].x_m, c.y_m - trajectory_[k].y_m));
    }
    return best;
  }

  std::vector<Task> tasks_;
  navi::test::TempDir nets_{"navigation_modules"};
  RobotPlugins plugins_;  // register_all in the constructor, with the world
  SimClock clock_;
  std::unique_ptr<Robot> robot_;
  std::string last_run_;
  int runs_ = 0;
  std::vector<Point2D> wall_cells_, box_cells_;
  std::vector<Pose2D> trajectory_;
  double max_turn_rate_ = 0.0;
};

const Pose2D kWest{0.6, 2.0, 0.0};    // start of the moves to the door, across the room
const Pose2D kCorner{0.3, 0.3, 0.0};  // start of the cleanings

double distance(const Pose2D& a, Point2D b) {
  return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The pieces

TEST_CASE("PublishedPath publishes under new ids, fails, and withdraws only what is still its own",
          "[navi][modules]") {
  NavigationData navigation;
  std::uint32_t ids = 0;
  ModuleContext c;
  c.navigation = &navigation;
  c.path_ids = &ids;
  navi::PublishedPath a, b;
  a.publish({{0, 0}, {3, 0}, {3, 4}}, 1.0, true, c);
  CHECK(a.id() == 1);
  CHECK(navigation.path_id == 1);
  REQUIRE(navigation.path.size() == 3);
  CHECK(navigation.path.data() == a.points().data());  // a view: the loop copies it when the id is new
  CHECK(navigation.path_start_m == 1.0);
  CHECK(navigation.path_final);
  CHECK(navigation.has_goal);
  CHECK(navigation.goal.x_m == 3.0);
  CHECK(navigation.goal.y_m == 4.0);
  CHECK(a.length_m() == Approx(7.0));
  CHECK(a.at(5.0).x_m == Approx(3.0));
  CHECK(a.at(5.0).y_m == Approx(2.0));
  CHECK(a.at(-1.0).x_m == 0.0);
  CHECK(a.at(100.0).y_m == 4.0);

  b.publish({{1, 1}, {2, 1}}, 0.0, false, c);  // a detour of another module
  CHECK(b.id() == 2);
  CHECK_FALSE(navigation.path_final);
  a.withdraw(c);  // not a's path any more: left alone
  CHECK(navigation.path_id == 2);
  CHECK(navigation.path.size() == 2);
  b.withdraw(c);
  CHECK(navigation.path_id == 0);
  CHECK(navigation.path.empty());
  CHECK_FALSE(navigation.has_goal);

  a.fail("unknown goal", c);
  CHECK(navigation.path_id == 3);
  CHECK(navigation.path_failure == "unknown goal");
  CHECK(navigation.path.empty());
  a.publish({{0, 0}, {1, 0}}, 0.0, true, c);
  CHECK(navigation.path_failure.empty());
}

TEST_CASE(
    "ObstacleReplanner is due replan_after_s into a blockage, then every replan_after_s, max_replans times",
    "[navi][modules]") {
  Modules m(6.0, 4.0, false);
  const auto params = [](double after_s, double max) {
    return ParameterSet::resolve(BhAutoMove::static_manifest(), {{"goal", Value{std::string("door")}},
                                                                 {"replan_after_s", Value{after_s}},
                                                                 {"max_replans", Value{max}}});
  };
  navi::ObstacleReplanner r;
  r.reset(params(2.0, 2.0));
  NavigationFeedback fb;
  fb.path_id = 1;
  CHECK_FALSE(r.due(fb, time_from_seconds(100.0)));  // not blocked
  fb.blocked = true;
  fb.blocked_since = time_from_seconds(10.0);
  CHECK_FALSE(r.due(fb, time_from_seconds(11.9)));
  CHECK(r.due(fb, time_from_seconds(12.0)));

  // The laser sees a box at (3, 2) the map does not hold, and the wall at x = 6 it does.
  LaserResource laser("laser", 500ms);
  ResourceTable table;
  table.add(laser);
  LaserScan scan;
  scan.angle_min_rad = -0.1;
  scan.angle_increment_rad = 0.1;
  scan.angle_max_rad = 0.1;
  scan.range_min_m = 0.05;
  scan.range_max_m = 12.0;
  scan.ranges_m = {5.4f, 2.4f, 5.4f};
  scan.stamp = time_from_seconds(12.0);
  laser.publish(scan);
  m.navigation.map_from_base = kWest;
  ModuleContext c = m.context(time_from_seconds(12.0));
  c.resources = &table;
  CHECK(r.observe(*m.maps, c));
  CHECK(r.attempts() == 1);
  REQUIRE(r.obstacles().size() == 1);
  CHECK(r.obstacles()[0].x_m == Approx(3.0).margin(1e-6));
  CHECK(r.obstacles()[0].y_m == Approx(2.0).margin(1e-6));

  CHECK_FALSE(r.due(fb, time_from_seconds(13.9)));  // replan_after_s since the last attempt
  CHECK(r.due(fb, time_from_seconds(14.0)));
  scan.ranges_m = {5.4f, 5.4f, 5.4f};  // the box went: only what the map holds
  scan.stamp = time_from_seconds(14.0);
  laser.publish(scan);
  c.now = time_from_seconds(14.0);
  CHECK_FALSE(r.observe(*m.maps, c));  // nothing new: the same plan again would not help
  CHECK(r.attempts() == 2);
  CHECK_FALSE(r.due(fb, time_from_seconds(30.0)));  // max_replans used up

  r.reset(params(0.0, 5.0));  // replan_after_s 0: never
  CHECK(r.attempts() == 0);
  CHECK(r.obstacles().empty());
  CHECK_FALSE(r.due(fb, time_from_seconds(100.0)));
}

TEST_CASE("The path planner resolves goal names: <section>.entry, a node, a room, a section",
          "[navi][modules]") {
  Modules m(6.0, 4.0, true);
  const navi::Section* a = m.splitter->section("A");
  REQUIRE(a != nullptr);
  const Point2D from{1.0, 1.0};

  const auto door = m.planner->resolve_goal("door", from);
  REQUIRE(door);
  CHECK(door->x_m == Approx(5.4));
  CHECK(door->y_m == Approx(2.0));
  const auto room101 = m.planner->resolve_goal("101", from);  // the centroid of its polygon
  REQUIRE(room101);
  CHECK(room101->x_m == Approx(3.0));
  CHECK(room101->y_m == Approx(2.0));
  const auto section = m.planner->resolve_goal("A", from);
  REQUIRE(section);
  CHECK(section->x_m == Approx(a->centroid.x_m));
  CHECK(section->y_m == Approx(a->centroid.y_m));
  CHECK_FALSE(m.planner->resolve_goal("Z.entry", from));
  CHECK_FALSE(m.planner->resolve_goal("nowhere", from));
  CHECK_FALSE(m.planner->resolve_goal(".entry", from));

  // The entry is the first point of the section's coverage path, on round 0 tangent to the walls:
  // a cell the robot can stand on, and the point the cleaning of A then starts from.
  const auto entry = m.planner->resolve_goal("A.entry", from);
  REQUIRE(entry);
  CHECK(m.maps->planner().traversable(m.maps->grid().cell_at(*entry)));
  m.navigation.map_from_base = {entry->x_m, entry->y_m, 0.0};
  m.activated(BhCleaning::static_manifest(), {{"section", Value{std::string("A")}}}, Time{});
  REQUIRE_FALSE(m.navigation.path.empty());
  CHECK(m.navigation.path.front().x_m == entry->x_m);
  CHECK(m.navigation.path.front().y_m == entry->y_m);

  // Sections of a room, for the planner's question.
  const KnowledgeAnswer sections = m.splitter->sections_of_room("101");
  REQUIRE(sections.ok);
  CHECK(sections.items.front() == "A");
  const KnowledgeAnswer bad = m.splitter->sections_of_room("999");
  CHECK_FALSE(bad.ok);
  CHECK_THAT(bad.error, Catch::Contains("unknown room '999'") && Catch::Contains("101"));
}

TEST_CASE("The path planner plans at activation and fails the behavior for an unknown or unreachable goal",
          "[navi][modules]") {
  Modules m(6.0, 4.0, true, {navi::MapNode{"inside_pillar", Pose2D{3.0, 2.0, 0.0}, "", {}}});
  m.navigation.map_from_base = kWest;
  const ModuleManifest& bh = BhAutoMove::static_manifest();
  m.activated(bh, {{"goal", Value{std::string("door")}}}, Time{});
  CHECK(m.navigation.path_failure.empty());
  CHECK(m.navigation.path_id == m.planner->path().id());
  CHECK(m.navigation.path.size() >= 3);  // the straight line crosses the pillar: corners around it
  CHECK(m.navigation.path.back().x_m == Approx(5.4));
  m.deactivated("BhAutoMove", Time{});
  CHECK(m.navigation.path_id == 0);

  m.activated(bh, {{"goal", Value{std::string("kitchen")}}}, Time{});
  CHECK(m.navigation.path_failure == "unknown goal");
  m.activated(bh, {{"goal", Value{std::string("inside_pillar")}}}, Time{});
  CHECK(m.navigation.path_failure == "no path to the goal");
  // Not served: another behavior's activation leaves the path alone.
  const std::uint32_t id = m.navigation.path_id;
  m.activated(BhGlobalLocalization::static_manifest(), {}, Time{});
  CHECK(m.navigation.path_id == id);
}

TEST_CASE("The coverage planner resumes a section where its coverage stopped, and records the cleaned cells",
          "[navi][modules][cleaning]") {
  Modules m(5.0, 4.0, false);
  m.navigation.map_from_base = kCorner;
  const ModuleManifest& bh = BhCleaning::static_manifest();
  const ParameterValues section_a{{"section", Value{std::string("A")}}};
  m.activated(bh, section_a, Time{});
  const std::uint32_t first = m.navigation.path_id;
  REQUIRE(first != 0);
  const std::vector<Pose2D> path(m.navigation.path.begin(), m.navigation.path.end());
  CHECK(m.navigation.path_start_m == 0.0);
  CHECK(m.navigation.path_final);
  const auto& progress = m.coverage->progress().at("A");
  // the default pattern, hybrid: one wall round, then lanes
  CHECK(progress.plan.rounds == 1);
  CHECK(progress.plan.passes >= 3);

  // The behavior reports its progress; the module records it and marks the footprint's cells.
  NavigationFeedback fb;
  fb.path_id = first;
  fb.progress_m = 4.0;
  m.update(time_from_seconds(1.0), fb);
  CHECK(progress.done_m == 4.0);
  CHECK_FALSE(progress.finished);
  const std::size_t cleaned = m.coverage->cleaned().count();
  CHECK(cleaned > 0);
  m.navigation.localized = false;  // lost: nothing is marked from a pose nobody trusts
  m.navigation.map_from_base = {2.5, 2.0, 0.0};
  m.update(time_from_seconds(1.1), fb);
  CHECK(m.coverage->cleaned().count() == cleaned);
  m.navigation.localized = true;

  m.deactivated("BhCleaning", time_from_seconds(2.0));
  CHECK(m.navigation.path_id == 0);
  CHECK(progress.done_m == 4.0);

  // Activated again for the same section: the same path, taken up where it stopped.
  m.activated(bh, section_a, time_from_seconds(3.0));
  CHECK(m.navigation.path_id != first);
  CHECK(m.navigation.path_start_m == 4.0);
  REQUIRE(m.navigation.path.size() == path.size());
  CHECK(m.navigation.path.front() == path.front());
  CHECK(m.navigation.path.back() == path.back());

  // Finished: the next cleaning of the section starts over.
  fb.path_id = m.navigation.path_id;
  fb.progress_m = m.coverage->progress().at("A").plan.stats.length_m;
  fb.reached_end = true;
  m.update(time_from_seconds(4.0), fb);
  CHECK(m.coverage->progress().at("A").finished);
  m.deactivated("BhCleaning", time_from_seconds(5.0));
  m.activated(bh, section_a, time_from_seconds(6.0));
  CHECK(m.navigation.path_start_m == 0.0);
  CHECK_FALSE(m.coverage->progress().at("A").finished);

  m.activated(bh, {{"section", Value{std::string("Q")}}}, time_from_seconds(7.0));
  CHECK(m.navigation.path_failure == "unknown section");
}

TEST_CASE("A section taken up again from the far side of a pillar is rejoined by a planned way",
          "[navi][modules][cleaning]") {
  // The faults world's kidnapping: the robot is carried off, found again, and its cleaning goes
  // on from where it stopped. The follower would steer straight at that point, through what
  // the map holds between (its laser watch ignores mapped obstacles).
  Modules m(6.0, 4.0, true);  // the pillar: x 2.7-3.3 m, y 1.2-2.8 m
  m.navigation.map_from_base = kCorner;
  const ModuleManifest& bh = BhCleaning::static_manifest();
  const ParameterValues section_a{{"section", Value{std::string("A")}}};
  m.activated(bh, section_a, Time{});
  const std::vector<Pose2D> path(m.navigation.path.begin(), m.navigation.path.end());
  // a point of the path west of the pillar, level with it (sampled every 5 cm along the legs)
  double s = 0.0, done_m = -1.0;
  Pose2D stop;
  for (std::size_t i = 1; i < path.size() && done_m < 0.0; ++i) {
    const double len = std::hypot(path[i].x_m - path[i - 1].x_m, path[i].y_m - path[i - 1].y_m);
    for (double d = 0.0; d < len; d += 0.05) {
      const double t = d / len;
      const Pose2D p{path[i - 1].x_m + t * (path[i].x_m - path[i - 1].x_m),
                     path[i - 1].y_m + t * (path[i].y_m - path[i - 1].y_m), 0.0};
      if (p.x_m > 1.2 && p.x_m < 2.2 && std::abs(p.y_m - 2.0) < 0.3) {
        done_m = s + d;
        stop = p;
        break;
      }
    }
    s += len;
  }
  REQUIRE(done_m > 0.0);
  NavigationFeedback fb;
  fb.path_id = m.navigation.path_id;
  fb.progress_m = done_m;
  m.update(time_from_seconds(1.0), fb);
  m.deactivated("BhCleaning", time_from_seconds(2.0));

  // found again east of the pillar, mirrored: the straight line back crosses it
  const Point2D found{6.0 - stop.x_m, stop.y_m};
  m.navigation.map_from_base = {found.x_m, found.y_m, 0.0};
  const navi::PathPlanner& pp = m.maps->planner();
  REQUIRE(pp.traversable(m.maps->grid().cell_at(found)));
  REQUIRE_FALSE(pp.line_of_sight(m.maps->grid().cell_at(found), m.maps->grid().cell_at({stop.x_m, stop.y_m})));
  m.activated(bh, section_a, time_from_seconds(3.0));
  const std::vector<Pose2D> way(m.navigation.path.begin(), m.navigation.path.end());
  REQUIRE(way.size() >= 3);  // round the pillar
  CHECK_FALSE(m.navigation.path_final);
  CHECK(way.front().x_m == Approx(found.x_m));
  CHECK(way.back().x_m == Approx(stop.x_m).margin(1e-6));
  CHECK(way.back().y_m == Approx(stop.y_m).margin(1e-6));
  for (std::size_t i = 1; i < way.size(); ++i) {
    CHECK(pp.line_of_sight(m.maps->grid().cell_at({way[i - 1].x_m, way[i - 1].y_m}),
                           m.maps->grid().cell_at({way[i].x_m, way[i].y_m})));
  }
  // at its end the coverage path is given again, from where the section stopped
  NavigationFeedback back;
  back.path_id = m.navigation.path_id;
  back.reached_end = true;
  m.navigation.map_from_base = stop;
  m.update(time_from_seconds(20.0), back);
  CHECK(m.navigation.path_final);
  CHECK(m.navigation.path_start_m == Approx(done_m));
  CHECK(m.navigation.path.size() == path.size());

  // taken up again where it stopped: no way to plan, the coverage path at once
  m.deactivated("BhCleaning", time_from_seconds(21.0));
  m.activated(bh, section_a, time_from_seconds(22.0));
  CHECK(m.navigation.path_final);
  CHECK(m.navigation.path_start_m == Approx(done_m));
}

// ---------------------------------------------------------------------------------------------
// A whole robot: the modules plan, the behaviors track, the simulator moves the body.

TEST_CASE(
    "BhAutoMove reaches a named goal around a pillar on the path the planner gives, omni and differential",
    "[navi][modules][robot]") {
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    // Stopped for 2 s by the laser returns of the walls and the pillar, it would fail.
    NavRobot r(omni, world(6.0, 4.0, true, kWest),
               {{"BhAutoMove", {{"goal", "door"}, {"blocked_timeout_s", "2"}}}});
    const RunOutcome o = r.run(0, 120.0);
    CHECK(o.success);
    CHECK(r.path_planner().path().points().size() >= 3);  // around the pillar
    CHECK(r.path_planner().replans() == 0);  // the laser saw only what the map holds: never blocked
    const Pose2D end = r.sim().pose();
    CHECK(distance(end, {5.4, 2.0}) <= 0.1);
    CHECK(r.wall_clearance() >= kRadius_m);  // the body never over a cell of the pillar or a wall
    CHECK(r.sim().collisions() == 0);
    CHECK(o.duration_s < 40.0);
    if (omni) CHECK(r.max_turn_rate() < 0.2);  // translated, kept its heading
  }
}

TEST_CASE(
    "BhAutoMove fails with the planner's reason for an unknown or unreachable goal, a cleaning for an "
    "unknown section",
    "[navi][modules][robot]") {
  sim::World w = world(6.0, 4.0, true, kWest);
  w.regions.nodes.push_back(navi::MapNode{"inside_pillar", Pose2D{3.0, 2.0, 0.0}, "", {}});
  NavRobot r(false, w,
             {{"BhAutoMove", {{"goal", "kitchen"}}},
              {"BhAutoMove", {{"goal", "inside_pillar"}}},
              {"BhCleaningTwoWheel", {{"section", "Q"}}}});
  RunOutcome o = r.run(0, 5.0);
  CHECK(o.finished);
  CHECK(o.message == "behavior BhAutoMove failed: unknown goal");
  CHECK(o.duration_s < 0.2);  // at once, not after a timeout
  o = r.run(1, 5.0);
  CHECK(o.message == "behavior BhAutoMove failed: no path to the goal");
  o = r.run(2, 5.0);
  CHECK(o.message == "behavior BhCleaningTwoWheel failed: unknown section");
  CHECK(distance(r.sim().pose(), {kWest.x_m, kWest.y_m}) < 0.01);  // it never moved
}

TEST_CASE(
    "BhAutoMove stops before a box the map does not hold and, not replanning, fails when blocked too long",
    "[navi][modules][robot]") {
  // Wall to wall across the room: no way around it.
  NavRobot r(true, world(6.0, 4.0, false, kWest, {{2.75, 0.0, 3.25, 4.0, {}}}),
             {{"BhAutoMove", {{"goal", "door"}, {"blocked_timeout_s", "3"}, {"replan_after_s", "0"}}}});
  const RunOutcome o = r.run(0, 60.0);
  CHECK(o.message == "behavior BhAutoMove failed: path blocked");
  CHECK(r.path_planner().replans() == 0);
  // About 9 s to drive up to the box and stop (slowing from 0.4 m of clearance), then 3 s.
  CHECK(o.duration_s > 3.0 + 5.0);
  CHECK(o.duration_s < 3.0 + 12.0);
  CHECK(r.box_clearance() >= kRadius_m);  // it did not drive into it
  CHECK(r.sim().collisions() == 0);
}

TEST_CASE("The path planner replans around a box the map does not hold, omni and differential",
          "[navi][modules][robot]") {
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    NavRobot r(omni, world(6.0, 4.0, false, kWest, {{2.75, 1.5, 3.25, 2.5, {}}}),  // across the straight line
               {{"BhAutoMove", {{"goal", "door"}, {"blocked_timeout_s", "20"}}}});
    std::size_t first_plan = 0;
    const RunOutcome o = r.run(0, 120.0, [&] {
      if (first_plan == 0) first_plan = r.path_planner().path().points().size();
    });
    CHECK(first_plan == 2);  // the map is empty: straight at first
    CHECK(o.success);
    CHECK(r.path_planner().replans() >= 1);
    CHECK(r.path_planner().path().points().size() >= 3);  // the last plan has corners around the box
    CHECK(r.box_clearance() >= kRadius_m);
    CHECK(r.sim().collisions() == 0);
    CHECK(distance(r.sim().pose(), {5.4, 2.0}) <= 0.1);
    CHECK(o.duration_s < 60.0);
  }
}

TEST_CASE(
    "With no way around, BhAutoMove waits for blocked_timeout_s while the planner retries, or goes on when "
    "the way clears",
    "[navi][modules][robot]") {
  const Task task{"BhAutoMove", {{"goal", "door"}, {"blocked_timeout_s", "6"}, {"replan_after_s", "1"}}};
  {
    NavRobot r(true, world(6.0, 4.0, false, kWest, {{2.75, 0.0, 3.25, 4.0, {}}}), {task});
    const RunOutcome o = r.run(0, 60.0);
    CHECK(o.message == "behavior BhAutoMove failed: path blocked");
    CHECK(r.path_planner().replans() >= 2);  // tried again while waiting
    CHECK(o.duration_s > 6.0 + 5.0);
    CHECK(o.duration_s < 6.0 + 12.0);
    CHECK(r.box_clearance() >= kRadius_m);
  }
  // The same box is pushed away at 12 s, while the robot waits before it: it arrives.
  NavRobot r(true, world(6.0, 4.0, false, kWest, {{2.75, 0.0, 3.25, 4.0, 12.0}}), {task});
  std::optional<Pose2D> waiting;
  const RunOutcome o = r.run(0, 60.0, [&] {
    if (!waiting && r.now_s() >= 11.9) waiting = r.sim().pose();
  });
  REQUIRE(waiting);
  CHECK(waiting->x_m < 2.75 - kRadius_m);  // before the box, still running at 11.9 s
  CHECK(r.sim().collisions() == 0);
  CHECK(o.success);
  CHECK(o.duration_s > 12.0);
  CHECK(distance(r.sim().pose(), {5.4, 2.0}) <= 0.1);
}

TEST_CASE("BhAutoMove pauses while the localizer is lost and goes on when it agrees again",
          "[navi][modules][robot]") {
  NavRobot r(false, world(6.0, 4.0, false, kWest), {{"BhAutoMove", {{"goal", "door"}}}},
             ", faults: 2-5, recover_at_fault_end: true");
  Pose2D at_2_5, at_4_9;
  const RunOutcome o = r.run(0, 60.0, [&] {
    if (std::abs(r.now_s() - 2.5) < 0.005) at_2_5 = r.sim().pose();
    if (std::abs(r.now_s() - 4.9) < 0.005) at_4_9 = r.sim().pose();
  });
  CHECK(o.success);
  CHECK(at_2_5.x_m > kWest.x_m + 0.3);                        // it was on its way
  CHECK(distance(at_4_9, {at_2_5.x_m, at_2_5.y_m}) < 0.005);  // stood still while lost
  CHECK(distance(r.sim().pose(), {5.4, 2.0}) <= 0.1);
}

TEST_CASE("BhCleaning covers a section with the hybrid path on the omni base, keeping its heading",
          "[navi][modules][robot][cleaning]") {
  NavRobot r(true, world(5.0, 4.0, true, kCorner), {{"BhCleaning", {{"section", "A"}}}});
  const RunOutcome o = r.run(0, 600.0);
  CHECK(o.success);
  const auto& progress = r.coverage().progress().at("A");
  CHECK(progress.plan.rounds == 1);  // the wall round; lanes inside it
  CHECK(progress.plan.passes >= 3);
  CHECK(progress.finished);
  const navi::Section& a = r.section("A");
  CHECK(r.coverage().section_coverage(a) >= 0.99);
  // Coverage of the cells the plan can reach, measured on the true trajectory.
  const OccupancyGrid& grid = r.sim().world().grid;
  navi::CleanedCells reach(grid), truth(grid);
  reach.mark_path(progress.plan.path, kCleaningWidth_m / 2);
  for (std::size_t k = 1; k < r.trajectory().size(); ++k) {
    const Pose2D& p = r.trajectory()[k - 1];
    const Pose2D& q = r.trajectory()[k];
    truth.mark_segment({p.x_m, p.y_m}, {q.x_m, q.y_m}, kCleaningWidth_m / 2);
  }
  std::vector<std::size_t> reachable;
  for (const std::size_t i : a.cells) {
    if (reach.cleaned(i)) reachable.push_back(i);
  }
  CHECK(truth.coverage(reachable) >= 0.98);
  CHECK(r.max_turn_rate() < 0.2);  // an omni base never needs to turn
  CHECK(r.wall_clearance() >= kRadius_m);
  CHECK(r.sim().collisions() == 0);
  CHECK(o.duration_s < 300.0);
}

TEST_CASE("BhCleaningTwoWheel covers the section on the differential base",
          "[navi][modules][robot][cleaning]") {
  NavRobot r(false, world(5.0, 4.0, true, kCorner), {{"BhCleaningTwoWheel", {{"section", "A"}}}});
  const RunOutcome o = r.run(0, 900.0);
  CHECK(o.success);
  CHECK(r.coverage().section_coverage(r.section("A")) >= 0.98);
  CHECK(r.max_turn_rate() > 0.5);  // steering by heading
  CHECK(r.sim().collisions() == 0);
}

TEST_CASE(
    "The coverage planner detours a cleaning around a box the map does not hold, without replanning it is "
    "blocked",
    "[navi][modules][robot][cleaning]") {
  const Box box{2.2, 0.05, 2.8, 0.6, {}};  // against the bottom wall, on the first rounds
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    NavRobot r(
        omni, world(5.0, 4.0, false, kCorner, {box}),
        {{omni ? "BhCleaning" : "BhCleaningTwoWheel", {{"section", "A"}, {"blocked_timeout_s", "20"}}}});
    int detours = 0;  // paths published whose end is not the behavior's goal
    std::uint32_t last_id = 0;
    const RunOutcome o = r.run(0, 900.0, [&] {
      const NavigationData& n = r.robot().navigation();
      if (n.path_id != last_id && n.path_id != 0 && !n.path_final) ++detours;
      last_id = n.path_id;
    });
    CHECK(o.success);
    CHECK(detours >= 1);
    CHECK(r.box_clearance() >= kRadius_m);
    CHECK(r.sim().collisions() == 0);
    // What the box hides is lost, the rest of the section is cleaned (the box and the ring
    // around it where the body cannot go are about 5 % of the section).
    CHECK(r.coverage().section_coverage(r.section("A")) >= 0.85);
  }
  NavRobot r(true, world(5.0, 4.0, false, kCorner, {box}),
             {{"BhCleaning", {{"section", "A"}, {"blocked_timeout_s", "5"}, {"replan_after_s", "0"}}}});
  const RunOutcome o = r.run(0, 900.0);
  CHECK(o.message == "behavior BhCleaning failed: path blocked");
  CHECK(r.box_clearance() >= kRadius_m);
}

TEST_CASE("A cleaning interrupted and activated again resumes where it stopped, lost, it marks nothing",
          "[navi][modules][robot][cleaning]") {
  NavRobot r(true, world(5.0, 4.0, false, kCorner), {{"BhCleaning", {{"section", "A"}}}},
             ", faults: 20-23, recover_at_fault_end: true");
  std::size_t cleaned_at_20_5 = 0, cleaned_at_22_9 = 0;
  const RunOutcome first = r.run(0, 30.0, [&] {
    if (std::abs(r.now_s() - 20.5) < 0.005) cleaned_at_20_5 = r.coverage().cleaned().count();
    if (std::abs(r.now_s() - 22.9) < 0.005) cleaned_at_22_9 = r.coverage().cleaned().count();
  });
  REQUIRE_FALSE(first.finished);
  CHECK(cleaned_at_20_5 > 0);
  CHECK(cleaned_at_22_9 == cleaned_at_20_5);  // lost: no cell marked from a pose nobody trusts
  const auto& progress = r.coverage().progress().at("A");
  const double done = progress.done_m;
  CHECK(done > 5.0);
  REQUIRE(r.robot().supervisor().stop(r.last_run(), "interrupted by the test"));
  r.run_for(2.0);
  CHECK_FALSE(r.robot().behavior_active("BhCleaning"));
  CHECK(progress.done_m == done);

  std::optional<double> taken_up_at_m;
  const RunOutcome second = r.run(0, 600.0, [&] {
    if (!taken_up_at_m && r.robot().navigation().path_id != 0)
      taken_up_at_m = r.robot().navigation().path_start_m;
  });
  CHECK(taken_up_at_m == done);
  CHECK(second.success);
  CHECK(r.coverage().section_coverage(r.section("A")) >= 0.99);
  // The remaining part only: well under the whole path's duration at 0.3 m/s.
  CHECK(second.duration_s < (navi::polyline_length_m(progress.plan.path) - done) / 0.3 * 1.6 + 5.0);
}

TEST_CASE("BhGlobalLocalization turns while the localizer attempts fixes, until one is accepted, or gives up",
          "[navi][modules][robot]") {
  {
    // Lost from the start; fixes are refused while the fault lasts (5 s). Attempts every 2 s of
    // the activation: at 2 and 4 s they fail, at 6 s one is accepted.
    NavRobot r(true, world(5.0, 4.0, false, {1.0, 1.0, 0.0}), {{"BhGlobalLocalization", {}}},
               ", faults: 0-5");
    CHECK_FALSE(r.robot().navigation().localized);
    const RunOutcome o = r.run(0, 60.0);
    CHECK(o.success);
    CHECK(o.duration_s == Approx(6.1).margin(0.03));  // with a sequencing period to activate, one to report
    CHECK(r.robot().navigation().fixes == 1);
    CHECK(r.sim().rotation_rad() > 0.5);  // it turned meanwhile
    r.run_for(0.2);
    CHECK(r.robot().navigation().localized);
  }
  NavRobot r(true, world(5.0, 4.0, false, {1.0, 1.0, 0.0}), {{"BhGlobalLocalization", {{"timeout_s", "5"}}}},
             ", faults: 0-1000");
  const RunOutcome o = r.run(0, 60.0);
  CHECK(o.message == "behavior BhGlobalLocalization failed: no position found");
  CHECK(o.duration_s == Approx(5.1).margin(0.03));
  CHECK(r.robot().navigation().fixes == 0);
}
