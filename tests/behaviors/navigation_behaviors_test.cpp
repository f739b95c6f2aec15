// The navigation behaviors on their own: PathTracker, and BhAutoMove, BhCleaning,
// BhCleaningTwoWheel and BhGlobalLocalization stepped by hand with the NavigationData the
// sequencing layer would publish (path, path_id, path_start_m, path_final, path_failure, fixes) and
// the feedback they report back. The body moves by integrating the commands (an ideal base), so
// these tests see what the behaviors themselves do; the modules in closed loop on the simulator are
// tests/navi/navigation_modules_test.cpp.
#include "tripodal/behaviors/navigation_behaviors.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

constexpr double kPi = std::numbers::pi;

ParameterValues params(std::initializer_list<std::pair<const std::string, std::string>> kv) {
  ParameterValues v;
  for (const auto& [k, s] : kv) v.emplace(k, Value{s});
  return v;
}

// A scan (360 beams, robot frame) with a return at `range_m` within +-half_width_rad of straight
// ahead, nothing elsewhere.
LaserScan scan_with_obstacle_ahead(Time stamp, double range_m, double half_width_rad) {
  LaserScan s;
  s.stamp = stamp;
  s.angle_min_rad = -kPi;
  s.angle_increment_rad = 2 * kPi / 360;
  s.angle_max_rad = s.angle_min_rad + 359 * s.angle_increment_rad;
  s.range_min_m = 0.05;
  s.range_max_m = 12.0;
  s.ranges_m.assign(360, std::numeric_limits<float>::infinity());
  for (int i = 0; i < 360; ++i) {
    const double a = s.angle_min_rad + i * s.angle_increment_rad;
    if (std::abs(a) <= half_width_rad) s.ranges_m[static_cast<std::size_t>(i)] = static_cast<float>(range_m);
  }
  return s;
}

// The map of the test: everything beyond x = 1 m is a wall it holds.
class WallBeyondOneMetre final : public ObstacleMap {
 public:
  [[nodiscard]] bool near_obstacle(double x_m, double /*y_m*/) const noexcept override { return x_m > 1.0; }
};

// What the reactive loop gives a behavior, by hand: 20 Hz steps; the commands move an ideal base.
struct Bench {
  NavigationData navi;
  LaserResource laser{"laser", 500ms};
  ResourceTable table;
  NavigationFeedback feedback;
  BehaviorContext ctx;
  std::vector<Pose2D> path;
  Time now{};
  double max_turn_rate = 0.0;

  explicit Bench(bool omni, Pose2D start = {0.6, 2.0, 0.0}) {
    table.add(laser);
    ctx.period = 50ms;
    ctx.resources = &table;
    ctx.navi = &navi;
    ctx.feedback = &feedback;
    ctx.base = BaseCapabilities{0.8, omni ? 0.8 : 0.0, 2.0};
    navi.map_from_base = start;
    navi.localized = true;
    navi.robot_radius_m = 0.2;
  }
  // What a path planner would publish.
  void publish(std::vector<Pose2D> points, std::uint32_t id, double start_m = 0.0, bool final = true) {
    path = std::move(points);
    navi.path = path;
    navi.path_id = id;
    navi.path_start_m = start_m;
    navi.path_final = final;
  }
  // One period: the behavior's command, executed for the period.
  std::optional<Twist2D> step(CBehavior& b) {
    ctx.now = now;
    feedback = NavigationFeedback{};
    const std::optional<Twist2D> cmd = b.step(ctx);
    const Twist2D v = cmd.value_or(Twist2D{});
    Pose2D& p = navi.map_from_base;
    const double dt = to_seconds(ctx.period);
    p.x_m += (std::cos(p.theta_rad) * v.vx_m_s - std::sin(p.theta_rad) * v.vy_m_s) * dt;
    p.y_m += (std::sin(p.theta_rad) * v.vx_m_s + std::cos(p.theta_rad) * v.vy_m_s) * dt;
    p.theta_rad = wrap_angle(p.theta_rad + v.wz_rad_s * dt);
    max_turn_rate = std::max(max_turn_rate, std::abs(v.wz_rad_s));
    now += ctx.period;
    return cmd;
  }
  // Steps while `b` runs, at most max_s; returns the seconds stepped.
  double run(CBehavior& b, double max_s, const std::function<void()>& each = {}) {
    const Time start = now;
    while (b.running() && now - start < from_seconds(max_s)) {
      if (each) each();
      (void)step(b);
    }
    return to_seconds(now - start);
  }
};

