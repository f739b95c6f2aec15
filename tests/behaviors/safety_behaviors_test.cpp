// The safety reflexes (cliff, bump, ultrasonic) on hand-made readings, and through the behavior
// coordinator: a back-off wins over whatever the task behavior asks, a hold stops forward motion.
#include "tripodal/behaviors/safety_behaviors.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

struct Readings {
  InfraredResource cliff{"cliff"};
  BumperResource bumpers{"bumpers"};
  SonarResource sonar{"ultrasonic"};
  ResourceTable table;
  NavigationData navi;
  NavigationFeedback feedback;
  BehaviorContext ctx;
  Readings() {
    table.add(cliff);
    table.add(bumpers);
    table.add(sonar);
    ctx.period = 10ms;
    ctx.resources = &table;
    ctx.navi = &navi;
    ctx.feedback = &feedback;
    navi.map_from_base = {1.0, 2.0, 0.0};
    set_cliff({0, 0, 0});
    set_bumps(0);
    set_sonar(
        {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()});
  }
  void set_cliff(std::vector<std::uint8_t> bits) {
    InfraredReading r;
    r.stamp = ctx.now;
    r.cliff = std::move(bits);
    cliff.publish(r);
  }
  void set_bumps(std::uint32_t mask) {
    BumperReading r;
    r.stamp = ctx.now;
    r.count = 8;
    r.pressed_mask = mask;
    bumpers.publish(r);
  }
  void set_sonar(std::vector<float> ranges) {
    SonarReading r;
    r.stamp = ctx.now;
    r.ranges_m = std::move(ranges);
    sonar.publish(r);
  }
  // One period of `b`: its envelope (nullopt: it imposes nothing).
  std::optional<VelocityEnvelope> step(CBehavior& b) {
    feedback = NavigationFeedback{};
    (void)b.step(ctx);
    ctx.now += ctx.period;
    return b.envelope();
  }
};

constexpr double kInf = VelocityEnvelope::kInf;

}  // namespace

TEST_CASE("BhCliffGuard: a cliff bit stops the robot, backs it straight off, holds it and raises `cliff` once",
          "[behaviors][safety]") {
  Readings w;
  BhCliffGuard guard;
  guard.activate(ParameterValues{{"back_off_m", Value{0.1}}, {"back_speed_m_s", Value{0.1}}, {"hold_s", Value{2.0}}}, w.ctx);
  REQUIRE(guard.running());
  CHECK_FALSE(w.step(guard).has_value());  // floor everywhere: nothing imposed
  CHECK(guard.take_signal().empty());

  w.set_cliff({0, 1, 0});  // the left front sensor (0.1, 0.17) sees a drop
  auto e = w.step(guard);
  REQUIRE(e.has_value());
  CHECK(e->vx_lo_m_s == -0.1);
  CHECK(e->vx_hi_m_s == -0.1);
  CHECK(e->wz_lo_rad_s == 0.0);
  CHECK(e->wz_hi_rad_s == 0.0);
  CHECK(guard.take_signal() == "cliff");
  REQUIRE(w.feedback.hazard_count == 3);  // under the sensor, and beyond the edge
  CHECK(w.feedback.hazards[0].x_m == Approx(1.1));
  CHECK(w.feedback.hazards[0].y_m == Approx(2.17));
  CHECK(w.feedback.hazards[2].x_m == Approx(1.8));
  CHECK(w.feedback.hazards[2].y_m == Approx(2.17));
  // Still over the drop: it keeps backing, without a second event.
  (void)w.step(guard);
  CHECK(guard.take_signal().empty());
  // Floor again: it backs back_off_m more (1 s at 0.1 m/s: it may have stopped with the sensor
  // past the edge), then holds forward motion.
  w.set_cliff({0, 0, 0});
  for (int k = 0; k < 99; ++k) CHECK(w.step(guard)->vx_lo_m_s == -0.1);
  for (int k = 0; k < 5; ++k) (void)w.step(guard);
  e = w.step(guard);
  REQUIRE(e.has_value());
  CHECK(e->vx_hi_m_s == 0.0);
  CHECK(e->vx_lo_m_s == -kInf);
  CHECK(e->wz_lo_rad_s == -kInf);       // turning in place is free while holding
  CHECK(w.feedback.hazard_count == 3);  // the place is reported while it holds
  for (int k = 0; k < 200; ++k) (void)w.step(guard);
  CHECK_FALSE(w.step(guard).has_value());
  CHECK(w.feedback.hazard_count == 0);
}

