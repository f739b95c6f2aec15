// The behavior coordinator: priority arbitration, timeouts, locks, ties, weighted sum, safety.
#include "tripodal/behaviors/behavior_coordinator.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;
using namespace std::chrono_literals;

namespace {
CoordinatorConfig three_inputs(CoordinationMode mode = CoordinationMode::priority) {
  CoordinatorConfig c;
  c.mode = mode;
  c.inputs = {{"joystick", 100, 500ms, 1.0, InputRole::normal},
              {"BhGoToPose", 10, 200ms, 3.0, InputRole::normal},
              {"BhStop", 0, 0ms, 1.0, InputRole::normal}};
  return c;
}
}  // namespace

TEST_CASE("Priority mode: the live input of highest priority wins and is named") {
  CBehaviorCoordinator co(three_inputs());
  const InputId joy = *co.find_input("joystick");
  const InputId go = *co.find_input("BhGoToPose");
  const InputId stop = *co.find_input("BhStop");
  co.submit(stop, {}, Time{0ms});
  co.submit(go, {0.3, 0.0, 0.1}, Time{0ms});
  auto out = co.update(Time{10ms});
  CHECK(out.winner == "BhGoToPose");
  CHECK(out.winner_id == go);
  CHECK(out.command == Twist2D{0.3, 0.0, 0.1});
  CHECK(out.live_inputs == 2);
  CHECK_FALSE(out.all_expired);
  co.submit(joy, {-0.1, 0.2, 0.0}, Time{20ms});
  out = co.update(Time{20ms});
  CHECK(out.winner == "joystick");
  CHECK(out.command == Twist2D{-0.1, 0.2, 0.0});
  co.withdraw(joy);
  CHECK(co.update(Time{30ms}).winner == "BhGoToPose");
}

TEST_CASE("Per-input timeouts, an explicit zero when every input expired") {
  CoordinatorConfig c = three_inputs();
  c.inputs.pop_back();  // no BhStop fallback
  CBehaviorCoordinator co(c);
  const InputId joy = *co.find_input("joystick");
  const InputId go = *co.find_input("BhGoToPose");
  co.submit(joy, {0.5, 0, 0}, Time{0ms});
  co.submit(go, {0.2, 0, 0}, Time{0ms});
  CHECK(co.update(Time{500ms}).winner == "joystick");  // exactly at the timeout: still live
  auto out = co.update(Time{501ms});
  CHECK(out.winner == "");  // go expired at 200 ms too
  CHECK(out.all_expired);
  CHECK(out.command == Twist2D{});
  CHECK_FALSE(out.winner_id.has_value());
  co.submit(go, {0.2, 0, 0}, Time{600ms});
  out = co.update(Time{700ms});
  CHECK(out.winner == "BhGoToPose");
  CHECK(co.update(Time{801ms}).all_expired);
}

TEST_CASE("Ties go to the input configured first, whatever the submission order") {
  CoordinatorConfig c;
  c.inputs = {{"a", 5, 0ms}, {"b", 5, 0ms}, {"c", 5, 0ms}};
  CBehaviorCoordinator co(c);
  co.submit(2, {3, 0, 0}, Time{0ms});
  co.submit(1, {2, 0, 0}, Time{1ms});
  CHECK(co.update(Time{2ms}).winner == "b");
  co.submit(0, {1, 0, 0}, Time{3ms});
  CHECK(co.update(Time{4ms}).winner == "a");
  CHECK(co.output().command.vx_m_s == 1.0);
}

