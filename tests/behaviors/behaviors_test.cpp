// CBehavior lifecycle, the registry, parameters, and the built-in behaviors on a kinematic model.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/controllers/kinematics.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

constexpr double kPi = std::numbers::pi;

// A point robot whose pose follows each command exactly over one period; publishes odometry.
struct KinematicWorld {
  OdometryResource odom{"odom", 100ms};
  LaserResource laser{"laser", 200ms};
  ResourceTable table;
  NavigationData navi;
  BehaviorContext ctx;
  Pose2D pose;
  KinematicWorld() {
    table.add(odom);
    table.add(laser);
    ctx.period = 10ms;
    ctx.resources = &table;
    ctx.navi = &navi;
    publish();
  }
  void publish() {
    OdometryReading r;
    r.stamp = ctx.now;
    r.pose = pose;
    odom.publish(r);
  }
  // Steps `b` until it leaves running or `max_steps` pass; the world moves by its command.
  int run(CBehavior& b, int max_steps) {
    int k = 0;
    for (; k < max_steps && b.running(); ++k) {
      const auto cmd = b.step(ctx);
      ctx.now += ctx.period;
      if (cmd) {
        Twist2D c = *cmd;
        if (!ctx.base.holonomic()) c.vy_m_s = 0.0;
        const double dt = to_seconds(ctx.period);
        pose = integrate_body_displacement(pose, c.vx_m_s * dt, c.vy_m_s * dt, c.wz_rad_s * dt);
      }
      publish();
    }
    return k;
  }
};

}  // namespace

TEST_CASE("Every registered behavior can be created by name and describes itself") {
  BehaviorRegistry reg;
  register_builtin_behaviors(reg);
  const auto names = reg.names();
  CHECK(names == std::vector<std::string>{"BhAvoidObstacle", "BhBackOff", "BhGoToPose", "BhRotateInPlace", "BhStop"});
  KinematicWorld w;
  for (const auto& name : names) {
    INFO(name);
    auto b = reg.create(name);
    REQUIRE(b);
    CHECK(b->name() == name);
    const ModuleManifest& m = b->manifest();
    REQUIRE(reg.find(name) != nullptr);
    CHECK(reg.find(name)->name == m.name);
    CHECK(reg.find(name)->parameters.size() == m.parameters.size());
    CHECK(m.layer == Layer::reactive);
    CHECK(m.kind == ModuleKind::behavior);
    CHECK_FALSE(m.description.empty());
    for (const auto& p : m.parameters) {
      INFO(p.name);
      CHECK_FALSE(p.description.empty());
      if (p.default_value) CHECK(type_of(*p.default_value) == p.type);
    }
    // Defaults are a valid activation for every built-in behavior.
    CHECK(b->status() == BehaviorStatus::idle);
    b->activate(ParameterValues{}, w.ctx);
    CHECK(b->status() == BehaviorStatus::running);
    (void)b->step(w.ctx);
    b->deactivate();
    CHECK(b->status() == BehaviorStatus::idle);
    CHECK_FALSE(b->step(w.ctx).has_value());
  }
  REQUIRE_THROWS_AS(reg.create("BhFly"), ConfigError);
  REQUIRE_THROWS_WITH(reg.create("BhFly"),
                      Catch::Contains("unknown behavior type 'BhFly'; known: BhAvoidObstacle, BhBackOff, BhGoToPose, "
                                      "BhRotateInPlace, BhStop") &&
                          !Catch::Contains("did you mean"));
  REQUIRE_THROWS_WITH(reg.create_at({"clean.xml", 4, 7}, "BhGoToPos"),
                      Catch::Contains("clean.xml:4:7: error: unknown behavior type 'BhGoToPos'; known: ") &&
                          Catch::Contains("; did you mean 'BhGoToPose'?"));
  BehaviorRegistry mine;
  mine.add<BhStop>();
  CHECK_THROWS_WITH(mine.add<BhStop>(), Catch::Contains("'BhStop' is already registered"));
}