TEST_CASE("BhCliffGuard: a sensor stuck over a drop backs the robot at most max_back_off_m, then it stands",
          "[behaviors][safety]") {
  Readings w;
  BhCliffGuard guard;
  guard.activate(ParameterValues{}, w.ctx);
  w.set_cliff({1, 0, 0});
  for (int k = 0; k < 390; ++k) CHECK(w.step(guard)->vx_lo_m_s == -0.1);  // 3.9 s at 0.1 m/s: 0.39 m
  for (int k = 0; k < 20; ++k) (void)w.step(guard);                       // past the 0.4 m cap
  const auto e = w.step(guard);
  REQUIRE(e.has_value());
  CHECK(e->vx_lo_m_s == 0.0);
  CHECK(e->vx_hi_m_s == 0.0);
}

TEST_CASE("BhCliffGuard: bad sensor places are refused with the parameter named, no resource fails",
          "[behaviors][safety][errors]") {
  Readings w;
  BhCliffGuard guard;
  CHECK_THROWS_WITH(guard.activate(ParameterValues{{"sensors", Value{std::string("0.2,0; 0.1")}}}, w.ctx),
                    Catch::Contains("parameter 'sensors'") && Catch::Contains("positions"));
  CHECK_THROWS_WITH(guard.activate(ParameterValues{{"sensors", Value{std::string("0.2,zero")}}}, w.ctx),
                    Catch::Contains("'zero' is not a number"));
  ResourceTable empty;
  BehaviorContext ctx;
  ctx.resources = &empty;
  guard.activate(ParameterValues{}, ctx);
  CHECK(guard.status() == BehaviorStatus::failed);
  CHECK(guard.failure_reason() == "no cliff resource");
}

TEST_CASE("BhBumperGuard: a front bump backs off, a back bump alone forbids backing", "[behaviors][safety]") {
  Readings w;
  BhBumperGuard guard;
  guard.activate(ParameterValues{{"hold_s", Value{1.0}}}, w.ctx);
  CHECK_FALSE(w.step(guard).has_value());
  w.set_bumps(0x1);  // sector 0: ahead
  auto e = w.step(guard);
  REQUIRE(e.has_value());
  CHECK(e->vx_lo_m_s == -0.1);
  CHECK(e->vx_hi_m_s == -0.1);
  CHECK(e->wz_lo_rad_s == 0.0);  // ahead: straight back, the way it came
  CHECK(e->wz_hi_rad_s == 0.0);
  REQUIRE(w.feedback.hazard_count == 1);
  CHECK(w.feedback.hazards[0].x_m == Approx(1.3));  // radius 0.25 + 0.05 ahead
  w.set_bumps(0x4);                                 // the back one only (front released): no backing into it
  e = w.step(guard);
  REQUIRE(e.has_value());
  CHECK(e->vx_lo_m_s == 0.0);
  CHECK(e->vx_hi_m_s == 0.0);
}

