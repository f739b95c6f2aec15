// Control loops: behaviors -> coordinator -> controller on simulated time, supervisor-side
// activation and events, several loops with different periods, the threaded runner's skip policy.
#include "tripodal/reactive/control_loop.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <thread>

#include "../support/builtin_registries.hpp"
#include "reactive_rig.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/behaviors/gesture_behaviors.hpp"
#include "tripodal/controllers/kinematics.hpp"
#include "tripodal_reactive_internal/sim_loop_driver.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

constexpr double kPi = std::numbers::pi;

struct GoalRun {
  Pose2D final_pose;
  std::vector<LoopEvent> events;
  double max_abs_vy = 0.0;
  int cycles = 0;
};

// Drives a base to (x, y, theta) with BhGoToPose under a control loop stepped by simulated time.
// The behavior code and its parameters are the same whatever the base.
GoalRun drive_to(const ControllerConfig& base, Pose2D goal) {
  SimClock clock;
  OdometryResource odom("odom", 50ms);
  ResourceTable resources;
  resources.add(odom);
  IdealWheelHardware hw(base.type == "differential" ? 2 : base.holonomic.wheels.size(), base.period);
  CoordinatorConfig cc;
  cc.inputs = {{"BhGoToPose", 10, 100ms}, {"BhStop", 0, 0ms}};
  ControlLoopOptions o;
  o.name = "motion";
  o.period = base.period;
  ControlLoop loop(o, resources, CBehaviorCoordinator(cc), test::builtin_controllers().create(base, hw));
  loop.set_odometry_output(&odom);
  SimLoopDriver driver(clock);
  driver.add(loop);
  loop.activate(test::builtin_behaviors().create("BhStop"), {});
  loop.activate(test::builtin_behaviors().create("BhGoToPose"), {{"goal_x_m", Value{goal.x_m}},
                                                                 {"goal_y_m", Value{goal.y_m}},
                                                                 {"goal_theta_rad", Value{goal.theta_rad}},
                                                                 {"position_tolerance_m", Value{0.02}},
                                                                 {"heading_tolerance_rad", Value{0.02}}});
  GoalRun run;
  for (int k = 0; k < 6000 && run.events.empty(); ++k) {
    driver.run_for(base.period);
    loop.collect_events(run.events);
    run.max_abs_vy = std::max(run.max_abs_vy, std::abs(loop.controller()->limited_command().vy_m_s));
    ++run.cycles;
  }
  // Let the stop behavior bring the base to rest, then read where it is.
  for (int k = 0; k < 100; ++k) driver.run_for(base.period);
  run.final_pose = loop.controller()->odometry().pose;
  return run;
}

}  // namespace

TEST_CASE("The same behavior drives an omni and a differential base to a goal pose") {
  const Pose2D goal{1.5, -0.8, 2.0};
  const GoalRun omni = drive_to(test::omni_base_psr(), goal);
  const GoalRun diff = drive_to(test::differential_base(), goal);
  for (const GoalRun* r : {&omni, &diff}) {
    REQUIRE(r->events.size() == 1);
    CHECK(r->events[0].kind == LoopEvent::Kind::behavior_succeeded);
    CHECK(r->events[0].event_name() == "BhGoToPose.done");
    CHECK(std::hypot(r->final_pose.x_m - goal.x_m, r->final_pose.y_m - goal.y_m) < 0.05);
    CHECK(std::abs(wrap_angle(r->final_pose.theta_rad - goal.theta_rad)) < 0.05);
  }
  // The omni base moved sideways; the differential base never did, and steered instead.
  CHECK(omni.max_abs_vy > 0.1);
  CHECK(diff.max_abs_vy == 0.0);
  CHECK(omni.cycles < diff.cycles);
}

