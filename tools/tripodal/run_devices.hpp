// `tripodal run` against devices: the robot's hardware "board" on the port it is given (a tty such
// as /dev/ttyUSB0, or the pseudo-terminal tripodal-board-sim made), its RPLIDAR A1 on another, the
// robot on its own threads at wall-clock time, nothing simulated in this process (the world file
// gives only the map, as a real robot loads its map). Internal to the tool (tools/tripodal): the
// run of run_task.cpp when `port` is set, with the device figures (link and lidar) it adds.
#pragma once

#include <cstdint>
#include <string>

#include "run_task.hpp"
#include "tripodal/board/board_link.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::app {

/// What the devices did over a run: the board's link as the host saw it, the lidar's scans.
struct DeviceFigures {
  std::string port, lidar_port;
  board::LinkStats link;
  std::uint64_t decoder_errors = 0;  ///< the host's frame decoder
  std::uint64_t lidar_scans = 0, lidar_dropped = 0, lidar_decoder_errors = 0, lidar_restarts = 0, lidar_faults = 0;
  double first_sync_s = 0.0;  ///< from the robot's start to the board's first SYNC answered
  /// Each loss of the link and its return (wall-clock seconds of the run): the fault posted, the
  /// link synchronised again, the task's process running again.
  struct Outage {
    double lost_s = 0.0, restored_s = -1.0, resumed_s = -1.0;
  };
  std::vector<Outage> outages;
  [[nodiscard]] std::string json() const;
};

/// Whether `profile`'s hardware is the control board with its port given (hardware type "board",
/// parameter `port` not empty): then the devices are real and run_on_devices() runs the task.
[[nodiscard]] bool runs_on_devices(const RobotProfile& profile);

/// Runs `o`'s task on the devices of `profile` (runs_on_devices). Needs --realtime at 1x (the
/// devices keep the wall clock); refuses what needs a simulator in this process (--board, --faults,
/// --record, --monitor) with a ConfigError naming the option. A port that does not open (absent,
/// not a tty, busy) is a ConfigError naming the port and the reason; a board that does not answer
/// SYNC within 5 s ends the run "failed" with what the link saw. Writes report.json, devices.json,
/// map.png, trajectory.csv and lifecycle.txt into o.out.
[[nodiscard]] RunResult run_on_devices(const RunOptions& o, const RobotProfile& profile);

}  // namespace tripodal::app