TEST_CASE("BhSonarGuard: slows down and stops before an echo ahead, not for one beside the corridor", "[behaviors][safety]") {
  Readings w;
  BhSonarGuard guard;
  guard.activate(ParameterValues{{"stop_distance_m", Value{0.1}}, {"slow_distance_m", Value{0.6}}, {"max_speed_m_s", Value{0.5}}},
                 w.ctx);
  constexpr float kNone = std::numeric_limits<float>::infinity();
  auto e = w.step(guard);
  REQUIRE(e.has_value());
  CHECK(e->vx_hi_m_s == 0.5);
  CHECK(e->vx_lo_m_s == -kInf);
  w.set_sonar({kNone, 0.35F, kNone});  // glass 0.35 m ahead: half way from stop to slow
  e = w.step(guard);
  CHECK(e->vx_hi_m_s == Approx(0.25));
  CHECK(w.feedback.hazard_count == 0);
  w.set_sonar({kNone, 0.08F, kNone});
  e = w.step(guard);
  CHECK(e->vx_hi_m_s == 0.0);
  REQUIRE(w.feedback.hazard_count == 1);
  CHECK(w.feedback.hazards[0].x_m == Approx(1.33));
  // The right transducer (-30 degrees) sees something 1 m away: its cone passes beside the body.
  w.set_sonar({1.0F, kNone, kNone});
  CHECK(w.step(guard)->vx_hi_m_s == 0.5);
  // Blind (no reading yet): no forward motion.
  Readings blind;
  SonarResource never{"ultrasonic"};
  ResourceTable t;
  t.add(never);
  blind.ctx.resources = &t;
  BhSonarGuard g2;
  g2.activate(ParameterValues{}, blind.ctx);
  CHECK(blind.step(g2)->vx_hi_m_s == 0.0);
}

TEST_CASE("safety reflexes through the coordinator: the back-off wins over the task's command, the hold stops it",
          "[behaviors][safety]") {
  CBehaviorCoordinator c;
  const InputId cover = c.add_input({.name = "BhCleaningTwoWheel", .priority = 5});
  const InputId cliff = c.add_input({.name = "BhCliffGuard", .priority = 1000, .role = InputRole::safety});
  const Time t0{};
  c.submit(cover, Twist2D{0.3, 0.0, 0.4}, t0);
  VelocityEnvelope back;
  back.vx_lo_m_s = back.vx_hi_m_s = -0.1;
  back.vy_lo_m_s = back.vy_hi_m_s = 0.0;
  back.wz_lo_rad_s = back.wz_hi_rad_s = 0.0;
  c.submit_envelope(cliff, back, t0);
  CoordinatorOutput out = c.update(t0);
  CHECK(out.command == Twist2D{-0.1, 0.0, 0.0});
  CHECK(out.safety_limited);
  CHECK(out.limited_by == "BhCliffGuard");
  // Nothing else live: the back-off still drives.
  c.withdraw(cover);
  out = c.update(t0);
  CHECK(out.command == Twist2D{-0.1, 0.0, 0.0});
  VelocityEnvelope hold;
  hold.vx_hi_m_s = 0.0;
  c.submit(cover, Twist2D{0.3, 0.0, 0.4}, t0);
  c.submit_envelope(cliff, hold, t0);
  out = c.update(t0);
  CHECK(out.command == Twist2D{0.0, 0.0, 0.4});
}

TEST_CASE("register_safety_behaviors registers the three reflexes", "[behaviors][safety]") {
  BehaviorRegistry reg;
  register_safety_behaviors(reg);
  for (const char* name : {"BhCliffGuard", "BhBumperGuard", "BhSonarGuard"}) {
    INFO(name);
    CHECK(reg.create(name) != nullptr);
  }
}

TEST_CASE("BhCliffGuard: the hold ends early once the robot has turned away (toward a detour)", "[behaviors][safety]") {
  Readings w;
  BhCliffGuard guard;
  guard.activate(ParameterValues{{"back_off_m", Value{0.1}}, {"hold_s", Value{12.0}}, {"release_turn_rad", Value{1.0}}}, w.ctx);
  w.set_cliff({1, 0, 0});
  (void)w.step(guard);
  w.set_cliff({0, 0, 0});
  for (int k = 0; k < 150; ++k) (void)w.step(guard);  // backed off: holding
  REQUIRE(w.step(guard).has_value());
  w.navi.map_from_base.theta_rad = 0.8;  // turning in place: still facing the drop
  REQUIRE(w.step(guard).has_value());
  w.navi.map_from_base.theta_rad = -1.1;  // turned away
  CHECK_FALSE(w.step(guard).has_value());
}