TEST_CASE("Activation, replacement, deactivation and status through the loop") {
  test::ReactiveRig rig(test::differential_base(), CoordinationMode::priority);
  ControlLoop& loop = *rig.loop;
  const BehaviorRegistry& reg = test::builtin_behaviors();
  const BehaviorHandle stop = loop.activate(reg.create("BhStop"), {}, "stop");
  CHECK(loop.status(stop) == BehaviorStatus::running);
  rig.cycle();
  CHECK(loop.last_cycle().coordinator.winner == "stop");
  CHECK(loop.last_cycle().active_behaviors == 1);

  const BehaviorHandle go = loop.activate(reg.create("BhGoToPose"), {{"goal_x_m", Value{0.5}}}, "goto_a");
  rig.cycle();
  CHECK(loop.last_cycle().coordinator.winner == "goto_a");
  // Replacing the behavior on an input: the old handle goes stale.
  const BehaviorHandle go2 = loop.activate(reg.create("BhRotateInPlace"), {{"angle_rad", Value{1.0}}}, "goto_a");
  CHECK_FALSE(loop.status(go).has_value());
  CHECK_FALSE(loop.deactivate(go));
  rig.cycle();
  CHECK(loop.last_cycle().active_behaviors == 2);
  CHECK(loop.deactivate(go2));
  rig.cycle();
  CHECK(loop.last_cycle().coordinator.winner == "stop");
  CHECK(loop.deactivate("stop"));
  CHECK_FALSE(loop.deactivate("stop"));
  rig.cycle();
  CHECK(loop.last_cycle().coordinator.all_expired);
  CHECK(loop.last_cycle().active_behaviors == 0);
  (void)stop;

  // Deactivating before the loop ever ran it.
  const BehaviorHandle quick = loop.activate(reg.create("BhStop"), {}, "stop");
  CHECK(loop.deactivate(quick));
  rig.cycle();
  CHECK(loop.last_cycle().active_behaviors == 0);

  CHECK_THROWS_WITH(loop.activate(reg.create("BhStop"), {}), Catch::Contains("no input named 'BhStop'"));
  CHECK_THROWS_WITH(loop.activate(reg.create("BhGoToPose"), {{"speed", Value{1.0}}}, "goto_a", {"PrAutoMove.xml", 3, 9}),
                    Catch::Contains("PrAutoMove.xml:3:9") && Catch::Contains("unknown parameter 'speed'"));
  CHECK_THROWS_WITH(loop.set_lock("nope", true, Time{0ms}), Catch::Contains("no coordinator lock named 'nope'"));
}

TEST_CASE("Behavior outcomes become supervisor events, a failure carries its reason") {
  test::ReactiveRig rig(test::omni_base_psr(), CoordinationMode::priority);
  ControlLoop& loop = *rig.loop;
  const BehaviorRegistry& reg = test::builtin_behaviors();
  loop.activate(reg.create("BhRotateInPlace"), {{"angle_rad", Value{0.5}}}, "rotate_a");
  loop.activate(reg.create("BhGoToPose"), {{"frame", Value{std::string("map")}}, {"stale_timeout_s", Value{0.05}}}, "goto_a");
  std::vector<LoopEvent> events;
  for (int k = 0; k < 500; ++k) {
    rig.cycle();
    loop.collect_events(events);
  }
  REQUIRE(events.size() == 2);
  // Not localized: BhGoToPose fails first, after its 50 ms of grace.
  CHECK(events[0].event_name() == "BhGoToPose.failed");
  CHECK(events[0].reason == "not localized");
  CHECK(events[0].input == "goto_a");
  CHECK(events[0].loop == "motion");
  CHECK(events[1].event_name() == "BhRotateInPlace.done");
  CHECK(std::abs(rig.odom.latest().pose.theta_rad - 0.5) < 0.05);
}

TEST_CASE("Controller faults are reported as loop events") {
  test::ReactiveRig rig(test::differential_base(), CoordinationMode::priority);
  std::vector<LoopEvent> events;
  rig.cycle();
  rig.hardware->set_refuse_writes(true);
  rig.cycle();
  rig.cycle();
  rig.hardware->set_refuse_writes(false);
  rig.cycle();
  rig.cycle();  // events recorded in a cycle are handed over at the start of the next
  rig.loop->collect_events(events);
  REQUIRE(events.size() == 2);
  CHECK(events[0].event_name() == "motion.controller_fault");
  CHECK(events[1].event_name() == "motion.controller_recovered");
}

TEST_CASE("Navigation data and locks reach the behaviors and the coordinator") {
  test::ReactiveRig rig(test::omni_base_psr(), CoordinationMode::priority);
  ControlLoop& loop = *rig.loop;
  loop.activate(test::builtin_behaviors().create("BhGoToPose"), {{"use_navigation_goal", Value{true}}}, "goto_a");
  NavigationData navi;
  navi.localized = true;
  navi.map_from_base = {0, 0, 0};
  navi.has_goal = true;
  navi.goal = {0, 2.0, 0};
  std::vector<Pose2D> path(5000);
  navi.path = path;
  CHECK_FALSE(loop.set_navigation(navi));  // more than max_path_points (4096): truncated
  path.resize(10);
  navi.path = path;
  CHECK(loop.set_navigation(navi));
  rig.cycle();
  rig.cycle();
  CHECK(loop.last_cycle().coordinator.winner == "goto_a");
  CHECK(loop.last_cycle().coordinator.command.vy_m_s > 0.0);
  loop.set_lock("pause", true, rig.clock.now());
  rig.cycle();
  CHECK(loop.last_cycle().coordinator.locked);
  CHECK(loop.last_cycle().coordinator.command == Twist2D{});
}

