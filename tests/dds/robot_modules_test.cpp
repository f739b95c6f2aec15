// The robot modules on DDS, created by name from the robot's registries like any plugin: a laser
// resource fed by a LaserScan topic, a controller publishing cmd_vel.
#include "tripodal/dds/robot_modules.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <thread>

#include "dds_test_support.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
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
  RobotPlugins plugins = builtin_plugins();
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
  RobotPlugins plugins = builtin_plugins();
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

TEST_CASE("dds: DdsPose, DdsImu and DdsOdometry hold a ROS 2 node's pose, IMU and odometry", "[dds]") {
  RobotPlugins plugins = builtin_plugins();
  register_dds_modules(plugins.resources, plugins.controllers);
  const std::uint32_t domain = test_domain(22);
  auto create = [&](const std::string& type, const std::string& name) {
    ResourceConfig config{name, ParameterSet::resolve(plugins.resources.manifest(type), binding(domain)), {}, nullptr};
    return plugins.resources.create(type, config);
  };
  auto pose_r = create("DdsPose", "amcl");
  auto imu_r = create("DdsImu", "imu");
  auto odom_r = create("DdsOdometry", "wheels");
  auto& pose = dynamic_cast<DdsPoseResource&>(*pose_r);
  auto& imu = dynamic_cast<DdsImuResource&>(*imu_r);
  auto& odom = dynamic_cast<DdsOdometryResource&>(*odom_r);
  CHECK(pose.topic() == ros_topic("amcl_pose", test_namespace()));
  CHECK(imu.topic() == ros_topic("imu", test_namespace()));
  CHECK(odom.topic() == ros_topic("odom", test_namespace()));

  Participant p(module_options(domain));
  // AMCL's QoS (reliable, transient local): the resource's reliable volatile reader matches it.
  Publisher<msg::PoseWithCovarianceStamped> amcl(
      p, ros_topic("amcl_pose", test_namespace()),
      {.qos = Qos{Reliability::reliable, Durability::transient_local, 1, {}, Liveliness::automatic, {}}});
  Publisher<msg::Imu> imu_pub(p, ros_topic("imu", test_namespace()), {.kind = TopicKind::scan});
  Publisher<msg::Odometry> odom_pub(p, ros_topic("odom", test_namespace()), {.kind = TopicKind::state});
  REQUIRE(amcl.wait_for_subscribers(1, 5s));
  REQUIRE(imu_pub.wait_for_subscribers(1, 5s));
  REQUIRE(odom_pub.wait_for_subscribers(1, 5s));

  const double yaw = 0.7;
  const msg::Quaternion q{0.0, 0.0, std::sin(yaw / 2.0), std::cos(yaw / 2.0)};
  msg::PoseWithCovarianceStamped a;
  a.pose.pose = {{1.5, -2.0, 0.0}, q};
  a.pose.covariance[0] = 0.04;   // x x
  a.pose.covariance[1] = 0.01;   // x y
  a.pose.covariance[35] = 0.09;  // yaw yaw
  amcl.publish(a);
  msg::Imu m;
  m.orientation = q;
  m.angular_velocity.z = -0.25;
  imu_pub.publish(m);
  msg::Odometry o;
  o.pose.pose = {{3.0, 4.0, 0.0}, q};
  o.twist.twist = {{0.2, 0.1, 0.0}, {0.0, 0.0, 0.3}};
  odom_pub.publish(o);

  const Time t0 = time_from_seconds(5.0);
  for (int i = 0; i < 1000 && (pose.received() == 0 || imu.received() == 0 || odom.received() == 0); ++i) std::this_thread::sleep_for(2ms);
  pose.poll(t0);
  imu.poll(t0);
  odom.poll(t0);
  REQUIRE(pose.has_reading());
  REQUIRE(imu.has_reading());
  REQUIRE(odom.has_reading());
  CHECK(pose.latest().stamp == t0);
  CHECK(pose.latest().map_from_base.x_m == 1.5);
  CHECK(pose.latest().map_from_base.y_m == -2.0);
  CHECK(pose.latest().map_from_base.theta_rad == Approx(yaw));
  // ROS's 6 x 6 over (x, y, z, roll, pitch, yaw) to the planar 3 x 3 over (x, y, yaw).
  CHECK(pose.latest().covariance == std::array<double, 9>{0.04, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.09});
  CHECK(imu.latest().yaw_rate_rad_s == -0.25);
  CHECK(imu.latest().yaw_rad == Approx(yaw));
  CHECK(odom.latest().pose.x_m == 3.0);
  CHECK(odom.latest().pose.theta_rad == Approx(yaw));
  CHECK(odom.latest().twist.vy_m_s == 0.1);
  CHECK(odom.latest().twist.wz_rad_s == 0.3);
  // Profile parameters are checked by the manifest: reliable is a flag.
  CHECK_THROWS_WITH(ParameterSet::resolve(plugins.resources.manifest("DdsPose"), {{"reliable", Value{2.0}}}),
                    Catch::Contains("reliable"));
}
