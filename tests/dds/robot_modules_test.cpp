// The robot modules on DDS, created by name from the robot's registries like any plugin: a laser
// resource fed by a LaserScan topic, a controller publishing cmd_vel.
#include <catch2/catch.hpp>

#include <cmath>
#include <thread>

#include "dds_test_support.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/dds/robot_modules.hpp"
#include "tripodal/robot/plugins.hpp"

using namespace tripodal;
using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {
// The modules' participants have the default options; a participant of the test in the same
// process and domain must have the same (one Cyclone domain per process and id).
ParticipantOptions module_options(std::uint32_t domain) {
  ParticipantOptions o;
  o.domain_id = domain;
  return o;
}
ParameterValues binding(std::uint32_t domain) {
  return {{"namespace", Value{test_namespace()}}, {"domain_id", Value{static_cast<double>(domain)}}};
}
}  // namespace

TEST_CASE("dds: the DdsLaser resource holds the scans of its topic", "[dds]") {
  RobotPlugins plugins = RobotPlugins::with_builtins();
  register_dds_modules(plugins.resources, plugins.controllers);
  REQUIRE(plugins.resources.contains("DdsLaser"));
  const ModuleManifest& manifest = plugins.resources.manifest("DdsLaser");
  CHECK(manifest.kind == ModuleKind::resource);

  auto given = binding(test_domain(20));
  given["max_age_s"] = Value{0.2};
  ResourceConfig config{"laser", ParameterSet::resolve(manifest, given), {}, nullptr};
  auto resource = plugins.resources.create("DdsLaser", config);
  auto& laser = dynamic_cast<DdsLaserResource&>(*resource);
  CHECK(laser.topic() == ros_topic("scan", test_namespace()));

  Participant p(module_options(test_domain(20)));
  Publisher<msg::LaserScan> scans(p, ros_topic("scan", test_namespace()), {.kind = TopicKind::scan});
  REQUIRE(scans.wait_for_subscribers(1, 5s));
  const auto sent = sample_scan();
  scans.publish(sent);

  const Time t0 = time_from_seconds(10.0);
  for (int i = 0; i < 500 && !laser.has_reading(); ++i) {
    std::this_thread::sleep_for(2ms);
    laser.poll(t0);
  }
  REQUIRE(laser.has_reading());
  const LaserScan& got = laser.latest();
  CHECK(got.stamp == t0);  // the loop's time of the poll that handed it over
  CHECK(got.ranges_m == sent.ranges);
  CHECK(got.intensities == sent.intensities);
  CHECK(got.angle_min_rad == Approx(-2.0));
  CHECK(got.angle_increment_rad == Approx(0.5));
  CHECK(got.range_max_m == Approx(30.0));
  CHECK(laser.sequence() == 1);
  CHECK(laser.is_fresh(t0 + 100ms));
  CHECK(laser.is_stale(t0 + 300ms));  // the laser went silent: stale after max_age_s
  laser.poll(t0 + 300ms);              // nothing new: the reading stays as it was
  CHECK(laser.sequence() == 1);
}

TEST_CASE("dds: the dds_cmd_vel controller publishes its limited command", "[dds]") {
  RobotPlugins plugins = RobotPlugins::with_builtins();
  register_dds_modules(plugins.resources, plugins.controllers);
  REQUIRE(plugins.controllers.contains("dds_cmd_vel"));

  ControllerConfig config;
  config.type = "dds_cmd_vel";
  config.limits.vx.max_velocity = 0.5;
  auto given = binding(test_domain(21));
  given["period_s"] = Value{0.1};
  config.parameters = ParameterSet::resolve(plugins.controllers.manifest("dds_cmd_vel"), given);
  apply_parameters(config);
  IdealWheelHardware no_wheels(2, config.period);
  auto controller = plugins.controllers.create(config, no_wheels);
  CHECK(controller->capabilities().max_vy_m_s == 0.0);
  CHECK(controller->capabilities().max_vx_m_s == 0.5);

  Participant p(module_options(test_domain(21)));
  Subscriber<msg::Twist> base(p, ros_topic("cmd_vel", test_namespace()), {.kind = TopicKind::command});
  REQUIRE(base.wait_for_publishers(1, 5s));

  const Time t0 = time_from_seconds(1.0);
  controller->set_command({1.0, 0.2, 0.3}, t0);
  CHECK(controller->update(t0) == ControlStatus::limited);
  auto got = base.take_one(5s);
  REQUIRE(got.has_value());
  CHECK(got->linear.x == Approx(0.5));  // clipped to limits.vx.max_velocity
  CHECK(got->linear.y == 0.0);          // not holonomic
  CHECK(got->angular.z == Approx(0.3));
  controller->update(t0 + 100ms);
  REQUIRE(base.take_one(5s).has_value());
  // Dead reckoning: 0.5 m/s for two periods of 0.1 s, turning at 0.3 rad/s.
  CHECK(controller->odometry().pose.x_m == Approx(0.05 + 0.05 * std::cos(0.03)));
  CHECK(controller->odometry().pose.theta_rad == Approx(0.06));
  CHECK(controller->wheel_commands().empty());
}
