#include <catch2/catch.hpp>
#include <numeric>

#include "trace_test_util.hpp"
#include "tripodal/trace/trace_replay.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace tripodal::trace;
using namespace tripodal::trace::test;
using namespace std::chrono_literals;

namespace {

// Records what arrives, as "channel:kind@ms".
class RecordingSink final : public TraceSink {
 public:
  std::vector<std::string> got;
  void on_laser(const ChannelInfo& c, const LaserScan& r) override { add(c, "laser", r.stamp); }
  void on_odometry(const ChannelInfo& c, const OdometryReading& r) override { add(c, "odometry", r.stamp); }
  void on_sonar(const ChannelInfo& c, const SonarReading& r) override { add(c, "sonar", r.stamp); }
  void on_infrared(const ChannelInfo& c, const InfraredReading& r) override { add(c, "infrared", r.stamp); }
  void on_bumper(const ChannelInfo& c, const BumperReading& r) override { add(c, "bumper", r.stamp); }
  void on_battery(const ChannelInfo& c, const BatteryReading& r) override { add(c, "battery", r.stamp); }
  void on_gyro(const ChannelInfo& c, const GyroReading& r) override { add(c, "gyro", r.stamp); }
  void on_command(const ChannelInfo& c, const CommandRecord& r) override { add(c, "command:" + r.source, r.stamp); }
  void on_event(const ChannelInfo& c, const EventRecord& r) override { add(c, "event:" + r.name, r.stamp); }

 private:
  void add(const ChannelInfo& c, const std::string& what, Time t) {
    got.push_back(c.name + ":" + what + "@" + std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count()));
  }
};

std::unique_ptr<TraceReader> open(const TempFile& f) { return std::make_unique<TraceReader>(f.path()); }

}  // namespace

TEST_CASE("advance_to delivers every record stamped at or before t, in order, to its callback") {
  TempFile file("replay");
  {
    TraceWriter w(file.path());
    std::vector<ChannelId> ids;
    for (const auto& r : one_of_each(Time{1000ms})) {
      w.write(w.add_channel(std::string(to_string(kind_of(r))), kind_of(r)), r);
    }
  }
  TraceReplay replay(open(file));
  RecordingSink sink;
  CHECK(replay.start_time() == Time{1000ms});
  CHECK(replay.next_stamp() == Time{1000ms});
  CHECK(replay.advance_to(Time{999ms}, sink) == 0);
  CHECK(replay.advance_to(Time{1002ms}, sink) == 3);
  CHECK(sink.got == std::vector<std::string>{"laser:laser@1000", "odometry:odometry@1001", "sonar:sonar@1002"});
  CHECK(replay.advance_to(Time{1002ms}, sink) == 0);
  CHECK(replay.advance_to(Time{2000ms}, sink) == 6);
  CHECK(sink.got.back() == "event:event:bumper_hit@1008");
  CHECK(sink.got[7] == "command:command:BhAvoidObstacle@1007");
  CHECK(replay.finished());
  CHECK(replay.delivered() == 9);
  CHECK_FALSE(replay.next_stamp().has_value());
}

TEST_CASE("a simulated clock drives the replay step by step") {
  TempFile file("replay_sim");
  {
    TraceWriter w(file.path());
    const auto odom = w.add_channel("odom", ChannelKind::kOdometry);
    for (int i = 0; i < 50; ++i) w.write(odom, OdometryReading{Time{i * 20ms}, {}, {}});  // 50 Hz
  }
  TraceReplay replay(open(file));
  SimClock clock;
  RecordingSink sink;
  std::vector<std::size_t> per_step;
  while (!replay.finished()) {
    clock.advance(100ms);  // a 10 Hz control loop
    per_step.push_back(replay.advance_to(clock.now(), sink));
  }
  // Records at 0..100 ms (6), then 5 per 100 ms; the record at 980 ms arrives at t = 1000 ms.
  CHECK(per_step.front() == 6);
  CHECK(per_step.size() == 10);
  CHECK(std::accumulate(per_step.begin(), per_step.end(), std::size_t{0}) == 50);
}

TEST_CASE("out-of-order stamps are delivered in file order and counted") {
  TempFile file("replay_ooo");
  {
    TraceWriter w(file.path());
    const auto ev = w.add_channel("events", ChannelKind::kEvent);
    w.write(ev, EventRecord{Time{10ms}, "a"});
    w.write(ev, EventRecord{Time{30ms}, "b"});
    w.write(ev, EventRecord{Time{20ms}, "c"});
    w.write(ev, EventRecord{Time{40ms}, "d"});
  }
  TraceReplay replay(open(file));
  RecordingSink sink;
  CHECK(replay.advance_to(Time{35ms}, sink) == 3);
  CHECK(sink.got == std::vector<std::string>{"events:event:a@10", "events:event:b@30", "events:event:c@20"});
  CHECK(replay.out_of_order() == 1);
}

TEST_CASE("real-time pacing waits on the injected clock") {
  TempFile file("replay_rt");
  {
    TraceWriter w(file.path());
    const auto odom = w.add_channel("odom", ChannelKind::kOdometry);
    for (int i = 0; i < 11; ++i) w.write(odom, OdometryReading{Time{5s + i * 100ms}, {}, {}});
  }
  SimClock clock(Time{42s});
  Duration slept{0};
  std::vector<Time> delivered_at;
  class AtSink final : public TraceSink {
   public:
    AtSink(const SimClock& c, std::vector<Time>& v) : clock_(c), at_(v) {}
    void on_odometry(const ChannelInfo&, const OdometryReading&) override { at_.push_back(clock_.now()); }

   private:
    const SimClock& clock_;
    std::vector<Time>& at_;
  } sink(clock, delivered_at);

  SECTION("at recorded speed") {
    TraceReplay replay(open(file), TraceReplayOptions{.pacing = ReplayPacing::kRealTime,
                                                      .clock = &clock,
                                                      .sleep = [&](Duration d) {
                                                        slept += d;
                                                        clock.advance(d);
                                                      }});
    CHECK(replay.play(sink) == 11);
    CHECK(slept == 1s);
    REQUIRE(delivered_at.size() == 11);
    CHECK(delivered_at[3] == Time{42s + 300ms});
  }
  SECTION("twice as fast") {
    TraceReplay replay(open(file), TraceReplayOptions{.pacing = ReplayPacing::kRealTime,
                                                      .speed = 2.0,
                                                      .clock = &clock,
                                                      .sleep = [&](Duration d) {
                                                        slept += d;
                                                        clock.advance(d);
                                                      }});
    replay.play(sink);
    CHECK(slept == 500ms);
  }
  SECTION("as fast as possible never sleeps") {
    TraceReplay replay(open(file));
    CHECK(replay.play(sink) == 11);
    CHECK(delivered_at.back() == Time{42s});
  }
  SECTION("real time without a clock is refused") {
    CHECK_THROWS_WITH(TraceReplay(open(file), TraceReplayOptions{.pacing = ReplayPacing::kRealTime}),
                      Catch::Contains("needs a clock and a sleep function"));
  }
}
