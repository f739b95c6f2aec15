// The whole-robot test kit: the PSR-2 demo robot (configs/robots/psr2.yaml, its nets, modules and
// behaviors) records a patrol on the simulator; the trace is then replayed open loop into a new
// robot of the same profile (the same task must succeed on the recorded sensors alone, with the
// recorded commands), cut short (the task must not succeed), and used as the start of a closed
// loop on the simulator (the robot starts at the recorded pose, the world reacts).
#include "tripodal/testing/robot_harness.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <map>

#include "../trace/trace_test_util.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_recorder.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace std::chrono_literals;
using Catch::Contains;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
constexpr const char* kTask = "patrol door_2111";

std::shared_ptr<const sim::World> workspace() {
  static const auto w = std::make_shared<const sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml"));
  return w;
}

struct Recording {
  std::vector<trace::CommandRecord> commands;
  Pose2D start, end;
  Time finished{};
  bool succeeded = false;
};

// PSR-2 with the ground-truth test double in place of its scan-matching localizer: these tests
// are about the harness (a replay gives the localizer the recorded true poses, so the replayed
// robot commands what the recorded one did), not about localization.
RobotProfile psr2() {
  RobotProfile p = load_robot_profile(kConfigs / "robots/psr2.yaml");
  for (ModuleEntry& e : p.navigation) {
    if (e.name != "localizer") continue;
    e.type = "GroundTruthLocalizer";
    e.parameters = {{"noise_xy_m", "0.005"}, {"noise_theta_rad", "0.005"}};
  }
  return p;
}

// The live run: the simulated PSR-2 patrols to door_2111; every behavior-loop period the recorder
// writes its sensors, the true pose (channel "truth") and the fused command.
Recording record_patrol(const std::filesystem::path& out) {
  RobotPlugins plugins;
  register_all(plugins, workspace());
  SimClock clock;
  auto robot = Robot::assemble(psr2(), plugins, clock);
  auto& sim = dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator();
  robot->behavior_loop().controller()->reset_odometry(sim.pose());

  OdometryResource truth("truth");
  trace::TraceWriter writer(out);
  trace::TraceRecorder recorder(writer);
  recorder.watch_all(robot->resources());
  recorder.watch(truth);
  recorder.record_commands("cmd");

  Recording rec;
  rec.start = sim.pose();
  auto sample = [&] {
    truth.publish(OdometryReading{clock.now(), sim.pose(), {}});
    (void)recorder.record(clock.now());
  };
  robot->run_until(clock.now());
  sample();
  REQUIRE(robot->command(kTask).accepted);
  while (robot->planner().busy() && clock.now() < time_from_seconds(120.0)) {
    robot->run_for(10ms);
    sample();
    recorder.record_command(clock.now(), robot->behavior_loop().last_cycle().coordinator.command, "coordinator");
    rec.commands.push_back({clock.now(), robot->behavior_loop().last_cycle().coordinator.command, "coordinator"});
  }
  // A second of the robot standing at the goal, as a recorder would keep running.
  for (int i = 0; i < 100; ++i) {
    robot->run_for(10ms);
    sample();
  }
  writer.close();
  rec.succeeded = robot->planner().report().state == TaskState::succeeded;
  rec.finished = robot->planner().report().finished.value_or(Time{});
  rec.end = sim.pose();
  return rec;
}

const Recording& recorded(const std::filesystem::path*& trace_out) {
  static trace::test::TempFile file("robot_harness");
  static const Recording rec = record_patrol(file.path());
  trace_out = &file.path();
  return rec;
}

testing::RobotHarnessOptions options() {
  testing::RobotHarnessOptions o;
  o.localization_channel = "truth";
  o.world = workspace();
  return o;
}


double distance(const Pose2D& a, const Pose2D& b) { return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m); }

}  // namespace

TEST_CASE("robot harness, replay: the recorded patrol succeeds again on the recorded sensors", "[testing][robot_harness]") {
  const std::filesystem::path* trace = nullptr;
  const Recording& rec = recorded(trace);
  // The recording is worth replaying: the robot drove the ~8 m to the door and the task ended.
  REQUIRE(rec.succeeded);
  REQUIRE(distance(rec.start, rec.end) > 6.0);

  testing::RobotHarness h(testing::RobotHarness::Mode::replay, psr2(), builtin_plugins(), *trace, options());
  CHECK(h.robot().hardware()->manifest().name == "trace");
  CHECK(distance(h.start_pose(), rec.start) < 1e-9);
  REQUIRE(h.command(kTask).accepted);
  const testing::RunLog& log = h.run();

  CHECK(log.event_before("task.succeeded", rec.finished + 1s));
  CHECK(log.event_before("PrAutoMove.started", h.start_time() + 1s));
  CHECK(log.event_before("PrAutoMove.succeeded", rec.finished + 1s));
  CHECK(log.event_never_happens("PrAutoMove.failed"));
  CHECK(log.event_never_happens("task.failed"));
  CHECK(log.succeeds_before("BhAutoMove", rec.finished + 1s));
  CHECK(log.never_fails("BhAutoMove"));
  CHECK(log.status_at("BhAutoMove", h.start_time() + 2s) == BehaviorStatus::running);
  CHECK(log.status_at("BhCleaning", h.start_time() + 2s) == BehaviorStatus::idle);
  CHECK(log.command_never_exceeds({.max_vx_m_s = 0.6, .max_vy_m_s = 0.6, .max_wz_rad_s = 1.6}));
  CHECK(log.never_drives_toward_obstacle_closer_than(0.02, 0.05));

  // The robot saw what the recorded one saw (its sensors, and the recorded poses through a
  // localizer seeded alike), so it planned the same path and commanded, period by period, what the
  // recorded one commanded.
  CHECK(log.commands_equal(rec.commands));
}