TEST_CASE("Activation checks parameters against the manifest and reports every problem") {
  KinematicWorld w;
  BhGoToPose b;
  const ParameterValues bad = {{"goal_x_m", Value{std::string("far")}},
                               {"max_speed_m_s", Value{-1.0}},
                               {"colour", Value{std::string("red")}},
                               {"use_navigation_goal", Value{2.0}}};
  REQUIRE_THROWS_WITH(b.activate(bad, w.ctx, SourceLocation{"clean.xml", 12, 4}),
                      Catch::Contains("clean.xml:12:4: error: BhGoToPose: unknown parameter 'colour'") &&
                          Catch::Contains("parameter 'goal_x_m' expects a number, got \"far\"") &&
                          Catch::Contains("parameter 'max_speed_m_s' = -1 m/s is outside [1e-06, inf]") &&
                          Catch::Contains("parameter 'use_navigation_goal' expects a bool, got 2"));
  CHECK(b.status() == BehaviorStatus::idle);
  // Net bindings carry text: numbers given as strings are accepted.
  b.activate({{"goal_x_m", Value{std::string("1.5")}}}, w.ctx);
  CHECK(b.running());
  ParameterSet set = ParameterSet::resolve(BhGoToPose::static_manifest(), {{"goal_x_m", Value{std::string("1.5")}}});
  CHECK(set.number("goal_x_m") == 1.5);
  CHECK(set.number("max_speed_m_s") == 0.4);
  CHECK(set.string("frame") == "odom");
  CHECK_THROWS_AS(set.number("nope"), std::out_of_range);
  REQUIRE_THROWS_WITH(b.activate({{"frame", Value{std::string("gps")}}}, w.ctx), Catch::Contains("'frame' must be \"odom\" or \"map\""));
}

TEST_CASE("Outcome events are named <BehaviorName>.done and <BehaviorName>.failed") {
  CHECK(done_event_name("BhGoToPose") == "BhGoToPose.done");
  CHECK(failed_event_name("BhBackOff") == "BhBackOff.failed");
  CHECK(to_string(BehaviorStatus::failed) == "failed");
}

TEST_CASE("BhStop commands zero and never finishes") {
  KinematicWorld w;
  BhStop b;
  b.activate(ParameterValues{}, w.ctx);
  for (int i = 0; i < 10; ++i) REQUIRE(b.step(w.ctx) == Twist2D{});
  CHECK(b.running());
  CHECK(b.steps() == 10);
}

TEST_CASE("BhRotateInPlace turns by the relative angle, more than half a turn included") {
  KinematicWorld w;
  w.pose.theta_rad = 3.0;  // the turn crosses the +-pi wrap
  w.publish();
  BhRotateInPlace b;
  b.activate({{"angle_rad", Value{4.0}}}, w.ctx);
  const int steps = w.run(b, 2000);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(steps < 2000);
  CHECK(std::abs(wrap_angle(w.pose.theta_rad - (3.0 + 4.0))) < 0.03);
  CHECK(w.pose.x_m == 0.0);
}

TEST_CASE("Behaviors fail when their resources go stale") {
  KinematicWorld w;
  BhRotateInPlace b;
  b.activate({{"angle_rad", Value{1.0}}, {"stale_timeout_s", Value{0.05}}}, w.ctx);
  // Odometry stops: max_age 100 ms, then 50 ms of grace.
  for (int k = 0; k < 30 && b.running(); ++k) {
    (void)b.step(w.ctx);
    w.ctx.now += 10ms;
  }
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "odometry stale");

  ResourceTable empty;
  BehaviorContext ctx = w.ctx;
  ctx.resources = &empty;
  BhBackOff back;
  back.activate(ParameterValues{}, ctx);
  CHECK(back.status() == BehaviorStatus::failed);
  CHECK(back.failure_reason() == "no odometry resource");
  BhAvoidObstacle avoid;
  avoid.activate(ParameterValues{}, ctx);
  CHECK(avoid.failure_reason() == "no laser resource");
}

TEST_CASE("BhGoToPose in the map frame needs a localized pose and can time out") {
  KinematicWorld w;
  BhGoToPose b;
  b.activate({{"frame", Value{std::string("map")}}, {"goal_x_m", Value{1.0}}, {"stale_timeout_s", Value{0.1}}}, w.ctx);
  w.navi.localized = false;
  for (int k = 0; k < 20 && b.running(); ++k) {
    const auto cmd = b.step(w.ctx);
    if (b.running()) CHECK(cmd == Twist2D{});  // holds still while not localized
    w.ctx.now += 10ms;
  }
  CHECK(b.failure_reason() == "not localized");

  w.navi.localized = true;
  w.navi.has_goal = true;
  w.navi.goal = {0.0, 2.0, kPi / 2};
  b.activate({{"use_navigation_goal", Value{true}}, {"timeout_s", Value{0.5}}}, w.ctx);
  const auto cmd = b.step(w.ctx);
  REQUIRE(cmd);
  CHECK(cmd->vy_m_s > 0.0);  // holonomic by default: straight at the goal (to the left)
  for (int k = 0; k < 60 && b.running(); ++k) {
    (void)b.step(w.ctx);
    w.ctx.now += 10ms;
  }
  CHECK(b.failure_reason() == "timeout");
}

