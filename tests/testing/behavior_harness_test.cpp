// The behavior test kit on the shipped Intel Research Lab excerpt (tests/data/trace): BhAvoidObstacle
// guarding a cruising behavior, a behavior that succeeds, and bad behaviors every helper must catch.
#include "tripodal/testing/behavior_harness.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>

#include "../trace/trace_test_util.hpp"
#include "test_behaviors.hpp"
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/cdr.hpp"
#include "tripodal/trace/mcap.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace tripodal::testing;
using namespace std::chrono_literals;
using Catch::Contains;
using tripodal::trace::test::TempFile;

namespace {

// The excerpt imported once per test into a temporary trace (channels front_laser, odom, laser_pose).
struct ExcerptTrace {
  TempFile file{"harness_excerpt"};
  ExcerptTrace() {
    trace::TraceWriter w(file.path());
    (void)trace::import_carmen_log(std::filesystem::path(TRIPODAL_TEST_DATA_DIR) / "trace/intel-excerpt.log", w);
    w.close();
  }
};

ParameterValues avoid_params() {
  // Stops 0.7 m short: the excerpt's closest returns ahead are 0.65-0.68 m from a 0.25 m footprint.
  return {{"stop_distance_m", Value{0.7}}, {"slow_distance_m", Value{1.5}}, {"max_speed_m_s", Value{0.5}},
          {"robot_radius_m", Value{0.25}}};
}

CoordinatorInputConfig normal(int priority) { return {.name = {}, .priority = priority}; }
CoordinatorInputConfig safety() { return {.name = {}, .priority = 100, .role = InputRole::safety}; }

}  // namespace

TEST_CASE("harness: BhAvoidObstacle keeps a cruising behavior away from the excerpt's walls", "[testing][harness]") {
  ExcerptTrace excerpt;
  BehaviorHarness h;
  h.load_trace(excerpt.file.path());
  REQUIRE(h.resources().find<LaserScan>("front_laser") != nullptr);
  REQUIRE(h.resources().find<OdometryReading>("odom") != nullptr);
  h.attach(std::make_unique<test::BhBlindCruise>(), {{"speed_m_s", Value{0.6}}}, normal(1));
  h.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), safety());
  const RunLog& run = h.run();

  // The run spans the trace (0.000246 s to 124.453 s) at 20 Hz, plus one period.
  REQUIRE(run.steps().front().t == h.start_time());
  CHECK(to_seconds(run.steps().back().t) == Approx(124.45).margin(0.06));
  CHECK(run.steps().size() == static_cast<std::size_t>((run.steps().back().t - h.start_time()) / 50ms) + 1);

  const CheckResult safe = run.never_drives_toward_obstacle_closer_than(0.7);
  INFO(safe);
  CHECK(safe);
  CHECK_THAT(safe.explanation, Contains("translating commands"));
  CHECK(run.command_never_exceeds({.max_vx_m_s = 0.6, .max_vy_m_s = 0.0, .max_wz_rad_s = 0.0}));
  // BhAvoidObstacle did act: slowed below 0.5 m/s near walls and stopped the robot at least once.
  std::size_t limited = 0, stopped = 0;
  for (const StepRecord& s : run.steps()) {
    if (s.safety_limited) ++limited;
    if (s.command.vx_m_s == 0.0) ++stopped;
    REQUIRE(s.behaviors.size() == 2);
    REQUIRE(s.behaviors[1].envelope.has_value());
  }
  CHECK(limited > 100);
  CHECK(stopped > 0);
  // ... so a tighter limit than the cruise speed is violated where the way is free.
  const CheckResult too_fast = run.command_never_exceeds({.max_vx_m_s = 0.5});
  CHECK_FALSE(too_fast);
  CHECK_THAT(too_fast.explanation, Contains("exceeds the limits (|vx| <= 0.5") && Contains("vx 0.6 m/s"));
  CHECK(run.never_fails("BhAvoidObstacle"));
  CHECK(run.status_at("BhAvoidObstacle", Time{60s}) == BehaviorStatus::running);
}

TEST_CASE("harness: the obstacle helper fails on a behavior that drives blind", "[testing][harness]") {
  ExcerptTrace excerpt;
  BehaviorHarness h;
  h.load_trace(excerpt.file.path());
  h.attach(std::make_unique<test::BhBlindCruise>(), {{"speed_m_s", Value{0.6}}});
  const RunLog& run = h.run();
  const CheckResult r = run.never_drives_toward_obstacle_closer_than(0.7);
  CHECK_FALSE(r);
  // The scan stamped 36.46 s has a return 0.677 m ahead of the footprint (0.73 m in the scan before).
  CHECK_THAT(r.explanation, Contains("at t=36.4") || Contains("at t=36.5"));
  CHECK_THAT(r.explanation, Contains("closer than 0.7 m"));
  // With the blind behavior as well the helper passes for a distance below every return ahead.
  CHECK(run.never_drives_toward_obstacle_closer_than(0.6));
  // A command limit it breaks from the first step.
  const CheckResult fast = run.command_never_exceeds({.max_vx_m_s = 0.3});
  CHECK_FALSE(fast);
  CHECK_THAT(fast.explanation, Contains(std::to_string(run.steps().size()) + " of " + std::to_string(run.steps().size())));
}