double distance(const Pose2D& a, const Pose2D& b) {
  return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// PathTracker

TEST_CASE("PathTracker takes a path up at an arc length and its progress never goes back",
          "[behaviors][navigation]") {
  PathTracker t;
  t.reserve(16);
  const std::vector<Pose2D> line{{0, 0, 0}, {2, 0, 0}, {4, 0, 0}};
  t.reset(line, 1.5);
  CHECK(t.length_m() == Approx(4.0));
  CHECK(t.progress_m() == Approx(1.5));
  CHECK(t.at(3.0).x_m == Approx(3.0));
  CHECK(t.at(-1.0).x_m == 0.0);
  CHECK(t.at(9.0).x_m == 4.0);
  // Beside the path at x = 2.2: progress there, lookahead point ahead of it on the path.
  PathTracker::Target target = t.update({2.2, 0.1, 0.0}, 0.5, 1.0);
  CHECK(t.progress_m() == Approx(2.2));
  CHECK(target.cross_track_m == Approx(0.1));
  CHECK(target.point.x_m == Approx(2.7));
  CHECK(target.point.y_m == Approx(0.0).margin(1e-9));
  CHECK(target.remaining_m == Approx(1.8));
  // Pushed back behind it: the progress stays.
  (void)t.update({1.0, 0.0, 0.0}, 0.5, 1.0);
  CHECK(t.progress_m() == Approx(2.2));
  // A start beyond the end is clamped to it.
  t.reset(line, 10.0);
  CHECK(t.progress_m() == Approx(4.0));
}

TEST_CASE("PathTracker searches only a short arc ahead, stops the lookahead at corners, keeps its capacity",
          "[behaviors][navigation]") {
  PathTracker t;
  t.reserve(8);
  // Out along y = 0 and back along y = 0.3, a round of a spiral: near the start, the way back
  // is closer than the way out but far ahead along the path.
  const std::vector<Pose2D> u{{0, 0, 0}, {2, 0, 0}, {2, 0.3, 0}, {0, 0.3, 0}};
  t.reset(u);
  (void)t.update({0.1, 0.2, 0.0}, 0.1, 1.0);
  CHECK(t.progress_m() == Approx(0.1));
  // The lookahead point stops before the corner at (2, 0) instead of cutting it.
  t.reset(u);
  const PathTracker::Target target = t.update({1.8, 0.0, 0.0}, 0.6, 1.0);
  CHECK(target.point.x_m <= 2.0 + 1e-9);
  CHECK(target.point.y_m == Approx(0.0).margin(1e-9));
  CHECK(target.corner_rad > 0.45);
  // Points beyond the reserved capacity are dropped: reset never allocates.
  std::vector<Pose2D> long_path;
  for (int i = 0; i < 20; ++i) long_path.push_back({0.1 * i, 0.0, 0.0});
  t.reset(long_path);
  CHECK(t.points().size() == 8);
  CHECK(t.capacity() == 8);
}

TEST_CASE("PathTracker::at walks from the progress and agrees with interpolating over the whole path",
          "[behaviors][navigation]") {
  // A zigzag of 200 segments of uneven lengths, one repeated point (a zero-length segment).
  std::vector<Pose2D> zig;
  for (int i = 0; i < 200; ++i) zig.push_back({0.05 * i + 0.01 * (i % 7), (i % 2 == 0 ? 0.0 : 0.2 + 0.01 * (i % 5)), 0.0});
  zig.insert(zig.begin() + 50, zig[50]);
  std::vector<double> s{0.0};
  for (std::size_t i = 1; i < zig.size(); ++i) s.push_back(s.back() + std::hypot(zig[i].x_m - zig[i - 1].x_m, zig[i].y_m - zig[i - 1].y_m));
  const auto brute = [&](double q) {
    if (q <= 0.0) return zig.front();
    if (q >= s.back()) return zig.back();
    std::size_t j = 1;
    while (s[j] <= q) ++j;
    const double t = (q - s[j - 1]) / (s[j] - s[j - 1]);
    return Pose2D{zig[j - 1].x_m + t * (zig[j].x_m - zig[j - 1].x_m), zig[j - 1].y_m + t * (zig[j].y_m - zig[j - 1].y_m), 0.0};
  };
  PathTracker t;
  t.reserve(512);
  for (const double start : {0.0, 0.3, s[50], 7.77, s.back() - 0.01}) {
    t.reset(zig, start);
    INFO("progress " << start);
    for (double q = -0.5; q <= s.back() + 0.5; q += 0.0137) {  // behind, around and far ahead of it
      const Pose2D a = t.at(q);
      const Pose2D b = brute(q);
      REQUIRE(a.x_m == Approx(b.x_m).margin(1e-12));
      REQUIRE(a.y_m == Approx(b.y_m).margin(1e-12));
    }
  }
}

TEST_CASE("PathTracker::update gives the same target for the same inputs, and searches again once they change",
          "[behaviors][navigation]") {
  const std::vector<Pose2D> line{{0, 0, 0}, {2, 0, 0}, {4, 0, 0}};
  PathTracker t;
  t.reserve(8);
  t.reset(line);
  const PathTracker::Target first = t.update({1.0, 0.1, 0.0}, 0.5, 1.0);
  const PathTracker::Target again = t.update({1.0, 0.1, 0.0}, 0.5, 1.0);
  CHECK(again.point.x_m == first.point.x_m);
  CHECK(again.remaining_m == first.remaining_m);
  CHECK(t.update({1.0, 0.1, 0.0}, 0.8, 1.0).point.x_m == Approx(1.8));  // another lookahead
  CHECK(t.update({1.5, 0.1, 0.0}, 0.5, 1.0).point.x_m == Approx(2.0));  // moved on
  t.reset(line, 3.0);                                                    // a new path start
  CHECK(t.update({1.5, 0.1, 0.0}, 0.5, 1.0).point.x_m == Approx(3.5));
}

// ---------------------------------------------------------------------------------------------
// The path-following behaviors against hand-made navigation data

TEST_CASE("A path-following behavior takes up each new path_id at path_start_m and reports its progress",
          "[behaviors][navigation]") {
  Bench bench(true);
  BhAutoMove b;
  b.activate(params({{"goal", "door"}}), bench.ctx);
  REQUIRE(b.running());
  bench.publish({{0.6, 2.0, 0}, {5.4, 2.0, 0}}, 1);
  (void)bench.step(b);
  CHECK(b.tracker().points().size() == 2);
  CHECK(bench.feedback.path_id == 1);
  CHECK(bench.feedback.progress_m == Approx(0.0).margin(1e-9));
  CHECK_FALSE(bench.feedback.blocked);
  // A detour published under a new id, taken up 1 m along.
  bench.publish({{0.6, 2.0, 0}, {0.6, 3.0, 0}, {3.0, 3.0, 0}}, 2, 1.0, false);
  (void)bench.step(b);
  CHECK(b.tracker().points().size() == 3);
  CHECK(bench.feedback.path_id == 2);
  CHECK(bench.feedback.progress_m >= 1.0);
  // The same id with other points is not a new path: the behavior keeps what it took up.
  std::vector<Pose2D> other{{9, 9, 0}, {9, 8, 0}};
  bench.navi.path = other;
  (void)bench.step(b);
  CHECK(b.tracker().points().size() == 3);
  CHECK(b.tracker().points().front().x_m == 0.6);
}

TEST_CASE(
    "A path-following behavior fails with the reason the sequencing layer gives, or 'no path' after the "
    "timeout",
    "[behaviors][navigation]") {
  Bench bench(false);
  BhAutoMove b;
  b.activate(params({{"goal", "kitchen"}}), bench.ctx);
  bench.navi.path_failure = "unknown goal";
  const auto cmd = bench.step(b);
  CHECK_FALSE(cmd);
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "unknown goal");

  bench.navi.path_failure = {};
  BhCleaningTwoWheel c;
  c.activate(params({{"section", "A"}, {"blocked_timeout_s", "2"}}), bench.ctx);
  const double t = bench.run(c, 10.0, [&] { CHECK(bench.navi.path_id == 0); });
  CHECK(c.status() == BehaviorStatus::failed);
  CHECK(c.failure_reason() == "no path");
  CHECK(t == Approx(2.05).margin(0.06));
  CHECK(distance(bench.navi.map_from_base, {0.6, 2.0, 0.0}) == 0.0);  // it stood still meanwhile
}

