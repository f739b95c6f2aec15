// GuideHri (tools/tripodal/guide_hri.hpp): the guide robot's HRI as the visit and the monitor's
// touch page share it, on Jinny assembled from its profile in the exhibit hall: reaction inputs
// answered from the RKMS of the profile's Hri module, an entry added to that store answered at once,
// command inputs started on the robot's planner or refused in plain words, and the internal state
// the HRI displays following the planner's life cycle.
#include "guide_hri.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "run_outputs.hpp"
#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/behaviors/gesture_behaviors.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/reactive/control_loop.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace tripodal::app;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

const std::filesystem::path kConfigs = TRIPODAL_SOURCE_DIR "/configs";

// Jinny in the exhibit hall, its Hri module on a copy of its knowledge file (the test edits it).
struct GuideRobot {
  std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tripodal_guide_hri_" + std::to_string(::getpid()));
  std::shared_ptr<sim::World> world = std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/exhibit_hall.yaml"));
  RobotProfile profile = load_robot_profile(kConfigs / "robots/jinny.yaml");
  RobotPlugins plugins;
  SimClock clock;
  std::unique_ptr<Robot> robot;
  CHri* hri = nullptr;

  GuideRobot() {
    spdlog::set_level(spdlog::level::warn);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    std::filesystem::copy_file(kConfigs / "hri/jinny.xml", dir / "jinny.xml");
    register_all(plugins, world);
    RobotOptions ro;
    ro.parameters = simulation_overrides(profile, *world, 1);
    ro.parameters.push_back({"hri", "knowledge", (dir / "jinny.xml").string()});
    robot = Robot::assemble(profile, plugins, clock, ro);
    if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(world->start_pose);
    hri = robot->module<CHri>();
    robot->run_until(clock.now());
  }
  ~GuideRobot() {
    robot.reset();
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  GuideRobot(const GuideRobot&) = delete;
  GuideRobot& operator=(const GuideRobot&) = delete;
};

}  // namespace

TEST_CASE("GuideHri: reaction inputs from the robot's RKMS, an edit answered at once, commands to its planner", "[app][guide][hri]") {
  GuideRobot g;
  REQUIRE(g.hri != nullptr);
  GuideHri guide(*g.robot, *g.hri, g.clock, g.profile.tasks, GuideHri::Options{[] { return 0.82; }, nullptr});
  StoreBackedHri& service = guide.service();
  CHECK(&service.knowledge_store() == &g.hri->knowledge_store());
  CHECK(service.knowledge_store().file() == g.dir / "jinny.xml");
  CHECK(service.voice() == nullptr);

  HriReply r = service.ask("Introduce yourself.");
  CHECK(r.kind == HriReply::Kind::answered);
  CHECK(r.entry_id == "introduce");
  CHECK_THAT(r.text, StartsWith("Hello, I am Jinny"));
  r = service.ask("how much battery do you have");
  CHECK(r.entry_id == "battery");
  CHECK_THAT(r.text, Contains("82 percent"));

  // An entry added to the module's store (what the /rkms page does) is answered from at once.
  KnowledgeEntry shop;
  shop.id = "souvenirs";
  shop.topic = "the souvenir shop";
  shop.keywords = {"souvenir", "souvenirs", "gift", "shop"};
  shop.questions = {"Where can I buy a souvenir?"};
  shop.answer = "The souvenir shop is by the entrance, open until 17.";
  CHECK(service.ask("where can I buy a souvenir").kind == HriReply::Kind::not_understood);
  REQUIRE(service.knowledge_store().add(shop, "test").ok());
  r = service.ask("where can I buy a souvenir");
  CHECK(r.kind == HriReply::Kind::answered);
  CHECK(r.entry_id == "souvenirs");
  CHECK(KnowledgeBase::load(g.dir / "jinny.xml").version() == 2);

  // A command with a node the hall lacks: refused with the nodes there are (from the planner's reason); nothing starts.
  r = service.ask("guide me to node 7");
  CHECK(r.kind == HriReply::Kind::task_refused);
  CHECK(r.text == "Sorry, there is no node 7 here. I can guide you to node 0, 1 or 2.");
  CHECK_FALSE(g.robot->planner().busy());
  CHECK(guide.take_started_task().empty());

  // A command the planner accepts starts on the robot, and the display follows its life cycle.
  r = service.ask("guide me to node 1");
  CHECK(r.kind == HriReply::Kind::task_started);
  CHECK(r.task == "guide");
  CHECK(guide.take_started_task() == "guide");
  CHECK(guide.take_started_task().empty());
  CHECK(g.robot->planner().busy());
  g.robot->run_for(std::chrono::seconds(2));
  CHECK(guide.update().empty());
  CHECK(guide.state().task == "guide");
  CHECK(guide.state().task_state == "running");
  CHECK(guide.state().process == "PrAutoMove(goal=node1)");
  const HriDisplay d = service.display();
  CHECK(display_text(d.state) == "task guide: running | process PrAutoMove(goal=node1) | no fault");
  REQUIRE(d.last.has_value());
  CHECK(d.last->input == "guide me to node 1");
  CHECK(d.last->kind == HriReply::Kind::task_started);

  // While the task runs, another command is refused by the planner, and the HRI says why.
  r = service.ask("guide me to node 0");
  CHECK(r.kind == HriReply::Kind::task_refused);
  CHECK_THAT(r.text, StartsWith("Sorry, I cannot start the guide task now: "));
}