TEST_CASE("Locks mask inputs at or below their priority") {
  CoordinatorConfig c = three_inputs();
  c.locks = {{"pause", 50, 0ms}};
  CBehaviorCoordinator co(c);
  const LockId pause = *co.find_lock("pause");
  co.submit(*co.find_input("BhGoToPose"), {0.3, 0, 0}, Time{0ms});
  co.submit(*co.find_input("BhStop"), {}, Time{0ms});
  CHECK_FALSE(co.update(Time{0ms}).locked);  // a lock without timeout is released until told otherwise
  co.set_lock(pause, true, Time{1ms});
  auto out = co.update(Time{2ms});
  CHECK(out.locked);
  CHECK(out.lock == "pause");
  CHECK(out.all_expired);
  CHECK(out.command == Twist2D{});
  // The joystick (priority 100) is above the lock.
  co.submit(*co.find_input("joystick"), {0.1, 0, 0}, Time{3ms});
  out = co.update(Time{3ms});
  CHECK(out.winner == "joystick");
  co.withdraw(*co.find_input("joystick"));
  co.set_lock(pause, false, Time{4ms});
  CHECK(co.update(Time{5ms}).winner == "BhGoToPose");
}

TEST_CASE("A lock with a timeout is a dead-man switch") {
  CoordinatorConfig c = three_inputs();
  c.locks = {{"heartbeat", 1000, 100ms}};
  CBehaviorCoordinator co(c);
  const LockId hb = *co.find_lock("heartbeat");
  co.submit(*co.find_input("joystick"), {0.4, 0, 0}, Time{0ms});
  CHECK(co.update(Time{0ms}).locked);  // engaged before the first message
  co.set_lock(hb, false, Time{10ms});
  CHECK(co.update(Time{50ms}).winner == "joystick");
  co.submit(*co.find_input("joystick"), {0.4, 0, 0}, Time{100ms});
  CHECK(co.update(Time{110ms}).winner == "joystick");  // 100 ms after the message: still released
  auto out = co.update(Time{111ms});                   // heartbeat silent: everything stops
  CHECK(out.locked);
  CHECK(out.lock == "heartbeat");
  CHECK(out.command == Twist2D{});
  co.set_lock(hb, false, Time{120ms});
  CHECK(co.update(Time{120ms}).winner == "joystick");
}

TEST_CASE("The highest engaged lock is reported") {
  CoordinatorConfig c = three_inputs();
  c.locks = {{"low", 5, 0ms}, {"high", 20, 0ms}};
  CBehaviorCoordinator co(c);
  co.submit(*co.find_input("BhGoToPose"), {0.3, 0, 0}, Time{0ms});
  co.submit(*co.find_input("BhStop"), {}, Time{0ms});
  co.set_lock(0, true, Time{0ms});
  auto out = co.update(Time{0ms});
  CHECK(out.lock == "low");
  CHECK(out.winner == "BhGoToPose");  // priority 10 > 5
  co.set_lock(1, true, Time{0ms});
  out = co.update(Time{0ms});
  CHECK(out.lock == "high");
  CHECK(out.all_expired);
}

TEST_CASE("Weighted-sum mode averages the live inputs with their weights") {
  CBehaviorCoordinator co(three_inputs(CoordinationMode::weighted_sum));
  co.submit(*co.find_input("joystick"), {1.0, 0.0, 0.4}, Time{0ms});    // weight 1
  co.submit(*co.find_input("BhGoToPose"), {0.2, 0.4, 0.0}, Time{0ms});  // weight 3
  auto out = co.update(Time{10ms});
  CHECK(out.winner == "weighted_sum");
  CHECK(out.winner_id == *co.find_input("BhGoToPose"));
  CHECK(out.command.vx_m_s == Approx((1.0 + 3 * 0.2) / 4));
  CHECK(out.command.vy_m_s == Approx(3 * 0.4 / 4));
  CHECK(out.command.wz_rad_s == Approx(0.4 / 4));
  CHECK(out.live_inputs == 2);
  // After BhGoToPose expires only the joystick counts.
  out = co.update(Time{300ms});
  CHECK(out.command == Twist2D{1.0, 0.0, 0.4});
  co.set_mode(CoordinationMode::priority);
  CHECK(co.update(Time{300ms}).winner == "joystick");
}