TEST_CASE("BhGoToPose reaches a goal behind the robot on a base without sideways motion") {
  KinematicWorld w;
  w.ctx.base.max_vy_m_s = 0.0;
  BhGoToPose b;
  b.activate({{"goal_x_m", Value{-1.0}}, {"goal_y_m", Value{0.5}}, {"goal_theta_rad", Value{-1.0}}}, w.ctx);
  w.run(b, 5000);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(std::hypot(w.pose.x_m + 1.0, w.pose.y_m - 0.5) <= 0.03 * 2);
  CHECK(std::abs(wrap_angle(w.pose.theta_rad + 1.0)) <= 0.03);
}

TEST_CASE("BhBackOff backs off the distance, then turns") {
  KinematicWorld w;
  w.pose.theta_rad = kPi / 2;
  w.publish();
  BhBackOff b;
  b.activate({{"distance_m", Value{0.3}}, {"turn_rad", Value{-kPi / 2}}}, w.ctx);
  w.run(b, 3000);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(w.pose.x_m == Approx(0.0).margin(1e-9));
  CHECK(w.pose.y_m == Approx(-0.3).margin(0.01));
  CHECK(w.pose.theta_rad == Approx(0.0).margin(0.03));
}

TEST_CASE("BhAvoidObstacle limits speed toward obstacles from the laser scan") {
  KinematicWorld w;
  LaserScan s;
  s.stamp = w.ctx.now;
  s.angle_min_rad = -kPi;
  s.angle_increment_rad = 2 * kPi / 360;
  s.angle_max_rad = s.angle_min_rad + 359 * s.angle_increment_rad;
  s.range_min_m = 0.05;
  s.range_max_m = 10.0;
  s.ranges_m.assign(360, std::numeric_limits<float>::infinity());
  s.ranges_m[180] = 0.65f;  // straight ahead, 0.4 m from a 0.25 m footprint
  s.ranges_m[270] = 0.30f;  // left (+90 deg), 0.05 m from the footprint
  w.laser.publish(s);
  BhAvoidObstacle b;
  b.activate({{"stop_distance_m", Value{0.1}}, {"slow_distance_m", Value{0.7}}, {"max_speed_m_s", Value{0.6}}}, w.ctx);
  CHECK_FALSE(b.step(w.ctx).has_value());  // it never commands, it limits
  REQUIRE(b.envelope());
  const VelocityEnvelope e = *b.envelope();
  CHECK(e.vx_hi_m_s == Approx(0.6 * (0.4 - 0.1) / 0.6).margin(1e-6));
  CHECK(std::isinf(e.vx_lo_m_s));  // nothing behind
  CHECK(e.vy_hi_m_s == 0.0);       // too close on the left
  CHECK(std::isinf(e.vy_lo_m_s));
  CHECK(std::isinf(e.wz_hi_rad_s));  // turning is never restricted
  // A stale scan blocks translation.
  w.ctx.now += 300ms;
  (void)b.step(w.ctx);
  REQUIRE(b.envelope());
  CHECK(b.envelope()->vx_hi_m_s == 0.0);
  CHECK(b.envelope()->vx_lo_m_s == 0.0);
  CHECK(std::isinf(b.envelope()->wz_lo_rad_s));
  REQUIRE_THROWS_WITH(b.activate({{"stop_distance_m", Value{1.0}}, {"slow_distance_m", Value{0.5}}}, w.ctx),
                      Catch::Contains("slow_distance_m must be greater than stop_distance_m"));
}

