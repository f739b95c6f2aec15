// `tripodal sim-server --robots N`: one simulated world stepped for several lock-step robots over
// DDS (docs/distribution.md, "One world, many robots"), the server side of a fleet that sees
// itself. The one-robot server is sim_server_command.cpp; this file holds the shared world.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/dds/messages.hpp"
#include "tripodal/resources/readings.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::sim {
class Simulator;
}

namespace tripodal::tool {

struct SharedWorldArgs {
  std::filesystem::path robot, world;
  std::filesystem::path fleet;   ///< a fleet file (fleet_file.hpp): its robots instead of `robots` x `robot`
  int robots = 2;                ///< slots robot1..robotN (namespaces `prefix`1..N)
  std::string prefix = "robot";  ///< namespace of robot k: prefix + k
  unsigned domain = 0;
  std::optional<std::uint64_t> seed;
  double lease_s = 2.0;
  double wait_s = 0.0;
  double stall_s = 0.2;  ///< wall time a round waits for a robot before stepping without it
  bool system_network = false;
};

/// The robot's other sensors after a step, into the state the server answers with: the gyro,
/// bumpers, cliff sensors and battery its world gives it (SimState::sensors says which), so that
/// a robot on hardware dds has them as on the in-process simulator. Both servers use it.
void put_sensors(dds::msg::SimState& state, sim::Simulator& sim);

/// The step's joint targets into the simulator, in its world's joint order (a NaN, or a list of
/// another length: that joint's, or every, target unchanged): a robot's neck on hardware dds.
void apply_joint_targets(const dds::msg::SimStep& step, sim::Simulator& sim);

/// A robot's LED buttons pressed over DDS: a button's name as std_msgs/String on
/// rt/<ns>/tripodal/press_button (a visitor's finger from another process: a test, a kiosk),
/// pressed on its simulator before its next step and so reported in that step's SimState. A name
/// its world has no button of is dropped (the simulator refuses it).
class ButtonInbox {
 public:
  ButtonInbox(dds::Participant& participant, const std::string& ns);
  ~ButtonInbox();
  ButtonInbox(const ButtonInbox&) = delete;
  ButtonInbox& operator=(const ButtonInbox&) = delete;
  /// Presses on `sim` what came since the last call, oldest first.
  void press_on(sim::Simulator& sim);

 private:
  std::mutex mutex_;
  std::vector<std::string> names_;  // under mutex_: written on a Cyclone DDS thread
  std::unique_ptr<dds::Subscriber<dds::msg::String>> subscriber_;
};

/// Serves until every robot that came has left, a signal, or (with wait_s) no robot came; prints
/// per-robot and total figures ("robot-robot contacts: N"). Returns the tool's exit code.
int run_shared_world(const SharedWorldArgs& a, std::ostream& out, std::ostream& err);

/// The sim-servers' DDS participant: the domain, loopback or the system's network, the lease.
dds::ParticipantOptions served_participant(unsigned domain, bool system_network, double lease_s);

/// A laser reading as the sensor_msgs/LaserScan both sim-servers publish (the header's frame kept).
void put_scan(const LaserScan& scan, dds::msg::LaserScan& message);

/// The base the profile's loop controls, as the sim-servers simulate it (the controller types
/// `tripodal run` knows); a located ConfigError when no loop has a controller.
ControllerConfig simulated_base(const RobotProfile& profile);

}  // namespace tripodal::tool