TEST_CASE("harness: succeeds_before and events of a behavior that finishes", "[testing][harness]") {
  ExcerptTrace excerpt;
  BehaviorHarness h;
  h.load_trace(excerpt.file.path());
  h.attach(std::make_unique<test::BhStopAtWall>(), {{"stop_distance_m", Value{1.0}}});
  const RunLog& run = h.run(std::nullopt, /*stop_when_done=*/true);
  // Clearances ahead: 1.775 m in the scan of 32.91 s, 0.73 m in the scan of 35.11 s.
  const CheckResult ok = run.succeeds_before("BhStopAtWall", Time{36s});
  INFO(ok);
  CHECK(ok);
  const CheckResult late = run.succeeds_before("BhStopAtWall", Time{35s});
  CHECK_FALSE(late);
  CHECK_THAT(late.explanation, Contains("succeeded at t=35.1") && Contains("after 35.000 s"));
  CHECK(run.event_before("BhStopAtWall.done", Time{36s}));
  CHECK_FALSE(run.event_before("BhStopAtWall.done", Time{35s}));
  CHECK_FALSE(run.event_before("BhStopAtWall.failed", Time{200s}));
  CHECK(run.never_fails("BhStopAtWall"));
  // stop_when_done: the run ended at the success, long before the trace.
  CHECK(to_seconds(run.steps().back().t) < 36.0);
  CHECK(run.status_at("BhStopAtWall", Time{30s}) == BehaviorStatus::running);
  CHECK(run.status_at("BhStopAtWall", Time{40s}) == BehaviorStatus::succeeded);
}

TEST_CASE("harness: helpers report a failing behavior and unknown names", "[testing][harness]") {
  ExcerptTrace excerpt;
  BehaviorHarness h;
  h.load_trace(excerpt.file.path());
  h.attach(std::make_unique<test::BhStopAtWall>(), {{"laser", Value{std::string("rear_laser")}}});
  const RunLog& run = h.run(h.start_time() + 1s);
  const CheckResult never = run.never_fails("BhStopAtWall");
  CHECK_FALSE(never);
  CHECK_THAT(never.explanation, Contains("failed at t=0.000 s: no laser resource"));
  const CheckResult succ = run.succeeds_before("BhStopAtWall", Time{100s});
  CHECK_FALSE(succ);
  CHECK_THAT(succ.explanation, Contains("failed at") && Contains("no laser resource"));
  const CheckResult unknown = run.succeeds_before("BhNope", Time{100s});
  CHECK_FALSE(unknown);
  CHECK_THAT(unknown.explanation, Contains("no behavior named 'BhNope'") && Contains("BhStopAtWall"));
  // A behavior that never finishes is reported with its last status.
  BehaviorHarness h2;
  h2.load_trace(excerpt.file.path());
  h2.attach(std::make_unique<test::BhBlindCruise>());
  const CheckResult never_done = h2.run(h2.start_time() + 2s).succeeds_before("BhBlindCruise", Time{100s});
  CHECK_FALSE(never_done);
  CHECK_THAT(never_done.explanation, Contains("never succeeded in 41 steps") && Contains("last status: running"));
}

TEST_CASE("harness: two runs of the same trace give the same commands, and run() continues", "[testing][harness]") {
  ExcerptTrace excerpt;
  auto run_once = [&](std::optional<Time> until) {
    BehaviorHarness h;
    h.load_trace(excerpt.file.path());
    h.attach(std::make_unique<test::BhBlindCruise>(), {}, normal(1));
    h.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), safety());
    if (until) {
      (void)h.run(*until);
      REQUIRE(h.log().steps().back().t <= *until);
    }
    std::vector<trace::CommandRecord> out;
    for (const auto& s : h.run().steps()) out.push_back({s.t, s.command, "fused"});
    return out;
  };
  const auto a = run_once(std::nullopt);
  const auto b = run_once(Time{60s});  // stopped half way, then continued
  REQUIRE(a.size() == b.size());
  BehaviorHarness h;
  h.load_trace(excerpt.file.path());
  h.attach(std::make_unique<test::BhBlindCruise>(), {}, normal(1));
  h.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), safety());
  const RunLog& run = h.run();
  CHECK(run.commands_equal(b));
  // A changed command is found and named.
  auto c = b;
  c[700].twist.vx_m_s += 1e-12;
  const CheckResult diff = run.commands_equal(c);
  CHECK_FALSE(diff);
  CHECK_THAT(diff.explanation, Contains("command 700 differs"));
  c.pop_back();
  c[700] = b[700];
  CHECK_THAT(run.commands_equal(c).explanation, Contains("were expected and"));
}