TEST_CASE("Several loops with different periods are stepped by simulated time, in order") {
  SimClock clock;
  ResourceTable resources;
  ControlLoopOptions fast;
  fast.name = "fast";
  fast.period = 10ms;
  ControlLoopOptions slow;
  slow.name = "slow";
  slow.period = 25ms;
  CoordinatorConfig cc;
  cc.inputs = {{"BhStop", 0, 0ms}};
  ControlLoop a(fast, resources, CBehaviorCoordinator(cc), nullptr);
  ControlLoop b(slow, resources, CBehaviorCoordinator(cc), nullptr);
  SimLoopDriver driver(clock);
  driver.add(a);
  driver.add(b);
  CHECK(driver.run_until(Time{100ms}) == 11 + 5);
  CHECK(a.cycles() == 11);  // 0, 10, ..., 100 ms
  CHECK(b.cycles() == 5);   // 0, 25, 50, 75, 100 ms
  CHECK(a.last_cycle().now == Time{100ms});
  CHECK(b.last_cycle().now == Time{100ms});
  CHECK(clock.now() == Time{100ms});
  CHECK(driver.run_until(Time{105ms}) == 0);
  CHECK(clock.now() == Time{105ms});
  CHECK(driver.run_for(5ms) == 1);  // fast at 110 ms
}

namespace {

// A clock whose sleeps return at once at the deadline: the runner's timing becomes deterministic.
class JumpClock final : public Clock {
 public:
  Time now() const noexcept override { return time_from_ns(t_.load()); }
  void sleep_until(Time deadline) const noexcept override {
    Time::rep cur = t_.load();
    while (to_ns(deadline) > cur && !t_.compare_exchange_weak(cur, to_ns(deadline))) {
    }
  }
  void advance(Duration d) const noexcept { t_.fetch_add(d.count()); }

 private:
  mutable std::atomic<Time::rep> t_{0};
};

// Records the time of every cycle; on cycle `slow_cycle` it takes 2.5 periods.
class BhRecorder final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = [] {
      ModuleManifest x;
      x.name = "BhRecorder";
      x.kind = ModuleKind::behavior;
      return x;
    }();
    return m;
  }
  BhRecorder(const JumpClock& clock, int slow_cycle) : clock_(clock), slow_cycle_(slow_cycle) {}
  std::array<Time, 64> times{};
  std::atomic<int> count{0};

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet&, const BehaviorContext&) override {}
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override {
    const int i = count.load();
    if (i < 64) times[static_cast<std::size_t>(i)] = context.now;
    if (i == slow_cycle_) clock_.advance(2500us);
    count.store(i + 1);
    return Twist2D{};
  }

 private:
  const JumpClock& clock_;
  int slow_cycle_;
};

}  // namespace

TEST_CASE("The runner keeps absolute deadlines and skips the ticks an overrun missed", "[threads]") {
  JumpClock clock;
  ResourceTable resources;
  ControlLoopOptions o;
  o.period = 1ms;
  CoordinatorConfig cc;
  cc.inputs = {{"rec", 0, 0ms}};
  ControlLoop loop(o, resources, CBehaviorCoordinator(cc), nullptr);
  auto owned = std::make_unique<BhRecorder>(clock, 5);
  BhRecorder& rec = *owned;
  ResourceTable none;
  loop.activate(std::move(owned), {}, "rec");
  LoopRunner runner(loop, clock, LoopTimingOptions{});
  runner.start();
  CHECK_THROWS_AS(runner.start(), std::logic_error);
  while (rec.count.load() < 40) std::this_thread::yield();
  runner.stop();
  CHECK_FALSE(runner.running());
  // The behavior joins at the first cycle (1 ms); cycles run at 1, 2, ... ms. Cycle index 5
  // (at 6 ms) ends at 8.5 ms: ticks 7 and 8 ms are skipped, the next cycle runs at 9 ms.
  for (int i = 0; i <= 5; ++i) CHECK(rec.times[static_cast<std::size_t>(i)] == Time{(i + 1) * 1ms});
  CHECK(rec.times[6] == Time{9ms});
  CHECK(rec.times[7] == Time{10ms});
  const LoopStatistics& s = runner.statistics();
  CHECK(s.overruns() == 1);
  CHECK(s.skipped_ticks() == 2);
  CHECK(s.max_jitter() == 0ns);
  CHECK(s.max_execution() == 2500us);
  CHECK(s.execution_quantile(0.5) == 1us);    // bin upper edge of the 0 us bin
  CHECK(s.execution_quantile(1.0) == 2501us);
  CHECK(s.cycles() >= 40);
}

