// The gesture behaviors: BhFaceVisitor turns the base to the person the laser sees (not to the
// walls the map holds), BhNeckGesture drives a joint through its position channel (it reads the
// joint's state from its JointResource).
#include "tripodal/behaviors/gesture_behaviors.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <numbers>

#include "tripodal/controllers/kinematics.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

// The map holds a wall along y = +wall_y_m (everything beyond counts as the map's).
struct WallMap final : ObstacleMap {
  double wall_y_m = std::numeric_limits<double>::infinity();
  [[nodiscard]] bool near_obstacle(double /*x_m*/, double y_m) const noexcept override { return y_m >= wall_y_m - 0.1; }
};

// A base turning on the spot at the origin, a 360-beam laser that sees one person (a disc) and
// an optional wall of the map, and odometry.
struct Scene {
  OdometryResource odom{"odom", 100ms};
  LaserResource laser{"laser", 500ms};
  ResourceTable table;
  NavigationData navi;
  WallMap map;
  BehaviorContext ctx;
  Pose2D pose;
  double person_x = 1.5, person_y = 1.0, person_r = 0.2;
  Scene() {
    table.add(odom);
    table.add(laser);
    ctx.period = 10ms;
    ctx.resources = &table;
    ctx.navi = &navi;
    ctx.base.max_vx_m_s = 0.5;
    ctx.base.max_wz_rad_s = 1.5;
    navi.map = &map;
    navi.localized = true;
    publish(true);
  }
  void publish(bool scan) {
    OdometryReading o;
    o.stamp = ctx.now;
    o.pose = pose;
    odom.publish(o);
    navi.map_from_base = pose;
    if (!scan) return;
    LaserScan s;
    s.stamp = ctx.now;
    s.angle_min_rad = -std::numbers::pi;
    s.angle_increment_rad = 2.0 * std::numbers::pi / 360.0;
    s.range_min_m = 0.1;
    s.range_max_m = 10.0;
    for (int i = 0; i < 360; ++i) {
      const double a = pose.theta_rad + s.angle_min_rad + i * s.angle_increment_rad;
      const double c = std::cos(a), sn = std::sin(a);
      double r = std::numeric_limits<double>::infinity();
      if (std::isfinite(map.wall_y_m) && sn > 1e-6) r = map.wall_y_m / sn;
      const double along = person_x * c + person_y * sn;
      const double across2 = person_x * person_x + person_y * person_y - along * along;
      if (along > 0.0 && across2 < person_r * person_r) r = std::min(r, along - std::sqrt(person_r * person_r - across2));
      s.ranges_m.push_back(static_cast<float>(r));
    }
    laser.publish(s);
  }
  int run(CBehavior& b, int max_steps) {
    int k = 0;
    for (; k < max_steps && b.running(); ++k) {
      const auto cmd = b.step(ctx);
      ctx.now += ctx.period;
      if (cmd) pose = integrate_body_displacement(pose, 0.0, 0.0, cmd->wz_rad_s * to_seconds(ctx.period));
      publish(k % 20 == 19);  // a scan every 0.2 s, odometry every step
    }
    return k;
  }
};

}  // namespace

TEST_CASE("BhFaceVisitor turns the base to face the person the laser sees", "[behaviors][gestures]") {
  Scene scene;
  BhFaceVisitor face;
  face.activate(ParameterValues{}, scene.ctx);
  REQUIRE(face.running());
  // The first scan it uses is the first taken after the activation.
  scene.run(face, 1000);
  CHECK(face.status() == BehaviorStatus::succeeded);
  CHECK(scene.pose.theta_rad == Approx(std::atan2(1.0, 1.5)).margin(0.1));
}

TEST_CASE("BhFaceVisitor ignores what the map holds: a wall nearer than the person", "[behaviors][gestures]") {
  Scene scene;
  scene.map.wall_y_m = 0.8;  // a mapped wall 0.8 m to the left, the person 1.1 m to the right
  scene.person_x = 0.5;
  scene.person_y = -1.0;
  BhFaceVisitor face;
  face.activate(ParameterValues{}, scene.ctx);
  scene.run(face, 1000);
  CHECK(face.status() == BehaviorStatus::succeeded);
  CHECK(scene.pose.theta_rad == Approx(std::atan2(-1.0, 0.5)).margin(0.1));
}

TEST_CASE("BhFaceVisitor: nobody within reach is nobody to face, and no laser fails", "[behaviors][gestures]") {
  Scene scene;
  scene.person_x = 5.0;  // beyond max_range_m (2.5 m)
  BhFaceVisitor face;
  face.activate(ParameterValues{}, scene.ctx);
  scene.run(face, 100);
  CHECK(face.status() == BehaviorStatus::succeeded);
  CHECK(scene.pose.theta_rad == 0.0);

  ResourceTable empty;
  BehaviorContext ctx = scene.ctx;
  ctx.resources = &empty;
  BhFaceVisitor blind;
  blind.activate(ParameterValues{}, ctx);
  CHECK(blind.status() == BehaviorStatus::failed);
  CHECK(blind.failure_reason() == "no laser");
}

namespace {

// A joint following its commands at 1 rad/s within [-0.5, 0.8], published every step.
struct JointModel {
  JointResource joint{"neck", 100ms};
  ResourceTable table;
  BehaviorContext ctx;
  double position = 0.0, target = 0.0;
  JointModel() {
    table.add(joint);
    ctx.period = 10ms;
    ctx.resources = &table;
    publish(0.0);
  }
  void publish(double velocity) {
    joint.publish({ctx.now, position, velocity, target, -0.5, 0.8});
  }
  int run(CBehavior& b, int max_steps) {
    int k = 0;
    for (; k < max_steps && b.running(); ++k) {
      const auto cmd = b.step(ctx);
      CHECK_FALSE(cmd.has_value());  // a gesture of the head never drives the base
      ctx.now += ctx.period;
      // The joint's driver takes what the behavior wrote to its channel (the behavior's only one).
      if (const auto& c = b.channel_write(0)) target = std::clamp(c->number, -0.5, 0.8);
      const double step = std::clamp(target - position, -0.01, 0.01);
      position = std::abs(target - position) <= 0.01 ? target : position + step;
      publish(step / 0.01);
    }
    return k;
  }
};

}  // namespace

TEST_CASE("BhNeckGesture moves the joint to its angle and succeeds when it has stopped there", "[behaviors][gestures]") {
  JointModel m;
  BhNeckGesture nod;
  nod.activate(ParameterValues{{"angle_deg", Value{30.0}}}, m.ctx);
  CHECK(nod.channel_name(0) == "neck");  // the channel its parameter joint names
  const int steps = m.run(nod, 1000);
  CHECK(nod.status() == BehaviorStatus::succeeded);
  CHECK(m.position == Approx(30.0 * std::numbers::pi / 180.0));
  CHECK(steps == Approx(54).margin(3));  // 0.52 rad at 1 rad/s

  BhNeckGesture too_far;
  too_far.activate(ParameterValues{{"angle_deg", Value{-60.0}}}, m.ctx);
  m.run(too_far, 1000);
  CHECK(too_far.status() == BehaviorStatus::failed);
  CHECK(too_far.failure_reason() == "joint limit");

  BhNeckGesture none;
  none.activate(ParameterValues{{"joint", Value{std::string("arm")}}}, m.ctx);
  CHECK(none.failure_reason() == "no joint");

  BhNeckGesture slow;
  slow.activate(ParameterValues{{"angle_deg", Value{-25.0}}, {"timeout_s", Value{0.2}}}, m.ctx);
  m.run(slow, 1000);
  CHECK(slow.failure_reason() == "timeout");
}
