// Round trip: a simulated run (BhGoToPose guarded by BhAvoidObstacle, driving at a wall) is recorded
// with TraceRecorder, then the trace is replayed into the same behaviors by the BehaviorHarness:
// the replayed commands equal the recorded ones bit for bit.
#include <catch2/catch.hpp>

#include "../sim/sim_test_util.hpp"
#include "../trace/trace_test_util.hpp"
#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/testing/behavior_harness.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_recorder.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace std::chrono_literals;
using Catch::Contains;

namespace {

constexpr Duration kPeriod = 50ms;

ParameterValues goto_params() {
  // Beyond the east wall (x = 6 m): the robot must be stopped by BhAvoidObstacle.
  return {{"goal_x_m", Value{7.5}}, {"goal_y_m", Value{1.8}}, {"max_speed_m_s", Value{0.6}}, {"stale_timeout_s", Value{1.0}}};
}
ParameterValues avoid_params() {
  return {{"stop_distance_m", Value{0.2}}, {"slow_distance_m", Value{0.9}}, {"max_speed_m_s", Value{0.6}},
          {"robot_radius_m", Value{0.25}}};
}

BaseCapabilities differential_caps() { return BaseCapabilities{1.0, 0.0, 2.0}; }

struct Recorded {
  std::vector<trace::CommandRecord> commands;
  double final_x_m = 0.0;
  std::uint64_t collisions = 0;
  std::size_t channels = 0;
  Duration laser_max_age{0};
};

// The live run: simulator sensors -> resources -> behaviors -> coordinator -> simulator wheels,
// recorded every cycle.
Recorded record_run(const std::filesystem::path& out, double seconds, bool with_noise) {
  sim::World world = sim::test::room_world(120, 60, Pose2D{1.0, 1.5, 0.0});
  if (with_noise) {
    world.robot.laser.noise_stddev_m = 0.01;
    world.robot.odometry.noise_ratio = 0.02;
  }
  sim::Simulator sim(world, sim::test::differential_base(), 42);
  ResourceTable table;
  sim.add_resources(table, /*with_odometry=*/true);

  trace::TraceWriter writer(out);
  trace::TraceRecorder recorder(writer);
  recorder.watch_all(table);
  recorder.record_commands("cmd");
  recorder.record_events("events");

  CBehaviorCoordinator coordinator;
  BhGoToPose go;
  BhAvoidObstacle avoid;
  const InputId go_in = coordinator.add_input({.name = "BhGoToPose", .priority = 1});
  const InputId avoid_in = coordinator.add_input({.name = "BhAvoidObstacle", .priority = 100, .role = InputRole::safety});
  NavigationData navi;
  BehaviorContext ctx{.now = sim.now(), .period = kPeriod, .resources = &table, .navi = &navi, .base = differential_caps()};
  (void)recorder.record(sim.now());
  go.activate(goto_params(), ctx);
  avoid.activate(avoid_params(), ctx);
  Recorded r;
  r.laser_max_age = sim.laser().max_age();
  const Time end = sim.now() + from_seconds(seconds);
  bool first = true, limited = false;
  while (sim.now() <= end) {
    const Time now = sim.now();
    if (!first) (void)recorder.record(now);
    first = false;
    ctx.now = now;
    navi.pose_stamp = now;
    const auto go_cmd = go.step(ctx);
    if (go_cmd) coordinator.submit(go_in, *go_cmd, now);
    else coordinator.withdraw(go_in);
    (void)avoid.step(ctx);
    coordinator.submit_envelope(avoid_in, *avoid.envelope(), now);
    const CoordinatorOutput& fused = coordinator.update(now);
    recorder.record_command(now, fused.command, "coordinator");
    if (fused.safety_limited && !limited) recorder.record_event(now, "safety_limited");
    limited = fused.safety_limited;
    r.commands.push_back({now, fused.command, "coordinator"});
    sim.command_twist(fused.command);
    sim.step(kPeriod);
  }
  writer.close();
  r.final_x_m = sim.pose().x_m;
  r.collisions = sim.collisions();
  r.channels = writer.channels().size();
  return r;
}

testing::RunLog replay(const std::filesystem::path& trace_path, const Recorded& rec) {
  testing::BehaviorHarness h({.period = kPeriod, .base = differential_caps(), .resource_max_age = rec.laser_max_age});
  h.load_trace(trace_path);
  h.attach(std::make_unique<BhGoToPose>(), goto_params(), {.name = "BhGoToPose", .priority = 1});
  h.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), {.name = "BhAvoidObstacle", .priority = 100, .role = InputRole::safety});
  return h.run(rec.commands.back().stamp);
}

}  // namespace