TEST_CASE("A runner on the steady clock runs, and asks for real-time priority without failing", "[threads]") {
  SteadyClock clock;
  ResourceTable resources;
  ControlLoopOptions o;
  o.period = 1ms;
  CoordinatorConfig cc;
  cc.inputs = {{"BhStop", 0, 0ms}};
  ControlLoop loop(o, resources, CBehaviorCoordinator(cc), nullptr);
  loop.activate(test::builtin_behaviors().create("BhStop"), {});
  LoopRunner runner(loop, clock, LoopTimingOptions{10, -1});
  runner.start();
  while (loop.cycles() < 20) std::this_thread::sleep_for(1ms);
  runner.stop();
  // Granted or not depends on the machine's permissions; either way the loop ran.
  INFO("SCHED_FIFO granted: " << runner.realtime_granted());
  CHECK(runner.statistics().cycles() >= 20);
  CHECK(runner.statistics().cycles() + runner.statistics().skipped_ticks() >= 20);
  CHECK(loop.last_cycle().coordinator.winner == "BhStop");
}

TEST_CASE("Loop statistics quantiles are histogram bin edges") {
  LoopStatistics s;
  for (int i = 0; i < 98; ++i) s.record(3us, 1us);
  s.record(40us, 1us);
  s.record(900us, 2us);
  CHECK(s.cycles() == 100);
  CHECK(s.jitter_quantile(0.5) == 4us);
  CHECK(s.jitter_quantile(0.99) == 41us);
  CHECK(s.jitter_quantile(1.0) == 901us);
  CHECK(s.max_jitter() == 900us);
  CHECK(s.mean_jitter_us() == Approx((98 * 3 + 40 + 900) / 100.0));
  s.record(1s, 0us);  // beyond the histogram: last bin, exact max
  CHECK(s.jitter_quantile(1.0) == 20000us);
  CHECK(s.max_jitter() == 1s);
}

namespace {

// Drives forward at 0.3 m/s and keeps what the loop told it of the safety override.
class BhSafetyWitness final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = [] {
      ModuleManifest x;
      x.name = "BhSafetyWitness";
      x.kind = ModuleKind::behavior;
      return x;
    }();
    return m;
  }
  bool told = false;  ///< context.safety was set in the last step
  SafetyFeedback seen;

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet&, const BehaviorContext&) override {}
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override {
    told = context.safety != nullptr;
    if (told) seen = *context.safety;
    return Twist2D{0.3, 0.0, 0.2};
  }
};

}  // namespace

TEST_CASE("The loop tells the behavior that won the last fusion what the safety override did to its command",
          "[safety]") {
  ResourceTable resources;
  CoordinatorConfig cc;
  cc.inputs = {{"drive", 10, 0ms}, {"other", 0, 0ms}, {"guard", 0, 0ms, 1.0, InputRole::safety}};
  ControlLoop loop({}, resources, CBehaviorCoordinator(cc), nullptr);
  auto drive_owned = std::make_unique<BhSafetyWitness>();
  auto other_owned = std::make_unique<BhSafetyWitness>();
  BhSafetyWitness& drive = *drive_owned;
  BhSafetyWitness& other = *other_owned;
  loop.activate(std::move(drive_owned), {}, "drive");
  loop.activate(std::move(other_owned), {}, "other");
  Time now{};
  const auto cycle = [&] {
    loop.step(now);
    now += 10ms;
  };
  cycle();
  cycle();
  REQUIRE(drive.told);  // it won: it hears of the fusion, unrestricted so far
  CHECK_FALSE(drive.seen.limited);
  CHECK(drive.seen.allowed == Twist2D{0.3, 0.0, 0.2});
  CHECK_FALSE(other.told);  // it lost: the command restricted was not its own

  // A safety input commanding a stop (envelope [0, 0] on every axis) holds the winner still.
  const BehaviorHandle guard = loop.activate(test::builtin_behaviors().create("BhStop"), {}, "guard");
  cycle();  // the guard joins and clamps this fusion
  cycle();  // the winner hears of it
  REQUIRE(drive.told);
  CHECK(drive.seen.limited);
  CHECK(drive.seen.limited_by == "guard");
  CHECK(drive.seen.requested == Twist2D{0.3, 0.0, 0.2});
  CHECK(drive.seen.allowed == Twist2D{});
  CHECK(drive.seen.requested_speed_m_s() == Approx(0.3));
  CHECK(drive.seen.allowed_speed_m_s() == 0.0);
  CHECK_FALSE(other.told);

  loop.deactivate(guard);
  cycle();
  cycle();
  REQUIRE(drive.told);
  CHECK_FALSE(drive.seen.limited);
  CHECK(loop.last_cycle().coordinator.requested == loop.last_cycle().coordinator.command);
}