TEST_CASE("BhAvoidObstacle handles odd beam counts, NaN and out-of-range returns, and a mounted laser") {
  KinematicWorld w;
  LaserScan s;
  s.stamp = w.ctx.now;
  s.angle_min_rad = -kPi / 2;
  s.angle_increment_rad = kPi / 360;  // 361 beams over 180 degrees: not a multiple of 4
  s.angle_max_rad = kPi / 2;
  s.range_min_m = 0.1;
  s.range_max_m = 5.0;
  s.ranges_m.assign(361, std::numeric_limits<float>::quiet_NaN());
  s.ranges_m[0] = 0.05f;    // below range_min: ignored
  s.ranges_m[1] = 50.0f;    // beyond range_max: ignored
  s.ranges_m[360] = 0.45f;  // the last beam (+90 deg, left), handled after the SIMD blocks
  w.laser.publish(s);
  BhAvoidObstacle b;
  // The laser looks backwards from 0.1 m behind the centre: its +90 deg beam points right.
  b.activate({{"laser_x_m", Value{-0.1}}, {"laser_yaw_rad", Value{kPi}}, {"stop_distance_m", Value{0.1}},
              {"slow_distance_m", Value{0.5}}, {"max_speed_m_s", Value{0.4}}},
             w.ctx);
  (void)b.step(w.ctx);
  REQUIRE(b.envelope());
  const VelocityEnvelope e = *b.envelope();
  // The return is at body (-0.1, -0.45): 0.2 m right of the footprint's edge.
  CHECK(e.vy_lo_m_s == Approx(-0.4 * (0.2 - 0.1) / 0.4).margin(1e-5));
  CHECK(std::isinf(e.vy_hi_m_s));
  CHECK(std::isinf(e.vx_hi_m_s));
  CHECK(std::isinf(e.vx_lo_m_s));
}

namespace {

// BhAvoidObstacle's envelope written plainly, beam by beam (no tables of its own, no blocks, no
// skipping): the specification its optimised step must reproduce bit for bit. Directions as the
// behavior rounds them (float cosines of the laser-frame angle), arithmetic in double.
VelocityEnvelope reference_avoid_envelope(const LaserScan& scan, double stop_m, double slow_m, double max_speed, double r,
                                          double lx, double ly, double lyaw) {
  constexpr double kInf = VelocityEnvelope::kInf;
  double front = kInf, back = kInf, left = kInf, right = kInf;
  const auto rmin = static_cast<float>(scan.range_min_m);
  const auto near = static_cast<float>(std::min(scan.range_max_m, r + slow_m + std::hypot(lx, ly)));
  const double reach2 = (r + slow_m) * (r + slow_m);
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const float range = scan.ranges_m[i];
    if (!(range >= rmin && range <= near)) continue;
    const double a = lyaw + scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double x = lx + range * static_cast<double>(static_cast<float>(std::cos(a)));
    const double y = ly + range * static_cast<double>(static_cast<float>(std::sin(a)));
    if (std::abs(y) <= r) (x > 0.0 ? front : back) = std::min(x > 0.0 ? front : back, x > 0.0 ? x - r : -x - r);
    if (std::abs(x) <= r) (y > 0.0 ? left : right) = std::min(y > 0.0 ? left : right, y > 0.0 ? y - r : -y - r);
    const double d2 = x * x + y * y;
    if (d2 < reach2 && d2 > 0.0) {
      const double d = std::sqrt(d2);
      const double gap_d = std::max(d - r, 0.0) * d;
      if (std::abs(x) > 0.1 * d) (x > 0.0 ? front : back) = std::min(x > 0.0 ? front : back, gap_d / std::abs(x));
      if (std::abs(y) > 0.1 * d) (y > 0.0 ? left : right) = std::min(y > 0.0 ? left : right, gap_d / std::abs(y));
    }
  }
  auto allowed = [&](double clearance) {
    if (clearance > slow_m) return kInf;
    return max_speed * std::clamp((clearance - stop_m) / (slow_m - stop_m), 0.0, 1.0);
  };
  VelocityEnvelope env;
  env.vx_hi_m_s = allowed(front);
  env.vx_lo_m_s = -allowed(back);
  env.vy_hi_m_s = allowed(left);
  env.vy_lo_m_s = -allowed(right);
  return env;
}

}  // namespace