TEST_CASE("robot harness, replay: a trace cut before the goal does not let the task succeed", "[testing][robot_harness]") {
  const std::filesystem::path* trace = nullptr;
  (void)recorded(trace);
  // The first 5 s of the recording, rewritten record by record.
  trace::test::TempFile cut("robot_harness_cut");
  {
    trace::TraceReader reader(*trace);
    trace::TraceWriter writer(cut.path());
    trace::TraceRecord r;
    std::map<trace::ChannelId, trace::ChannelId> ids;
    while (reader.next(r)) {
      if (trace::stamp_of(r.data) > time_from_seconds(5.0)) break;
      if (!ids.contains(r.channel)) {
        const trace::ChannelInfo& c = reader.channel(r.channel);
        ids[r.channel] = writer.add_channel(c.name, c.kind);
      }
      writer.write(ids[r.channel], r.data);
    }
    writer.close();
  }
  testing::RobotHarness h(testing::RobotHarness::Mode::replay, psr2(), builtin_plugins(), cut.path(), options());
  REQUIRE(h.command(kTask).accepted);
  const testing::RunLog& log = h.run(time_from_seconds(60.0));
  // The replay ends with the trace, the robot still on its way.
  CHECK(h.now() <= time_from_seconds(5.0) + 20ms);
  CHECK(h.robot().planner().busy());
  const testing::CheckResult r = log.event_before("task.succeeded", time_from_seconds(60.0));
  CHECK_FALSE(r);
  CHECK_THAT(r.explanation, Contains("never happened"));
  CHECK(log.status_at("BhAutoMove", h.now()) == BehaviorStatus::running);
}

TEST_CASE("robot harness, closed loop: the robot starts at the recorded pose and the world reacts", "[testing][robot_harness]") {
  const std::filesystem::path* trace = nullptr;
  const Recording& rec = recorded(trace);
  // A world whose own start is elsewhere: the harness must put the robot at the trace's start.
  sim::World moved = *workspace();
  moved.start_pose = Pose2D{3.0, 3.0, 1.0};
  testing::RobotHarnessOptions o = options();
  o.world = std::make_shared<const sim::World>(moved);
  testing::RobotHarness h(testing::RobotHarness::Mode::closed_loop, psr2(), builtin_plugins(), *trace, o);
  auto& sim = dynamic_cast<sim::SimHardware&>(*h.robot().hardware()).simulator();
  CHECK(distance(sim.pose(), rec.start) < 1e-9);
  CHECK(h.now() == h.start_time());

  // Another goal than the recorded one: the simulated world, not the trace, moves the robot.
  REQUIRE(h.command("patrol entrance").accepted);
  const testing::RunLog& log = h.run(h.start_time() + 90s);
  CHECK(log.event_before("task.succeeded", h.start_time() + 90s));
  CHECK(log.never_fails("BhAutoMove"));
  const Pose2D entrance{5.0, 0.6, 1.5708};
  CHECK(distance(sim.pose(), entrance) < 0.3);
  CHECK(sim.collisions() == 0);
}

TEST_CASE("robot harness: bad traces and options are refused, naming what is wrong", "[testing][robot_harness]") {
  const std::filesystem::path* trace = nullptr;
  (void)recorded(trace);
  testing::RobotHarnessOptions o = options();
  o.localization_channel = "amcl_pose";
  REQUIRE_THROWS_WITH(testing::RobotHarness(testing::RobotHarness::Mode::replay, psr2(), builtin_plugins(), *trace, o),
                      Contains("has no odometry channel 'amcl_pose'"));
  o = options();
  o.world = nullptr;
  REQUIRE_THROWS_WITH(testing::RobotHarness(testing::RobotHarness::Mode::closed_loop, psr2(), builtin_plugins(), *trace, o),
                      Contains("needs a simulated world"));
  // A shared-library plugin the harness is told to load, refused as `tripodal run --plugin` refuses it.
  o = options();
  o.plugins = {TRIPODAL_TEST_PLUGIN_THROWING};
  REQUIRE_THROWS_WITH(testing::RobotHarness(testing::RobotHarness::Mode::replay, psr2(), builtin_plugins(), *trace, o),
                      Contains("--plugin: error: plugin '" TRIPODAL_TEST_PLUGIN_THROWING
                               "' failed to register its types: the licence file /etc/waver.lic is missing"));

  trace::test::TempFile empty("robot_harness_empty");
  {
    trace::TraceWriter writer(empty.path());
    writer.close();
  }
  REQUIRE_THROWS_WITH(
      testing::RobotHarness(testing::RobotHarness::Mode::replay, psr2(), builtin_plugins(), empty.path(), options()),
      Contains("has no records"));

  trace::test::TempFile missing("robot_harness_missing");
  REQUIRE_THROWS_WITH(
      testing::RobotHarness(testing::RobotHarness::Mode::replay, psr2(), builtin_plugins(), missing.path(), options()),
      Contains(missing.str()));

  // Corrupt in the middle: the replay stops there and says where.
  trace::test::TempFile corrupt("robot_harness_corrupt");
  std::vector<std::uint8_t> bytes = trace::test::read_all(*trace);
  REQUIRE(bytes.size() > 100000);
  for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 64; ++i) bytes[i] ^= 0x5a;
  {
    std::ofstream f(corrupt.path(), std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  }
  REQUIRE_THROWS_WITH(
      testing::RobotHarness(testing::RobotHarness::Mode::replay, psr2(), builtin_plugins(), corrupt.path(), options()),
      Contains("byte"));
}