TEST_CASE("harness: bad traces, bad parameters and misuse are reported", "[testing][harness]") {
  BehaviorHarness h;
  CHECK_THROWS_AS(h.run(), std::logic_error);
  CHECK_THROWS_AS(h.load_trace("/nonexistent/tripodal/trace.trp"), trace::TraceIoError);
  CHECK_THROWS_WITH(h.load_trace(std::filesystem::path(TRIPODAL_TEST_DATA_DIR) / "trace/intel-excerpt.log"),
                    Contains("byte 0") && Contains("not a tripodal trace"));
  CHECK_THROWS_AS(BehaviorHarness(HarnessOptions{.period = Duration{0}}), std::invalid_argument);

  ExcerptTrace excerpt;
  HarnessOptions o;
  o.laser = "no_such_laser";
  BehaviorHarness missing(o);
  CHECK_THROWS_WITH(missing.load_trace(excerpt.file.path()), Contains("no laser channel 'no_such_laser'"));

  BehaviorHarness bad;
  bad.load_trace(excerpt.file.path());
  bad.attach(std::make_unique<BhAvoidObstacle>(), {{"stop_distance_m", Value{std::string("far")}}}, safety(),
             SourceLocation{"my_test.yaml", 3, 7});
  CHECK_THROWS_WITH(bad.run(), Contains("my_test.yaml:3:7") && Contains("stop_distance_m"));
  CHECK_THROWS_AS(bad.attach(std::make_unique<BhStop>()), std::logic_error);
}

TEST_CASE("harness: damaged traces are refused at load with the byte offset, a cut one replays to its last record",
          "[testing][harness][errors]") {
  ExcerptTrace excerpt;
  const auto bytes = trace::test::read_all(excerpt.file.path());
  std::vector<std::uint64_t> offsets;
  Time stamp_of_last_whole{};
  {
    trace::TraceReader r(excerpt.file.path());
    trace::TraceRecord rec;
    while (r.next(rec)) offsets.push_back(rec.offset);
  }
  REQUIRE(offsets.size() > 650);  // 690 records: the 29 odometry echoes are dropped on import
  TempFile bad("harness_bad");

  SECTION("wrong version") {
    auto b = bytes;
    b[8] = 7;
    trace::test::write_all(bad.path(), b, b.size());
    BehaviorHarness h;
    CHECK_THROWS_WITH(h.load_trace(bad.path()), Contains("byte 8: trace format version 7 is not supported"));
  }
  SECTION("a corrupted record deep in the file fails the first pass, before any behavior runs") {
    auto b = bytes;
    const std::uint64_t at = offsets[500];
    b[at + 8 + 12] ^= 0x20;
    trace::test::write_all(bad.path(), b, b.size());
    BehaviorHarness h;
    CHECK_THROWS_WITH(h.load_trace(bad.path()), Contains("byte " + std::to_string(at) + ": record checksum mismatch"));
    CHECK_THROWS_AS(h.run(), std::logic_error);  // nothing loaded
  }
  SECTION("a recorder killed mid-write: replayed up to the last whole record, with the warning") {
    const std::uint64_t cut = offsets[600] + 5;  // inside record 600's frame
    trace::test::write_all(bad.path(), bytes, cut);
    {
      trace::TraceReader r(bad.path());
      trace::TraceRecord rec;
      while (r.next(rec)) stamp_of_last_whole = trace::stamp_of(rec.data);
    }
    BehaviorHarness h;
    h.load_trace(bad.path());
    CHECK_THAT(h.trace_warning(), Contains("truncated at byte " + std::to_string(offsets[600])));
    CHECK(h.end_time() == stamp_of_last_whole);
    h.attach(std::make_unique<test::BhBlindCruise>());
    const RunLog& run = h.run();
    CHECK(run.steps().back().t <= stamp_of_last_whole + 50ms);
    CHECK(run.steps().back().t > stamp_of_last_whole);
    BehaviorHarness whole;
    whole.load_trace(excerpt.file.path());
    CHECK(whole.trace_warning().empty());
    CHECK(whole.end_time() > h.end_time());
  }
}