TEST_CASE("GuideHri: the explanation PrExplain asks for is spoken from the RKMS at the node", "[app][guide][hri]") {
  GuideRobot g;
  GuideHri guide(*g.robot, *g.hri, g.clock, g.profile.tasks, GuideHri::Options{});
  REQUIRE(guide.service().ask("explain the robot at node 1").kind == HriReply::Kind::task_started);
  std::vector<HriReply> spoken;
  for (int i = 0; i < 1800 && g.robot->planner().busy(); ++i) {
    g.robot->run_for(std::chrono::milliseconds(50));
    for (HriReply& x : guide.update()) spoken.push_back(std::move(x));
  }
  CHECK(guide.last_task_end() == "succeeded");
  REQUIRE(spoken.size() == 1);
  CHECK(spoken[0].entry_id == "node1_robot");
  CHECK_THAT(spoken[0].text, StartsWith("At node 1 stands PSR-2"));
  CHECK(guide.state().task_state == "succeeded");
  CHECK(guide.processes().size() >= 2);
}

namespace {

// Drives straight ahead at 0.5 m/s whatever is there: the task's behavior that does not look.
class BhPush final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = behavior_manifest("BhPush", "straight ahead at 0.5 m/s, blind", {}, {});
    return m;
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet&, const BehaviorContext&) override {}
  std::optional<Twist2D> on_step(const BehaviorContext&) noexcept override { return Twist2D{0.5, 0.0, 0.0}; }
};

// Jinny's shipped profile, with its safety behavior (BhAvoidObstacle, safety: true) or without it.
RobotProfile jinny_profile(bool with_safety) {
  RobotProfile profile = load_robot_profile(kConfigs / "robots/jinny.yaml");
  if (!with_safety) std::erase_if(profile.behaviors, [](const ModuleEntry& e) { return e.safety; });
  return profile;
}

// Jinny at the entrance facing +x, one visitor standing 1.1 m ahead (0.6 m between the bodies),
// pushed towards it for 4 s; with or without the profile's safety behavior.
struct PushResult {
  std::uint64_t collisions = 0;
  double clearance_m = 0.0;
};