TEST_CASE("A zero-weight input takes no part in the weighted sum") {
  CoordinatorConfig c;
  c.mode = CoordinationMode::weighted_sum;
  c.inputs = {{"a", 0, 0ms, 0.0}, {"b", 0, 0ms, 2.0}};
  CBehaviorCoordinator co(c);
  co.submit(0, {5, 5, 5}, Time{0ms});
  CHECK(co.update(Time{0ms}).all_expired);
  co.submit(1, {1, 0, 0}, Time{0ms});
  CHECK(co.update(Time{0ms}).command == Twist2D{1, 0, 0});
}

TEST_CASE("Safety inputs restrict the fused command to the most restrictive envelope") {
  for (CoordinationMode mode : {CoordinationMode::priority, CoordinationMode::weighted_sum}) {
    CoordinatorConfig c = three_inputs(mode);
    c.inputs.push_back({"BhAvoidObstacle", 1000, 200ms, 1.0, InputRole::safety});
    c.inputs.push_back({"cliff", 1000, 200ms, 1.0, InputRole::safety});
    CBehaviorCoordinator co(c);
    const InputId go = *co.find_input("BhGoToPose");
    const InputId avoid = *co.find_input("BhAvoidObstacle");
    const InputId cliff = *co.find_input("cliff");
    co.submit(go, {0.5, 0.3, 0.2}, Time{0ms});
    VelocityEnvelope e;
    e.vx_hi_m_s = 0.1;   // obstacle ahead
    e.vy_lo_m_s = -0.05;
    co.submit_envelope(avoid, e, Time{0ms});
    auto out = co.update(Time{0ms});
    CHECK(out.safety_limited);
    CHECK(out.limited_by == "BhAvoidObstacle");
    CHECK(out.command.vx_m_s == Approx(0.1));
    CHECK(out.command.vy_m_s == Approx(0.3));  // left is free
    CHECK(out.command.wz_rad_s == Approx(0.2));
    // A plain command from a safety input allows [0, c] per axis: here no forward motion, no
    // turning left; the intersection with the obstacle envelope is the most restrictive.
    co.submit(cliff, {0.0, 0.1, 0.0}, Time{0ms});
    out = co.update(Time{0ms});
    CHECK(out.command.vx_m_s == 0.0);
    CHECK(out.command.vy_m_s == Approx(0.1));
    CHECK(out.command.wz_rad_s == 0.0);
    // Backing away is allowed by the obstacle envelope but not by the cliff's [0, 0].
    co.submit(go, {-0.2, 0.0, 0.0}, Time{0ms});
    CHECK(co.update(Time{0ms}).command.vx_m_s == 0.0);
    co.withdraw(cliff);
    CHECK(co.update(Time{0ms}).command.vx_m_s == Approx(-0.2));
    CHECK_FALSE(co.output().safety_limited);
    // Safety inputs never win on their own.
    co.withdraw(go);
    out = co.update(Time{0ms});
    CHECK(out.winner == "");
    CHECK(out.all_expired);
    CHECK(out.command == Twist2D{});
    // Expired safety input no longer restricts.
    co.submit(go, {0.5, 0, 0}, Time{300ms});
    CHECK(co.update(Time{300ms}).command.vx_m_s == Approx(0.5));
  }
}

TEST_CASE("An empty envelope intersection stops that axis") {
  CoordinatorConfig c;
  c.inputs = {{"go", 0, 0ms}, {"s1", 0, 0ms, 1.0, InputRole::safety}, {"s2", 0, 0ms, 1.0, InputRole::safety}};
  CBehaviorCoordinator co(c);
  co.submit(0, {0.3, 0.0, 0.5}, Time{0ms});
  VelocityEnvelope a, b;
  a.vx_lo_m_s = 0.2;   // must go forward at least 0.2
  b.vx_hi_m_s = -0.1;  // must go backward
  co.submit_envelope(1, a, Time{0ms});
  co.submit_envelope(2, b, Time{0ms});
  const auto out = co.update(Time{0ms});
  CHECK(out.command.vx_m_s == 0.0);
  CHECK(out.command.wz_rad_s == 0.5);
}

