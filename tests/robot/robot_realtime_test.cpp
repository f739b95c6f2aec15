// The robot on the wall-clock runtime (Robot::start): PSR-2 in the simulator at 20 times real time,
// on its own threads, cleaning a room (scripts/tsan.sh runs the [threads] tests under TSan: no data
// race between the loops, the sequencing layer and the observer), and a starved behavior loop whose
// run of overruns becomes the fault "motion.deadline" the supervisor and the task see. What is
// checked does not depend on how fast the machine is: the wall time only bounds the run.
#include <atomic>
#include <catch2/catch.hpp>
#include <mutex>
#include <thread>

#include "robot_doubles.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/hri/answer_providers.hpp"
#include "tripodal/hri/hri_robot_module.hpp"
#include "tripodal/hri/hri_service.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";

// Waits (wall time) until `done` or `limit` has passed; whether it was done.
template <class Done>
bool wait_for(const Done& done, std::chrono::seconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(20ms);
  }
  return true;
}

// Records the supervisor's faults from the sequencing thread for the test's thread.
class FaultLog final : public SupervisorObserver {
 public:
  void on_fault(std::string_view source, std::string_view reason, Time /*now*/) override {
    std::lock_guard lock(mutex_);
    faults_.push_back(std::string(source) + ": " + std::string(reason));
  }
  [[nodiscard]] std::vector<std::string> faults() const {
    std::lock_guard lock(mutex_);
    return faults_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> faults_;
};

}  // namespace

