// `tripodal sim-server --robots N`: one simulated world stepped for several lock-step robots over
// DDS (docs/distribution.md, "One world, many robots"), the server side of a fleet that sees
// itself. The one-robot server is sim_server_command.cpp; this file holds the shared world.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>

namespace tripodal::dds::msg {
struct SimState;
}
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

/// Serves until every robot that came has left, a signal, or (with wait_s) no robot came; prints
/// per-robot and total figures ("robot-robot contacts: N"). Returns the tool's exit code.
int run_shared_world(const SharedWorldArgs& a, std::ostream& out, std::ostream& err);

}  // namespace tripodal::tool