TEST_CASE("Coordinator configuration errors") {
  CBehaviorCoordinator co;
  co.add_input({"a", 0, 0ms});
  CHECK_THROWS_WITH(co.add_input({"a", 1, 0ms}), Catch::Contains("'a' already exists"));
  CHECK_THROWS_WITH(co.add_input({"w", 1, 0ms, -1.0}), Catch::Contains("weight must be >= 0"));
  CHECK_THROWS_WITH(co.add_input({"t", 1, -1ms}), Catch::Contains("timeout must be >= 0"));
  CHECK_FALSE(co.find_input("zzz").has_value());
  // Unknown ids are ignored rather than trusted.
  co.submit(99, {1, 1, 1}, Time{0ms});
  CHECK(co.update(Time{0ms}).all_expired);
  co.submit(0, {1, 0, 0}, Time{0ms});
  co.reset();
  CHECK(co.update(Time{0ms}).all_expired);
}

// --- command channels -----------------------------------------------------------------------------

namespace {
CoordinatorConfig with_channels(CoordinationMode mode = CoordinationMode::priority) {
  CoordinatorConfig c = three_inputs(mode);
  c.channels = {ChannelSpec{"uv_lamp", ChannelType::digital, ChannelValue::of(false), false, 0ms, 0.0, 0.0, "", ""},
                ChannelSpec{"neck", ChannelType::joint_position, ChannelValue::of(0.25), true, 0ms, -1.0, 1.0, "rad", ""},
                ChannelSpec{"fog", ChannelType::analog, ChannelValue::of(0.0), false, 300ms, 0.0, 1.0, "", ""},
                ChannelSpec{"lcd", ChannelType::text, ChannelValue::of_text("idle"), false, 0ms, 0.0, 0.0, "", ""}};
  c.inputs.push_back({"interlock", 0, 0ms, 1.0, InputRole::safety});
  return c;
}
}  // namespace

TEST_CASE("Channels: the live writer of highest priority wins each channel on its own, the others keep theirs", "[channels]") {
  CBehaviorCoordinator co(with_channels());
  const ChannelId lamp = *co.find_channel("uv_lamp");
  const ChannelId lcd = *co.find_channel("lcd");
  const InputId joy = *co.find_input("joystick");
  const InputId go = *co.find_input("BhGoToPose");
  co.update(Time{0ms});
  CHECK_FALSE(co.channel_output(lamp).live);
  CHECK(co.channel_output(lcd).value.text() == "idle");  // the safe value before any write
  co.submit_channel(go, lamp, ChannelValue::of(true), Time{0ms});
  co.submit_channel(go, lcd, ChannelValue::of_text("covering"), Time{0ms});
  co.submit_channel(joy, lcd, ChannelValue::of_text("driven by hand, a text longer than the LCD"), Time{0ms});
  co.update(Time{10ms});
  CHECK(co.channel_output(lamp).value.on());
  CHECK(co.channel_output(lamp).writer == "BhGoToPose");
  CHECK(co.channel_output(lcd).writer == "joystick");
  CHECK(co.channel_output(lcd).value.text() == "driven by hand, a text longer th");  // cut at 32
  // Motion is not touched by channel writes.
  CHECK(co.output().all_expired);
  co.withdraw_channels(joy);
  co.update(Time{20ms});
  CHECK(co.channel_output(lcd).value.text() == "covering");
}