TEST_CASE(
    "A path-following behavior stops before an obstacle the map does not hold, reports it blocked, fails "
    "when blocked too long",
    "[behaviors][navigation]") {
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    Bench bench(omni);
    BhAutoMove b;
    b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "3"}}), bench.ctx);
    bench.publish({{0.6, 2.0, 0}, {5.4, 2.0, 0}}, 1);
    // Something 0.24 m ahead of the body's centre, moving with it: 4 cm from the footprint.
    std::optional<Time> blocked_since;
    const double t = bench.run(b, 20.0, [&] {
      bench.laser.publish(scan_with_obstacle_ahead(bench.now, 0.24, 0.3));
      if (bench.feedback.blocked && !blocked_since) blocked_since = bench.feedback.blocked_since;
    });
    CHECK(b.status() == BehaviorStatus::failed);
    CHECK(b.failure_reason() == "path blocked");
    REQUIRE(blocked_since);
    CHECK(to_seconds(*blocked_since) < 0.1);  // stopped from the first period
    CHECK(t > 3.0);
    CHECK(t < 3.2);
    CHECK(bench.navi.map_from_base.x_m < 0.61);  // it did not drive into it
  }
}

TEST_CASE("A path-following behavior is not stopped by laser returns of what the map holds",
          "[behaviors][navigation]") {
  Bench bench(true);
  WallBeyondOneMetre map;
  bench.navi.map = &map;
  BhAutoMove b;
  b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "1"}}), bench.ctx);
  bench.publish({{0.6, 2.0, 0}, {0.95, 2.0, 0}}, 1);
  // The wall at 1.05 m is 0.25 m ahead of the centre at the start: the map's, not in the way.
  const double t = bench.run(b, 20.0, [&] {
    bench.laser.publish(scan_with_obstacle_ahead(bench.now, 1.05 - bench.navi.map_from_base.x_m, 0.3));
  });
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(t < 3.0);
}