TEST_CASE("round trip: a recorded simulated run replays into the same commands, bit for bit", "[testing][round_trip]") {
  for (const bool noise : {false, true}) {
    DYNAMIC_SECTION("sensor noise " << noise) {
      trace::test::TempFile file("round_trip");
      const Recorded rec = record_run(file.path(), 12.0, noise);
      // The run is worth comparing: the robot drove most of the way to the wall and was stopped
      // by the safety override without touching it.
      REQUIRE(rec.commands.size() == 241);
      CHECK(rec.final_x_m > 4.5);
      CHECK(rec.collisions == 0);
      std::size_t moving = 0;
      for (const auto& c : rec.commands) moving += c.twist.vx_m_s > 0.05 ? 1u : 0u;
      CHECK(moving > 100);
      CHECK(rec.commands.back().twist.vx_m_s < 0.01);

      const testing::RunLog run = replay(file.path(), rec);
      // The trace carries the live commands; both they and the in-memory copy equal the replay's.
      REQUIRE(run.recorded_commands().size() == rec.commands.size());
      const testing::CheckResult same = run.commands_equal(rec.commands);
      INFO(same);
      CHECK(same);
      CHECK(run.commands_equal(run.recorded_commands()));
      CHECK(run.event_before("trace:safety_limited", rec.commands.back().stamp));
      CHECK(run.never_drives_toward_obstacle_closer_than(0.2));

      // Replayed into a behavior with other parameters, the commands differ: the comparison can fail.
      testing::BehaviorHarness other({.period = kPeriod, .base = differential_caps(), .resource_max_age = rec.laser_max_age});
      other.load_trace(file.path());
      ParameterValues p = goto_params();
      p["max_speed_m_s"] = Value{0.5};
      other.attach(std::make_unique<BhGoToPose>(), p, {.priority = 1});
      other.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), {.priority = 100, .role = InputRole::safety});
      const testing::CheckResult differs = other.run(rec.commands.back().stamp).commands_equal(rec.commands);
      CHECK_FALSE(differs);
      CHECK_THAT(differs.explanation, Contains("differs"));
    }
  }
}

TEST_CASE("recorder: writes each reading once per publish, with its own stamp, and refuses misuse", "[testing][recorder]") {
  trace::test::TempFile file("recorder");
  LaserResource laser("front_laser");
  OdometryResource odom("odom");
  {
    trace::TraceWriter w(file.path());
    trace::TraceRecorder rec(w);
    CHECK(rec.watch(laser) == 0);
    CHECK(rec.watch(odom) == 1);
    CHECK_THROWS_AS(rec.watch(laser), std::invalid_argument);  // name already declared
    CHECK_THROWS_AS(rec.record_command(Time{}, Twist2D{}, "x"), std::logic_error);
    CHECK_THROWS_AS(rec.record_event(Time{}, "x"), std::logic_error);
    CHECK(rec.record(Time{}) == 0);  // nothing published yet
    LaserScan s;
    s.stamp = Time{5ms};
    s.ranges_m = {1.0f, 2.0f};
    s.range_max_m = 10.0;
    laser.publish(s);
    CHECK(rec.record(Time{10ms}) == 1);
    CHECK(rec.record(Time{20ms}) == 0);  // not republished
    odom.publish(OdometryReading{Time{21ms}, Pose2D{1.0, 2.0, 0.5}, Twist2D{0.1, 0.0, 0.2}});
    s.stamp = Time{25ms};
    laser.publish(s);
    s.stamp = Time{28ms};
    laser.publish(s);  // two publishes between records: the latest is written
    CHECK(rec.record(Time{30ms}) == 2);
    CHECK(rec.readings_written() == 3);
    w.close();
  }
  trace::TraceReader r(file.path());
  trace::TraceRecord rec;
  std::vector<std::pair<trace::ChannelId, Time>> got;
  while (r.next(rec)) got.emplace_back(rec.channel, trace::stamp_of(rec.data));
  CHECK(r.state() == trace::ReadState::kEnd);
  REQUIRE(got.size() == 3);
  CHECK(got[0] == std::pair<trace::ChannelId, Time>{0, Time{5ms}});
  CHECK(got[1] == std::pair<trace::ChannelId, Time>{0, Time{28ms}});
  CHECK(got[2] == std::pair<trace::ChannelId, Time>{1, Time{21ms}});
  REQUIRE(r.channels().size() == 2);
  CHECK(r.channels()[1].kind == trace::ChannelKind::kOdometry);
  CHECK(r.channels()[1].name == "odom");
}
