// The closed-loop test of BhApproach (docs/behavior-tutorial.md, section 8): the tutorial's robot
// (approach_robot.yaml: its process net, the behavior, the coordinator and a differential base)
// on the simulator, started from a recorded pose and given its task in words. Unlike the replay of
// bh_approach_test.cpp, the simulated world moves as the robot commands.
#define CATCH_CONFIG_MAIN
#include <catch2/catch.hpp>

#include "tripodal/builtin/register_all.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/testing/robot_harness.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

// A trace of one odometry reading: the pose a closed-loop run starts from.
std::filesystem::path start_at(const Pose2D& pose) {
  const auto out = std::filesystem::temp_directory_path() / "bh_approach_start.trp";
  trace::TraceWriter writer(out);
  writer.write(writer.add_channel("odom", trace::ChannelKind::kOdometry), OdometryReading{.stamp = Time{}, .pose = pose});
  writer.close();
  return out;
}

}  // namespace

TEST_CASE("On the simulator, the tutorial's robot stops short of the wall ahead") {
  RobotPlugins plugins = builtin_plugins();  // BhApproach comes from the profile's plugin
  testing::RobotHarnessOptions o;
  o.world = std::make_shared<const sim::World>(sim::load_world(TRIPODAL_CONFIGS "/worlds/workspace.yaml"));
  testing::RobotHarness h(testing::RobotHarness::Mode::closed_loop, load_robot_profile(APPROACH_PROFILE), std::move(plugins),
                          start_at({0.8, 0.8, 0.0}), o);
  REQUIRE(h.command("approach").accepted);
  const testing::RunLog& log = h.run(h.start_time() + 60s);

  CHECK(log.event_before("task.succeeded", h.start_time() + 30s));
  CHECK(log.never_fails("BhApproach"));
  CHECK(log.never_drives_toward_obstacle_closer_than(0.8));
  const sim::Simulator& sim = dynamic_cast<sim::SimHardware&>(*h.robot().hardware()).simulator();
  CHECK(sim.collisions() == 0);
  CHECK(sim.pose().x_m > 8.5);  // it crossed the room: the wall ahead is at x = 10 m
}