PushResult push_towards_visitor(bool with_safety) {
  spdlog::set_level(spdlog::level::warn);
  auto world = std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/exhibit_hall.yaml"));
  sim::Visitor standing = world->visitors.at(1);
  standing.name = "stander";
  standing.path = {{2.6, 4.0}};
  standing.give_way_m = 0.0;
  standing.radius_m = 0.25;
  world->visitors = {standing};
  RobotProfile profile = jinny_profile(with_safety);
  RobotPlugins plugins;
  register_all(plugins, world);
  SimClock clock;
  RobotOptions ro;
  ro.parameters = simulation_overrides(profile, *world, 1);
  auto robot = Robot::assemble(profile, plugins, clock, ro);
  ControlLoop& loop = robot->behavior_loop();
  loop.coordinator().add_input(CoordinatorInputConfig{.name = "push", .priority = 50});
  robot->run_until(clock.now());
  robot->run_for(std::chrono::milliseconds(500));  // the first scans
  loop.activate(std::make_unique<BhPush>(), {}, "push");
  robot->run_for(std::chrono::seconds(4));
  const auto& sim = dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator();
  return {sim.collisions(), sim.min_visitor_clearance_m()};
}

}  // namespace

TEST_CASE("BhAvoidObstacle as Jinny's safety behavior (safety: true) stops a behavior that drives into a visitor who does not give way",
          "[app][guide][safety]") {
  {
    const RobotProfile profile = jinny_profile(true);  // as shipped
    REQUIRE(std::count_if(profile.behaviors.begin(), profile.behaviors.end(), [](const ModuleEntry& e) { return e.safety; }) == 1);
    SimClock clock;
    auto world = std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/exhibit_hall.yaml"));
    RobotPlugins plugins;
    register_all(plugins, world);
    const auto robot = Robot::assemble(profile, plugins, clock);
    const CBehaviorCoordinator& c = robot->behavior_loop().coordinator();
    const auto id = c.find_input("BhAvoidObstacle");
    REQUIRE(id.has_value());
    CHECK(c.input_config(*id).role == InputRole::safety);
    CHECK(c.input_config(*id).priority > c.input_config(*c.find_input("BhAutoMove")).priority);
  }
  const PushResult without = push_towards_visitor(false);
  CHECK(without.collisions >= 1);  // the blind push reaches the visitor
  const PushResult with = push_towards_visitor(true);
  CHECK(with.collisions == 0);
  CHECK(with.clearance_m > 0.0);
  CHECK(with.clearance_m < 0.3);  // it did drive up to the visitor, then stopped
}

TEST_CASE("A safety behavior: safety takes true or false, behaviors only, and no net may bind it", "[app][guide][safety][errors]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tripodal_safety_profile_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto error_of = [&](const std::string& yaml) {
    {
      std::ofstream(dir / "robot.yaml") << yaml;
    }
    try {
      (void)load_robot_profile(dir / "robot.yaml");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK_THAT(error_of("robot: {name: r}\nbehaviors:\n  - {name: BhAvoidObstacle, safety: maybe}\n"),
             Contains("robot.yaml:3:37: error: safety: expected true or false, got 'maybe'"));
  CHECK_THAT(error_of("robot: {name: r}\nhri:\n  - {name: hri, type: Hri, safety: true}\n"),
             Contains("robot.yaml:3:28: error: unknown key 'safety' in a hri entry"));
  CHECK(error_of("robot: {name: r}\nbehaviors:\n  - {name: BhAvoidObstacle, safety: true}\n").empty());
  std::filesystem::remove_all(dir);

  // BhAutoMove made a safety behavior: PrAutoMove's net binds it, which the robot refuses.
  RobotProfile profile = load_robot_profile(kConfigs / "robots/jinny.yaml");
  for (ModuleEntry& b : profile.behaviors) b.safety = b.name == "BhAutoMove";
  auto world = std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/exhibit_hall.yaml"));
  RobotPlugins plugins;
  register_all(plugins, world);
  SimClock clock;
  try {
    (void)Robot::assemble(profile, plugins, clock);
    FAIL("the robot assembled with a net binding a safety behavior");
  } catch (const ConfigError& e) {
    CHECK_THAT(std::string(e.what()), Contains("binds behavior 'BhAutoMove', which the robot runs as a safety behavior"));
  }
}