TEST_CASE("Channels: a write past its input's or the channel's timeout falls to the safe value, a holding channel keeps its last",
          "[channels]") {
  CBehaviorCoordinator co(with_channels());
  const ChannelId lamp = *co.find_channel("uv_lamp");
  const ChannelId neck = *co.find_channel("neck");
  const ChannelId fog = *co.find_channel("fog");
  const InputId go = *co.find_input("BhGoToPose");  // timeout 200 ms
  const InputId stop = *co.find_input("BhStop");    // no timeout
  co.submit_channel(go, lamp, ChannelValue::of(true), Time{0ms});
  co.submit_channel(go, neck, ChannelValue::of(0.5), Time{0ms});
  co.submit_channel(stop, fog, ChannelValue::of(0.7), Time{0ms});
  co.update(Time{200ms});
  CHECK(co.channel_output(lamp).value.on());
  CHECK(co.channel_output(neck).value.number == 0.5);
  CHECK(co.channel_output(fog).value.number == 0.7);
  co.update(Time{250ms});  // the input's 200 ms passed
  CHECK_FALSE(co.channel_output(lamp).value.on());
  CHECK_FALSE(co.channel_output(lamp).live);
  CHECK(co.channel_output(neck).value.number == 0.5);  // holds
  CHECK(co.channel_output(fog).value.number == 0.7);   // its input never expires, the channel's 300 ms not yet
  co.update(Time{301ms});
  CHECK(co.channel_output(fog).value.number == 0.0);  // the channel's own timeout
  co.reset();
  CHECK(co.channel_output(neck).value.number == 0.25);
}

TEST_CASE("Channels: weighted mean for numeric channels only, clamped, locks mask, a safety write replaces the result",
          "[channels]") {
  CBehaviorCoordinator co(with_channels(CoordinationMode::weighted_sum));
  const ChannelId lamp = *co.find_channel("uv_lamp");
  const ChannelId neck = *co.find_channel("neck");
  const InputId joy = *co.find_input("joystick");   // weight 1, priority 100
  const InputId go = *co.find_input("BhGoToPose");  // weight 3, priority 10
  const InputId interlock = *co.find_input("interlock");
  co.submit_channel(joy, neck, ChannelValue::of(1.0), Time{0ms});
  co.submit_channel(go, neck, ChannelValue::of(0.2), Time{0ms});
  co.submit_channel(joy, lamp, ChannelValue::of(false), Time{0ms});
  co.submit_channel(go, lamp, ChannelValue::of(true), Time{0ms});
  co.update(Time{10ms});
  CHECK(co.channel_output(neck).value.number == Approx((1.0 + 3 * 0.2) / 4));
  CHECK(co.channel_output(neck).writer == "weighted_sum");
  CHECK_FALSE(co.channel_output(lamp).value.on());  // digital: priority, the joystick's
  co.submit_channel(joy, neck, ChannelValue::of(9.0), Time{10ms});
  co.withdraw_channel(go, neck);
  co.update(Time{20ms});
  CHECK(co.channel_output(neck).value.number == 1.0);  // clamped into [-1, 1]
  // A lock of priority 100 masks both writers: the lamp falls to off, the neck holds.
  const LockId lock = co.add_lock({"pause", 100, 0ms});
  co.set_lock(lock, true, Time{20ms});
  co.submit_channel(go, lamp, ChannelValue::of(true), Time{20ms});
  co.update(Time{30ms});
  CHECK_FALSE(co.channel_output(lamp).live);
  co.set_lock(lock, false, Time{30ms});
  co.withdraw_channels(joy);
  co.update(Time{40ms});
  CHECK(co.channel_output(lamp).value.on());
  co.submit_channel(interlock, lamp, ChannelValue::of(false), Time{40ms});
  co.update(Time{50ms});
  CHECK_FALSE(co.channel_output(lamp).value.on());
  CHECK(co.channel_output(lamp).safety_override);
  CHECK(co.channel_output(lamp).writer == "interlock");
}

TEST_CASE("Channels: a duplicate or unnamed channel is refused") {
  CBehaviorCoordinator co(with_channels());
  CHECK_THROWS_WITH(co.add_channel(ChannelSpec{"uv_lamp", ChannelType::digital, {}, false, 0ms, 0.0, 0.0, "", ""}),
                    Catch::Contains("'uv_lamp' already exists"));
  CHECK_THROWS_WITH(co.add_channel(ChannelSpec{"", ChannelType::digital, {}, false, 0ms, 0.0, 0.0, "", ""}),
                    Catch::Contains("needs a name"));
}