TEST_CASE(
    "BhAutoMove drives to the end of a final path and succeeds: an omni base keeps its heading, a "
    "differential one steers",
    "[behaviors][navigation]") {
  const std::vector<Pose2D> around{{0.6, 2.0, 0}, {2.0, 0.6, 0}, {4.0, 0.6, 0}, {5.4, 2.0, 0}};
  for (const bool omni : {true, false}) {
    INFO((omni ? "omni" : "differential"));
    Bench bench(omni, {0.6, 2.0, 0.3});
    BhAutoMove b;
    b.activate(params({{"goal", "door"}}), bench.ctx);
    bench.publish(around, 1);
    double worst_cross_track = 0.0;
    const double t = bench.run(b, 60.0, [&] {
      const Pose2D& p = bench.navi.map_from_base;
      if (p.x_m > 2.2 && p.x_m < 3.8) worst_cross_track = std::max(worst_cross_track, std::abs(p.y_m - 0.6));
    });
    CHECK(b.status() == BehaviorStatus::succeeded);
    CHECK(distance(bench.navi.map_from_base, {5.4, 2.0, 0}) <= 0.1);
    CHECK(worst_cross_track < 0.05);  // on the path, not cutting across
    CHECK(t < 30.0);
    if (omni) {
      CHECK(bench.navi.map_from_base.theta_rad == Approx(0.3).margin(0.01));
    } else {
      CHECK(bench.max_turn_rate > 0.5);
    }
  }
}

TEST_CASE("A cleaning behavior holds at the end of a detour and succeeds at the end of the coverage path",
          "[behaviors][navigation][cleaning]") {
  Bench bench(true, {0.5, 0.5, 0.0});
  BhCleaning b;
  b.activate(params({{"section", "A"}}), bench.ctx);
  bench.publish({{0.5, 0.5, 0}, {0.5, 1.5, 0}, {1.5, 1.5, 0}}, 1, 0.0, false);  // a detour
  (void)bench.run(b, 20.0);
  REQUIRE(b.running());  // 20 s later: still waiting for the way on
  CHECK(bench.feedback.reached_end);
  CHECK(distance(bench.navi.map_from_base, {1.5, 1.5, 0}) < 0.1);
  const auto held = bench.step(b);
  REQUIRE(held);
  CHECK(*held == Twist2D{});
  // The coverage path again, taken up beyond the obstacle: it ends there.
  bench.publish({{0.5, 0.5, 0}, {1.5, 0.5, 0}, {1.5, 1.5, 0}, {2.5, 1.5, 0}}, 2, 2.0, true);
  const double t = bench.run(b, 20.0);
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(distance(bench.navi.map_from_base, {2.5, 1.5, 0}) <= 0.1);
  CHECK(t < 8.0);
}

