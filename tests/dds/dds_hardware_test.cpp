// The hardware type "dds" through the library: created by name, its wheel commands out on cmd_vel by
// the base's kinematics, no simulator a fault rather than a hang, its bad parameters located. The
// lock-step with `tripodal sim-server` is tests/dds/sim_server_test.cpp (two processes).
#include "tripodal/dds/dds_hardware.hpp"

#include <array>
#include <catch2/catch.hpp>
#include <chrono>

#include "dds_test_support.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/controllers/base_kinematics.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"

using namespace tripodal;
using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {

ControllerConfig psr2_base() {
  const auto base = base_controller_config(load_robot_profile(std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/psr2.yaml"),
                                           builtin_plugins().controllers);
  REQUIRE(base.has_value());
  return *base;
}

HardwareConfig dds_config(const ControllerConfig* base, ParameterValues given) {
  HardwareConfig c;
  c.type = "dds";
  c.where = SourceLocation{"robot.yaml", 12, 3};
  c.parameters = ParameterSet::resolve(DdsHardware::static_manifest(), given, c.where);
  c.base = base;
  return c;
}

}  // namespace

TEST_CASE("dds: hardware dds sends the wheels' command as cmd_vel, and no simulator is its fault, not a hang",
          "[dds]") {
  const ControllerConfig base = psr2_base();
  const std::uint32_t domain = test_domain(42);
  HardwareRegistry registry{"hardware type"};
  register_dds_hardware(registry);
  REQUIRE(registry.contains("dds"));
  const HardwareConfig config = dds_config(&base, {{"namespace", Value{test_namespace()}},
                                                   {"domain_id", Value{static_cast<double>(domain)}},
                                                   {"connect_timeout_s", Value{0.3}}});
  auto hw = registry.create_at(config.where, "dds", config);
  auto& dds_hw = dynamic_cast<DdsHardware&>(*hw);
  CHECK(dds_hw.topics().cmd_vel == "rt/" + test_namespace() + "/cmd_vel");
  ResourceTable table;
  hw->add_resources(table);
  CHECK(table.find<LaserScan>("laser") != nullptr);

  ParticipantOptions po;
  po.domain_id = domain;  // the hardware's participant options: one Cyclone domain per process and id
  Participant p(po);
  Subscriber<msg::Twist> cmd_vel(p, dds_hw.topics().cmd_vel, {.kind = TopicKind::command});
  REQUIRE(cmd_vel.wait_for_publishers(1, 5s));

  // The three omni wheels of a twist, and back to the twist on the wire.
  const BaseKinematics kinematics(base);
  REQUIRE(hw->wheels().wheel_count() == 3);
  std::array<double, 3> wheels{};
  kinematics.inverse(Twist2D{0.3, -0.1, 0.5}, wheels);
  REQUIRE(hw->wheels().write_wheel_velocities(wheels));
  const auto got = cmd_vel.take_one(5s);
  REQUIRE(got.has_value());
  CHECK(got->linear.x == Approx(0.3));
  CHECK(got->linear.y == Approx(-0.1).margin(1e-12));
  CHECK(got->angular.z == Approx(0.5));
  std::array<double, 3> velocity{}, position{};
  CHECK_FALSE(hw->wheels().read_wheel_states(velocity, position));  // no wheel states yet

  // No simulator: the first step waits connect_timeout_s, then the link is down, once.
  auto& faults = dynamic_cast<ResourceFaultSource&>(*hw);
  auto t0 = std::chrono::steady_clock::now();
  hw->advance_to(Time{});
  CHECK(std::chrono::steady_clock::now() - t0 < 3s);
  const auto reported = faults.take_faults();
  REQUIRE(reported.size() == 1);
  CHECK_THAT(reported[0], Catch::Contains("no simulator answers on rt/" + test_namespace() +
                                          "/tripodal/sim_step within 300 ms"));
  CHECK_FALSE(dds_hw.link_up());
  t0 = std::chrono::steady_clock::now();
  hw->advance_to(Time{std::chrono::milliseconds(10)});
  CHECK(std::chrono::steady_clock::now() - t0 < 50ms);  // no second wait
  CHECK(faults.take_faults().empty());
  CHECK_FALSE(hw->wheels().write_wheel_velocities(wheels));
  CHECK_FALSE(hw->wheels().read_wheel_states(velocity, position));
}

TEST_CASE("dds: hardware dds refuses a namespace ROS 2 would not take and a robot without a base, located",
          "[dds]") {
  const ControllerConfig base = psr2_base();
  CHECK_THROWS_WITH(
      DdsHardware(
          dds_config(&base, {{"namespace", Value{std::string("9lives")}}, {"domain_id", Value{43.0}}})),
      Catch::Contains("robot.yaml:12:3: error: hardware 'dds' namespace '9lives' is not a ROS 2 namespace"));
  CHECK_THROWS_WITH(
      DdsHardware(dds_config(nullptr, {{"domain_id", Value{43.0}}})),
      Catch::Contains("robot.yaml:12:3: error: hardware 'dds' needs the robot's base controller"));
  CHECK_THROWS_WITH(ParameterSet::resolve(DdsHardware::static_manifest(), {{"step_timeout_s", Value{0.0}}},
                                          SourceLocation{"robot.yaml", 12, 3}),
                    Catch::Contains("step_timeout_s"));
}

// A profile whose modules read the battery (the disinfection robot's BatteryMonitor) passes the
// start-up check on hardware dds as on sim: the type says what it may give, as the simulator's
// does (it once listed the laser only: "missing provider ... needs 'battery'").
TEST_CASE("dds: a profile reading the battery passes the robot's check on hardware dds", "[dds]") {
  RobotProfile profile = load_robot_profile(std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/psr2.yaml");
  REQUIRE(profile.hardware.has_value());
  profile.hardware->type = "dds";
  profile.hardware->parameters = {{"sensors", "battery"}};
  ModuleEntry monitor;
  monitor.name = "battery_monitor";
  monitor.type = "BatteryMonitor";
  monitor.where = SourceLocation{"robot.yaml", 40, 5};
  profile.modules.push_back(monitor);
  RobotPlugins plugins = builtin_plugins();
  register_dds_hardware(plugins.hardware);
  Diagnostics d;
  (void)check_robot(profile, plugins, d);
  INFO(d.str());
  CHECK_FALSE(d.has_errors());
}

// Jinny's profile (its BhNeckGesture reads joint_state, its HRI the buttons) passes the start-up
// check on hardware dds, which carries the world's joints (it once stopped at "missing provider:
// reactive behavior 'BhNeckGesture' needs 'joint_state'").
TEST_CASE("dds: the guide robot's profile with its neck passes the robot's check on hardware dds", "[dds]") {
  RobotProfile profile = load_robot_profile(std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/jinny.yaml");
  REQUIRE(profile.hardware.has_value());
  profile.hardware->type = "dds";
  profile.hardware->parameters.clear();
  RobotPlugins plugins = builtin_plugins();
  register_dds_hardware(plugins.hardware);
  Diagnostics d;
  (void)check_robot(profile, plugins, d);
  INFO(d.str());
  CHECK_FALSE(d.has_errors());
}