TEST_CASE(
    "Command channels: a behavior's writes reach the loop's command output, an unknown channel is refused at activation, located",
    "[reactive][channels]") {
  JointResource neck("neck");
  neck.publish(JointReading{Time{0ms}, 0.0, 0.0, 0.0, -1.0, 1.0});
  ResourceTable resources;
  resources.add(neck);
  const ChannelSpec spec{"neck", ChannelType::joint_position, ChannelValue::of(0.0), true, 0ms, -1.0, 1.0, "rad", ""};
  CoordinatorConfig cc;
  cc.inputs = {{"BhNeckGesture", 10, 0ms}};
  cc.channels = {spec};
  ControlLoop loop(ControlLoopOptions{}, resources, CBehaviorCoordinator(cc), nullptr);
  CommandChannels hardware;  // what a hardware exports
  CommandChannels other;
  other.add(ChannelSpec{"arm", ChannelType::joint_position, {}, true, 0ms, 0.0, 0.0, "", ""});
  CHECK_THROWS_WITH(loop.set_command_output(&other), Catch::Contains("not the coordinator's"));
  hardware.add(spec);
  loop.set_command_output(&hardware);

  loop.activate(std::make_unique<BhNeckGesture>(), {{"angle_deg", Value{20.0}}});
  loop.step(Time{10ms});
  CHECK(hardware.value(0).number == Approx(20.0 * kPi / 180.0));
  CHECK(loop.coordinator().channel_output(0).writer == "BhNeckGesture");

  CHECK_THROWS_WITH(loop.activate(std::make_unique<BhNeckGesture>(), {{"joint", Value{std::string("arm")}}}, {},
                                  SourceLocation{"PrGuide.xml", 14, 5}),
                    Catch::Contains("PrGuide.xml:14:5") &&
                        Catch::Contains("behavior BhNeckGesture writes the command channel 'arm', which the hardware does not "
                                        "export (it exports neck (joint_position))"));
  // The refused activation changed nothing: the first gesture still holds the channel.
  loop.step(Time{20ms});
  CHECK(loop.coordinator().channel_output(0).writer == "BhNeckGesture");
}

namespace {
// Raises "cliff" on its second step and goes on running (a safety reflex's finding).
class SignallingBehavior final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = behavior_manifest("BhSignals", "test: raises an event while running", {}, {});
    return m;
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet&, const BehaviorContext&) override {}
  std::optional<Twist2D> on_step(const BehaviorContext&) noexcept override {
    if (steps() == 2) signal("cliff");
    return std::nullopt;
  }
};
}  // namespace

TEST_CASE("A behavior's signal is a loop event named after it, once, and the behavior keeps running") {
  test::ReactiveRig rig(test::differential_base(), CoordinationMode::priority);
  const BehaviorHandle h = rig.loop->activate(std::make_unique<SignallingBehavior>(), {}, "goto_a");
  std::vector<LoopEvent> events;
  for (int k = 0; k < 5; ++k) rig.cycle();
  rig.loop->collect_events(events);
  REQUIRE(events.size() == 1);
  CHECK(events[0].kind == LoopEvent::Kind::behavior_signal);
  CHECK(events[0].event_name() == "cliff");
  CHECK(events[0].behavior == "BhSignals");
  CHECK(events[0].input == "goto_a");
  CHECK(events[0].handle == h);
}