TEST_CASE("The path-following behaviors pause while the robot is not localized", "[behaviors][navigation]") {
  Bench bench(false);
  BhAutoMove b;
  b.activate(params({{"goal", "door"}, {"blocked_timeout_s", "1"}}), bench.ctx);
  bench.publish({{0.6, 2.0, 0}, {5.4, 2.0, 0}}, 1);
  bench.navi.localized = false;
  for (int k = 0; k < 40; ++k) {  // longer than the timeouts: pausing is not failing
    const auto cmd = bench.step(b);
    REQUIRE(cmd);
    CHECK(*cmd == Twist2D{});
  }
  CHECK(b.running());
  CHECK(bench.feedback.path_id == 0);  // nothing tracked, nothing reported
  bench.navi.localized = true;
  const auto cmd = bench.step(b);
  REQUIRE(cmd);
  CHECK(cmd->vx_m_s > 0.0);
}

TEST_CASE("Navigation behaviors refuse what they cannot do, with located parameter errors",
          "[behaviors][navigation]") {
  Bench bench(false);
  BhCleaning omni_only;
  omni_only.activate(params({{"section", "A"}}), bench.ctx);
  CHECK(omni_only.status() == BehaviorStatus::failed);
  CHECK(omni_only.failure_reason() == "BhCleaning needs an omni-directional base");
  BhAutoMove b;
  REQUIRE_THROWS_WITH(b.activate(params({{"goal", "door"}, {"max_speed_m_s", "-1"}}), bench.ctx,
                                 SourceLocation{"PrAutoMove.xml", 9, 5}),
                      Catch::Contains("PrAutoMove.xml:9:5: error: BhAutoMove: parameter 'max_speed_m_s'"));
  BhCleaningTwoWheel c;
  REQUIRE_THROWS_WITH(
      c.activate(params({{"section", "A"}, {"speed", "1"}}), bench.ctx,
                 SourceLocation{"PrCleaning.xml", 20, 6}),
      Catch::Contains("PrCleaning.xml:20:6: error: BhCleaningTwoWheel: unknown parameter 'speed'"));
}

TEST_CASE("BhGlobalLocalization turns until the localizer accepts a fix, or gives up after timeout_s",
          "[behaviors][navigation]") {
  Bench bench(true, {1.0, 1.0, 0.0});
  bench.navi.fixes = 3;  // fixes of earlier searches do not count
  BhGlobalLocalization b;
  b.activate(ParameterValues{}, bench.ctx);
  const double t = bench.run(b, 60.0, [&] {
    if (bench.now >= Time{6s}) bench.navi.fixes = 4;
  });
  CHECK(b.status() == BehaviorStatus::succeeded);
  CHECK(t == Approx(6.05).margin(0.06));
  CHECK(std::abs(bench.navi.map_from_base.theta_rad) > 0.5);  // it turned meanwhile
  b.activate(params({{"timeout_s", "5"}}), bench.ctx);
  const double t2 = bench.run(b, 60.0);
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "no position found");
  CHECK(t2 == Approx(5.05).margin(0.06));
}

TEST_CASE("register_navigation_behaviors registers the four behaviors by name", "[behaviors][navigation]") {
  BehaviorRegistry reg;
  register_navigation_behaviors(reg);
  CHECK(reg.names() ==
        std::vector<std::string>{"BhAutoMove", "BhCleaning", "BhCleaningTwoWheel", "BhGlobalLocalization"});
  for (const auto& n : reg.names()) {
    auto b = reg.create(n);
    CHECK(b->name() == n);
    for (const auto& p : b->manifest().parameters) CHECK_FALSE(p.description.empty());
  }
  REQUIRE_THROWS_WITH(reg.create("BhClean"), Catch::Contains("unknown behavior type 'BhClean'; known: BhAutoMove, BhCleaning, "
                                                             "BhCleaningTwoWheel, BhGlobalLocalization; did you mean 'BhCleaning'?"));
}