namespace {

// The robot beside a wall (glass) its left (or right) side touches: the bump reflex drives it,
// its commands integrated as a differential base moves (the reflex's envelope pinned, so the
// command is the envelope). Returns the body's gap to the wall once the backing is done, and
// leaves the robot holding.
double back_from_side_bump(Readings& w, BhBumperGuard& guard, std::uint32_t sector_bit, double wall_side) {
  w.navi.map_from_base = {1.0, 2.0, 0.0};
  const double wall_y = 2.0 + wall_side * 0.255;  // 5 mm from the 0.25 m footprint
  w.set_bumps(sector_bit);
  for (int k = 0; k < 400; ++k) {
    const auto e = w.step(guard);
    REQUIRE(e.has_value());
    if (e->vx_lo_m_s != e->vx_hi_m_s || e->wz_lo_rad_s != e->wz_hi_rad_s) break;  // holding
    const double dt = 0.01, v = e->vx_lo_m_s, wz = e->wz_lo_rad_s;
    Pose2D& p = w.navi.map_from_base;
    p.x_m += v * std::cos(p.theta_rad) * dt;
    p.y_m += v * std::sin(p.theta_rad) * dt;
    p.theta_rad += wz * dt;
    if (std::abs(p.y_m - wall_y) > 0.25 + 0.005) w.set_bumps(0);  // off the wall: released
  }
  CHECK(guard.take_signal().empty());
  return std::abs(w.navi.map_from_base.y_m - wall_y) - 0.25;
}

}  // namespace

// Driving along glass, a side switch pressed: straight back would slide the body along the glass
// (a differential base cannot move sideways), so it backs along an arc whose rear swings away
// from the contact, and drives on along the obstacle once heading along it again.
TEST_CASE("BhBumperGuard: a bump on a side backs the robot off along an arc away from it, not along the obstacle",
          "[behaviors][safety]") {
  Readings w;
  BhBumperGuard guard;  // the profile's: 4 sectors, sector 1 the left, 3 the right, back_off_m 0.1
  guard.activate(ParameterValues{{"back_off_m", Value{0.1}}, {"hold_s", Value{12.0}}}, w.ctx);
  SECTION("left") {
    const double gap = back_from_side_bump(w, guard, 0x2, +1.0);
    WARN("a left bump: the body 5 mm from the wall before, " << gap * 1000.0 << " mm after backing");
    CHECK(gap > 0.025);
    CHECK(w.navi.map_from_base.theta_rad == Approx(0.6).margin(0.02));  // the front turned toward the side
    CHECK(w.navi.map_from_base.x_m < 1.0);
    REQUIRE(w.step(guard).has_value());  // holding: no forward motion toward the glass
    CHECK(w.step(guard)->vx_hi_m_s == 0.0);
    w.navi.map_from_base.theta_rad = 0.4;  // turning back: still heading toward the glass
    REQUIRE(w.step(guard).has_value());
    w.navi.map_from_base.theta_rad = 0.25;  // about along it again (side_release_rad 0.3): the way on is free
    CHECK_FALSE(w.step(guard).has_value());
  }
  SECTION("right") {
    const double gap = back_from_side_bump(w, guard, 0x8, -1.0);
    CHECK(gap > 0.025);
    CHECK(w.navi.map_from_base.theta_rad == Approx(-0.6).margin(0.02));
    w.navi.map_from_base.theta_rad = 0.01;
    CHECK_FALSE(w.step(guard).has_value());
  }
  SECTION("both sides at once (a narrow gap): straight back") {
    w.set_bumps(0xA);
    const auto e = w.step(guard);
    REQUIRE(e.has_value());
    CHECK(e->vx_lo_m_s == -0.1);
    CHECK(e->wz_lo_rad_s == 0.0);
    CHECK(e->wz_hi_rad_s == 0.0);
  }
}

TEST_CASE("BhBumperGuard: a side hold that would end as the backing does is refused, the parameters named",
          "[behaviors][safety]") {
  Readings w;
  BhBumperGuard guard;
  CHECK_THROWS_WITH(guard.activate(ParameterValues{{"side_turn_rad", Value{0.3}}, {"side_release_rad", Value{0.5}}}, w.ctx),
                    Catch::Contains("side_release_rad (0.500000) must be less than side_turn_rad (0.300000)"));
}