TEST_CASE("harness: a pose channel of the trace localizes map-frame behaviors", "[testing][harness]") {
  ExcerptTrace excerpt;
  // The corrected Intel log's laser poses are SLAM-corrected map poses; the first comes with the
  // first scan at 33.1 s. A goal 1 m ahead of that pose is in the map frame.
  const ParameterValues go = {{"frame", Value{std::string("map")}}, {"goal_x_m", Value{1.0}}, {"goal_y_m", Value{0.0}},
                              {"stale_timeout_s", Value{40.0}}};
  SECTION("without it the behavior is never localized") {
    BehaviorHarness h;
    h.load_trace(excerpt.file.path());
    h.attach(std::make_unique<BhGoToPose>(), go);
    const CheckResult r = h.run().never_fails("BhGoToPose");
    CHECK_FALSE(r);
    CHECK_THAT(r.explanation, Contains("failed at t=40.0") && Contains("not localized"));
  }
  SECTION("with laser_pose it drives once the first pose arrives") {
    BehaviorHarness h({.localization_channel = "laser_pose"});
    h.load_trace(excerpt.file.path());
    h.attach(std::make_unique<BhGoToPose>(), go);
    const RunLog& run = h.run(h.start_time() + 40s);
    CHECK(run.never_fails("BhGoToPose"));
    std::size_t driving = 0;
    for (const auto& s : run.steps()) {
      if (s.command.vx_m_s != 0.0 || s.command.wz_rad_s != 0.0) {
        ++driving;
        CHECK(to_seconds(s.t) > 33.0);
      }
    }
    CHECK(driving > 0);
  }
  SECTION("a missing channel is refused before anything is created") {
    BehaviorHarness h({.localization_channel = "slam_pose"});
    CHECK_THROWS_WITH(h.load_trace(excerpt.file.path()), Contains("no odometry channel 'slam_pose'"));
    CHECK(h.resources().size() == 0);
  }
}

TEST_CASE("harness: resource_max_age makes sparse scans go stale, and BhAvoidObstacle then blocks translation",
          "[testing][harness]") {
  ExcerptTrace excerpt;
  BehaviorHarness h({.resource_max_age = 500ms});
  h.load_trace(excerpt.file.path());
  h.attach(std::make_unique<test::BhBlindCruise>(), {}, normal(1));
  h.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), safety());
  const RunLog& run = h.run();
  std::size_t moving = 0;
  for (const StepRecord& s : run.steps()) {
    if (s.command.vx_m_s > 0.0) {
      ++moving;
      // Only within 0.5 s of a scan, and never before the first one (33.1 s).
      CHECK(to_seconds(s.t) > 33.0);
    }
  }
  // 30 scans, each fresh for at most 11 periods of 50 ms.
  CHECK(moving > 0);
  CHECK(moving <= 30u * 11u);
  CHECK(run.never_drives_toward_obstacle_closer_than(0.7));
}

TEST_CASE("harness: a rosbag2 bag loads where a trace does (converted with the default topic mapping)",
          "[testing][harness][rosbag]") {
  TempFile bag{"harness_bag"};  // no extension: the MCAP magic tells
  {
    trace::mcap::Writer w(bag.path());
    const auto scan_ch = w.add_channel("/scan", "cdr", w.add_schema("sensor_msgs/msg/LaserScan", "ros2msg", ""));
    const auto odom_ch = w.add_channel("/odom", "cdr", w.add_schema("nav_msgs/msg/Odometry", "ros2msg", ""));
    trace::ros::LaserScan scan;
    scan.angle_min = -1.5f;
    scan.angle_max = 1.5f;
    scan.angle_increment = 0.1f;
    scan.range_max = 10.0f;
    scan.ranges.assign(31, 0.6f);  // a wall 0.6 m away all round
    trace::ros::Odometry odom;
    for (int i = 0; i <= 10; ++i) {
      const std::int64_t ns = 1'000'000'000 + i * 100'000'000LL;
      scan.header.stamp = {static_cast<std::int32_t>(ns / 1'000'000'000), static_cast<std::uint32_t>(ns % 1'000'000'000)};
      odom.header.stamp = scan.header.stamp;
      w.write(scan_ch, static_cast<std::uint64_t>(ns), 0, trace::ros::encode_cdr(scan));
      w.write(odom_ch, static_cast<std::uint64_t>(ns), 0, trace::ros::encode_cdr(odom));
    }
    w.close();
  }
  BehaviorHarness h;
  h.load_trace(bag.path());
  REQUIRE(h.resources().find<LaserScan>("laser") != nullptr);
  REQUIRE(h.resources().find<OdometryReading>("odometry") != nullptr);
  h.attach(std::make_unique<test::BhBlindCruise>(), {{"speed_m_s", Value{0.6}}}, normal(1));
  h.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), safety());
  const RunLog& run = h.run();
  CHECK(to_seconds(h.start_time()) == Approx(1.0));
  CHECK(run.steps().size() == 22);  // 1.0 s to 2.0 s at 20 Hz, plus one period
  // The wall is inside the stop distance: the safety behavior holds the robot still throughout.
  for (const auto& step : run.steps()) CHECK(step.command.vx_m_s <= 0.0);
}