TEST_CASE(
    "A path-following behavior held still by a safety input reports itself blocked after safety_hold_s, not "
    "before, and not once released",
    "[behaviors][navigation][safety]") {
  Bench bench(false);
  BhAutoMove b;
  b.activate(params({{"goal", "door"}, {"safety_hold_s", "1"}, {"blocked_timeout_s", "3"}}), bench.ctx);
  bench.publish({{0.6, 2.0, 0}, {5.4, 2.0, 0}}, 1);
  // What the loop hands over: the safety override of the previous period's command. The base
  // stands still (no laser return: the behavior itself sees nothing in the way).
  SafetyFeedback safety;
  bench.ctx.safety = &safety;
  const auto step = [&](bool held, double allowed_fraction = 0.0) {
    bench.ctx.now = bench.now;
    bench.feedback = NavigationFeedback{};
    const Twist2D cmd = b.step(bench.ctx).value_or(Twist2D{});
    safety.limited = held;
    safety.requested = cmd;
    safety.allowed = held ? Twist2D{allowed_fraction * cmd.vx_m_s, 0.0, cmd.wz_rad_s} : cmd;
    safety.limited_by = held ? "BhAvoidObstacle" : "";
    bench.now += bench.ctx.period;
    return cmd;
  };
  for (int i = 0; i < 10; ++i) CHECK(step(false).vx_m_s > 0.1);  // free: it drives on
  CHECK_FALSE(bench.feedback.blocked);

  // Slowed (to half) but not held: never blocked.
  for (int i = 0; i < 40; ++i) step(true, 0.5);
  CHECK_FALSE(bench.feedback.blocked);

  // Held: the first step that sees the hold starts the timer; blocked from 1 s on, not before.
  (void)step(true);
  const Time held_from = bench.now;
  std::optional<Time> blocked_at;
  while (bench.now - held_from < 1500ms) {
    (void)step(true);
    if (bench.feedback.blocked && !blocked_at) blocked_at = bench.ctx.now;
    if (!blocked_at) CHECK_FALSE(bench.feedback.blocked);
  }
  REQUIRE(blocked_at);
  CHECK(to_seconds(*blocked_at - held_from) == Approx(1.0).margin(0.051));
  CHECK(bench.feedback.blocked_since == *blocked_at);
  CHECK(b.running());

  // Released: not blocked once the release reaches the behavior (the step after the one whose
  // command was let through), and the hold starts again from zero.
  (void)step(false);
  CHECK(step(false).vx_m_s > 0.1);
  CHECK_FALSE(bench.feedback.blocked);
  for (int i = 0; i < 10; ++i) (void)step(true);  // 0.5 s held: under safety_hold_s
  CHECK_FALSE(bench.feedback.blocked);
  // A hold that reaches another behavior's command (context.safety null) is not this one's.
  bench.ctx.safety = nullptr;
  for (int i = 0; i < 40; ++i) (void)step(true);
  CHECK_FALSE(bench.feedback.blocked);

  // Held for good: blocked after 1 s, then "path blocked" after blocked_timeout_s (3 s) more, as
  // before an obstacle on the path (the replanning and the recovery rules take it from there).
  bench.ctx.safety = &safety;
  const Time from = bench.now;
  while (b.running() && bench.now - from < 10s) (void)step(true);
  CHECK(b.status() == BehaviorStatus::failed);
  CHECK(b.failure_reason() == "path blocked");
  CHECK(to_seconds(bench.now - from) == Approx(4.1).margin(0.15));
}

// A safety reflex backing the robot off (a drop ahead: BhCliffGuard pins the translation at
// -0.1 m/s) lets it make no progress along its path: held, as when stopped, so the sequencing
// layer plans around the hazard instead of the behavior driving back at it once released.
TEST_CASE("A path-following behavior backed off by a safety input counts as held", "[behaviors][navigation][safety]") {
  Bench bench(false);
  BhAutoMove b;
  b.activate(params({{"goal", "door"}, {"safety_hold_s", "1"}, {"blocked_timeout_s", "30"}}), bench.ctx);
  bench.publish({{0.6, 2.0, 0}, {5.4, 2.0, 0}}, 1);
  SafetyFeedback safety;
  bench.ctx.safety = &safety;
  const Time from = bench.now;
  std::optional<Time> blocked_at;
  while (bench.now - from < 1500ms) {
    bench.ctx.now = bench.now;
    bench.feedback = NavigationFeedback{};
    const Twist2D cmd = b.step(bench.ctx).value_or(Twist2D{});
    safety.limited = true;
    safety.requested = cmd;
    safety.allowed = Twist2D{-0.1, 0.0, 0.0};
    safety.limited_by = "BhCliffGuard";
    if (bench.feedback.blocked && !blocked_at) blocked_at = bench.ctx.now;
    bench.now += bench.ctx.period;
  }
  REQUIRE(blocked_at);
  CHECK(to_seconds(*blocked_at - from) == Approx(1.0).margin(0.051));
}