TEST_CASE("PSR-2 cleans on its own threads at 20 times real time", "[robot][threads]") {
  RobotPlugins plugins = builtin_plugins(std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml")));
  ScaledClock clock(20.0);
  const auto robot = Robot::assemble(load_robot_profile(kConfigs / "robots/psr2.yaml"), plugins, clock);
  REQUIRE(robot->command("clean the room 3211").accepted);
  // What the test reads of the sequencing layer while it runs, observed on its own thread.
  std::atomic<bool> busy{true};
  std::atomic<int> periods{0};
  std::atomic<bool> cleaning_seen{false};
  const auto* coverage = robot->module<navi::CCoveragePlanner>();
  RealtimeOptions ro;
  ro.after_sequencing = [&](Time) {
    periods.fetch_add(1);
    busy.store(robot->planner().busy());
    if (robot->behavior_active("BhCleaning")) cleaning_seen.store(true);
  };
  robot->start(ro);
  // Bounded wall time: the task (about 300 s simulated) or 40 s of wall time, whichever is first.
  const bool finished = wait_for([&] { return !busy.load(); }, 40s);
  robot->stop();
  CHECK_FALSE(robot->started());

  const auto& sim = dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator();
  const double progress_m = coverage->progress().count("A") != 0 ? coverage->progress().at("A").done_m : 0.0;
  const std::vector<LoopTimingReport> timing = robot->timing();
  REQUIRE(timing.size() == 2);
  INFO("finished " << finished << ", state " << to_string(robot->planner().state()) << " (" << robot->planner().report().reason
                   << "), simulated " << to_seconds(clock.now()) << " s, distance " << sim.distance_m() << " m, section A "
                   << progress_m << " m, " << sim.collisions() << " collisions; motion: " << timing[0].cycles << " cycles, "
                   << timing[0].skipped_ticks << " skipped, period error p99 " << to_seconds(timing[0].period_error_p99) * 1e6
                   << " us");
  // Done, or under way: the base drove and the coverage of the first section advanced. (On a
  // machine too loaded for 0.5 ms wall periods the loop skips ticks, drives on stale commands and
  // may touch a wall or fail the task: a fact of starvation, which deadline_overruns would report;
  // what this test proves is the threads' hand-over, not the machine's speed.)
  CHECK((robot->planner().state() == TaskState::succeeded || (cleaning_seen.load() && progress_m > 1.0)));
  CHECK(sim.distance_m() > 2.0);
  CHECK(periods.load() > 10);
  // The modules read the resources through the snapshot: the localizer saw the laser's scans.
  const auto* scans = robot->sequencing_resources().first<LaserScan>();
  REQUIRE(scans != nullptr);
  CHECK(scans != robot->resources().first<LaserScan>());
  CHECK(scans->sequence() > 10);
  // Every thread kept a record of its deadlines.
  CHECK(timing[0].name == "motion");
  CHECK(timing[0].period == 10ms);
  CHECK(timing[0].cycles > 100);
  CHECK(timing[1].name == "sequencing");
  CHECK(timing[1].period == 50ms);
  CHECK(timing[1].cycles > 10);
  CHECK(timing[0].deadline_faults == 0);  // the profile does not ask for deadline faults
}

namespace {

// The loop's work made slow on demand: a resource whose poll takes 25 ms while `slow` is set.
std::atomic<bool> g_slow{false};

class SlowResource final : public BumperResource {
 public:
  static const ModuleManifest& manifest_of() {
    static const ModuleManifest m = [] {
      ModuleManifest x = resource_manifest<BumperReading>();
      x.name = "SlowBumper";
      return x;
    }();
    return m;
  }
  explicit SlowResource(std::string name) : BumperResource(std::move(name), Duration{0}, manifest_of()) {}

 protected:
  void on_poll(Time) noexcept override {
    if (g_slow.load()) std::this_thread::sleep_for(25ms);
  }
};

}  // namespace

TEST_CASE("A starved behavior loop posts motion.deadline as a fault the supervisor and the task see", "[robot][threads]") {
  test::TestWorld world;
  RobotPlugins plugins = test::test_plugins(world);
  plugins.resources.add(SlowResource::manifest_of(),
                        [](const ResourceConfig& c) { return std::make_unique<SlowResource>(c.name); });
  RobotProfile profile = load_robot_profile(kConfigs / "robots/psr2.yaml");
  ModuleEntry slow;
  slow.kind = ModuleKind::resource;
  slow.name = "slow_bumper";
  slow.type = "SlowBumper";
  profile.resources.push_back(slow);
  REQUIRE(profile.loops.size() == 1);
  profile.loops[0].timing.deadline_overruns = 3;
  SteadyClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  FaultLog faults;
  LifecycleRecorder life(true);
  robot->supervisor().add_observer(faults);
  robot->supervisor().add_observer(life);
  robot->planner().add_observer(life);
  REQUIRE(robot->command("clean the room 3211").accepted);
  std::atomic<bool> failed{false};
  RealtimeOptions ro;
  ro.after_sequencing = [&](Time) {
    if (robot->planner().state() == TaskState::failed) failed.store(true);
  };
  g_slow.store(false);
  robot->start(ro);
  // The task under way, then the loop starved: every cycle takes 25 ms of a 10 ms period.
  CHECK(wait_for([&] { return !faults.faults().empty() || robot->behavior_loop().cycles() > 20; }, 20s));
  g_slow.store(true);
  const bool posted = wait_for(
      [&] {
        for (const std::string& f : faults.faults()) {
          if (f.rfind("motion: missed its deadline", 0) == 0) return true;
        }
        return false;
      },
      30s);
  const bool task_failed = wait_for([&] { return failed.load(); }, 10s);
  g_slow.store(false);
  robot->stop();
  CHECK(posted);
  CHECK(task_failed);
  const std::vector<LoopTimingReport> timing = robot->timing();
  REQUIRE(timing.size() == 2);
  CHECK(timing[0].name == "motion");
  CHECK(timing[0].overruns >= 3);
  CHECK(timing[0].deadline_faults >= 1);
  CHECK(timing[0].execution_max >= 25ms);
  // The fault's event went to the running process, which did not take it: the task failed with
  // the loop named, where the planner's recovery rules look for a match.
  CHECK_THAT(life.str(), Catch::Contains("motion: missed its deadline 3 times in a row (period 0.010 s, budget 0.010 s)") ||
                             Catch::Contains("missed its deadline 3 times in a row"));
  CHECK_THAT(robot->planner().report().reason, Catch::Contains("module motion failed: missed its deadline"));
}

namespace {

// The hall's nodes for the HRI's task templates, as the robot's Hri module answers them from where
// the robot stands (what the guide application's GuideHri does; read on the sequencing thread).
class HallKnowledge final : public TaskKnowledge {
 public:
  HallKnowledge(const CHri& hri, const Robot& robot) : hri_(hri), robot_(robot) {}
  [[nodiscard]] ListResult list(std::string_view function, std::string_view argument) const override {
    const auto a = hri_.answer(function, argument, robot_.navigation());
    if (!a) return {false, {}, "no " + std::string(function) + "()"};
    return {a->ok, a->items, a->error};
  }

 private:
  const CHri& hri_;
  const Robot& robot_;
};

}  // namespace

TEST_CASE("Jinny on its own threads answers a visitor and guides them to a node at 10 times real time", "[robot][threads]") {
  const auto world = std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/exhibit_hall.yaml"));
  RobotPlugins plugins = builtin_plugins(world);
  const RobotProfile profile = load_robot_profile(kConfigs / "robots/jinny.yaml");
  ScaledClock clock(10.0);
  const auto robot = Robot::assemble(profile, plugins, clock);
  if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(world->start_pose);
  auto* const hri_module = robot->module<CHri>();
  REQUIRE(hri_module != nullptr);

  // The HRI as the guide application runs it on the robot's thread: the module's knowledge store,
  // the hall's nodes, local providers, command inputs to the planner (under the sequencing lock).
  const TaskLibrary tasks = TaskLibrary::load(kConfigs / "tasks/jinny_guide.yaml");
  const HallKnowledge hall(*hri_module, *robot);
  AnswerProviders providers;
  providers.add("time", std::make_unique<ClockTimeProvider>(clock, std::chrono::hours(14)));
  providers.add("battery", std::make_unique<BatteryProvider>([] { return 0.82; }));
  providers.add("weather",
                std::make_unique<WeatherTableProvider>(clock, std::chrono::hours(14), std::vector<std::string>{"sunny"}));
  const TaskStarter start_task = [&](const Understanding& u) -> std::string {
    const CommandAnswer a = robot->planner().command("guide me to node " + u.slots.at("node"));
    return a.accepted ? std::string() : a.text;
  };
  StoreBackedHri service(hri_module->knowledge_store(), tasks, hall, providers, start_task);

  // The visitor's requests, typed on the test's thread, answered on the sequencing thread.
  std::mutex mutex;
  std::vector<std::string> requests{"Introduce yourself.", "Could you guide me to node 1, please?"};
  std::vector<HriReply> replies;
  std::atomic<std::size_t> answered{0};
  std::atomic<bool> moving{false}, busy{false};
  RealtimeOptions ro;
  ro.after_sequencing = [&](Time) {
    {
      const std::lock_guard lock(mutex);
      if (replies.size() < requests.size()) {
        replies.push_back(service.ask(requests[replies.size()]));
        answered.store(replies.size());
      }
    }
    if (robot->behavior_active("BhAutoMove")) moving.store(true);
    busy.store(robot->planner().busy());
  };
  robot->start(ro);
  const bool got_answers = wait_for([&] { return answered.load() == 2; }, 20s);
  const bool got_moving = wait_for([&] { return moving.load(); }, 20s);
  // Guided as far as a few seconds of wall time go (node 1 is some metres away): done or under way.
  (void)wait_for([&] { return moving.load() && !busy.load(); }, 5s);
  robot->stop();
  CHECK_FALSE(robot->started());

  CHECK(got_answers);
  CHECK(got_moving);
  const std::lock_guard lock(mutex);
  REQUIRE(replies.size() == 2);
  CHECK(replies[0].kind == HriReply::Kind::answered);
  CHECK(replies[0].entry_id == "introduce");
  CHECK_THAT(replies[0].text, Catch::StartsWith("Hello, I am Jinny"));
  CHECK(replies[1].kind == HriReply::Kind::task_started);
  CHECK(replies[1].task == "guide");
  const auto& sim = dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator();
  CHECK(sim.distance_m() > 0.5);
  CHECK(sim.collisions() == 0);
  CHECK((robot->planner().state() == TaskState::succeeded || robot->planner().busy()));
}