TEST_CASE("BhAvoidObstacle's envelope equals the plain per-beam computation exactly on seeded random scans") {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int limited = 0;
  for (int trial = 0; trial < 300; ++trial) {
    KinematicWorld w;
    LaserScan s;
    s.stamp = w.ctx.now;
    const std::size_t beams = 1 + static_cast<std::size_t>(unit(rng) * 720.0);
    s.angle_min_rad = -kPi + unit(rng);
    s.angle_increment_rad = (0.2 + 1.8 * unit(rng)) * kPi / static_cast<double>(beams);
    s.angle_max_rad = s.angle_min_rad + static_cast<double>(beams - 1) * s.angle_increment_rad;
    s.range_min_m = 0.05;
    s.range_max_m = 2.0 + 10.0 * unit(rng);
    s.ranges_m.resize(beams);
    const double clutter = unit(rng);
    for (float& r : s.ranges_m) {
      const double u = unit(rng);
      r = u < 0.02      ? std::numeric_limits<float>::quiet_NaN()
          : u < 0.04    ? std::numeric_limits<float>::infinity()
          : u < clutter ? static_cast<float>(0.01 + 1.5 * unit(rng))
                        : static_cast<float>(1.0 + 10.0 * unit(rng));
    }
    const double stop = 0.05 + 0.2 * unit(rng), slow = stop + 0.05 + unit(rng), speed = 0.2 + unit(rng);
    const double radius = 0.1 + 0.3 * unit(rng);
    const double lx = trial % 3 == 0 ? 0.0 : 0.3 * (unit(rng) - 0.5), ly = trial % 3 == 0 ? 0.0 : 0.3 * (unit(rng) - 0.5);
    const double lyaw = trial % 4 == 0 ? 0.0 : 2.0 * kPi * (unit(rng) - 0.5);
    w.laser.publish(s);
    BhAvoidObstacle b;
    b.activate({{"stop_distance_m", Value{stop}},
                {"slow_distance_m", Value{slow}},
                {"max_speed_m_s", Value{speed}},
                {"robot_radius_m", Value{radius}},
                {"laser_x_m", Value{lx}},
                {"laser_y_m", Value{ly}},
                {"laser_yaw_rad", Value{lyaw}}},
               w.ctx);
    (void)b.step(w.ctx);
    REQUIRE(b.envelope());
    const VelocityEnvelope e = *b.envelope();
    const VelocityEnvelope want = reference_avoid_envelope(s, stop, slow, speed, radius, lx, ly, lyaw);
    INFO("trial " << trial << ", " << beams << " beams");
    CHECK(e.vx_hi_m_s == want.vx_hi_m_s);
    CHECK(e.vx_lo_m_s == want.vx_lo_m_s);
    CHECK(e.vy_hi_m_s == want.vy_hi_m_s);
    CHECK(e.vy_lo_m_s == want.vy_lo_m_s);
    for (const double v : {e.vx_hi_m_s, -e.vx_lo_m_s, e.vy_hi_m_s, -e.vy_lo_m_s}) limited += v > 0.0 && v < speed ? 1 : 0;
  }
  CHECK(limited > 40);  // the trials exercise the proportional range, not only stop and free
}

namespace {

// Writes its channels while running; succeeds at step `finish_at` (writing in that step too).
class BhChannelWriter final : public CBehavior {
 public:
  explicit BhChannelWriter(std::size_t channels, std::uint64_t finish_at = 0) : finish_at_(finish_at) {
    ManifestBuilder b("BhChannelWriter", ModuleKind::behavior);
    for (std::size_t i = 0; i < channels; ++i) b.writes("out" + std::to_string(i), ChannelType::analog, "");
    b.writes_named_by("target", ChannelType::joint_position, "");
    b.text("target", "neck", "");
    manifest_ = std::move(b).build();
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return manifest_; }
  void on_activate(const ParameterSet&, const BehaviorContext&) override {}
  std::optional<Twist2D> on_step(const BehaviorContext&) noexcept override {
    write_channel(0, ChannelValue::of(0.5));
    if (steps() == finish_at_) succeed();
    return std::nullopt;
  }

 private:
  ModuleManifest manifest_;
  std::uint64_t finish_at_;
};

}  // namespace

TEST_CASE("Channel writes: names resolved at activation (a parameter names one), kept for one step, none from a finishing step",
          "[channels]") {
  BehaviorContext ctx;
  BhChannelWriter b(1, 3);
  b.activate(ParameterValues{{"target", Value{std::string("arm")}}}, ctx);
  CHECK(b.channel_name(0) == "out0");
  CHECK(b.channel_name(1) == "arm");
  (void)b.step(ctx);
  REQUIRE(b.channel_write(0).has_value());
  CHECK(b.channel_write(0)->number == 0.5);
  CHECK_FALSE(b.channel_write(1).has_value());  // not written this step
  (void)b.step(ctx);
  (void)b.step(ctx);  // succeeds: like its motion command, its writes of this step do not count
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK_FALSE(b.channel_write(0).has_value());

  BhChannelWriter greedy(kMaxBehaviorChannels);  // one more with the named one
  CHECK_THROWS_WITH(greedy.activate(ParameterValues{}, ctx),
                    Catch::Contains("behavior 'BhChannelWriter' declares 5 channel writes, at most 4"));
}
