// The whole disinfection robot on its own threads (Robot::start) against its devices in another
// process: a forked child runs the control board's firmware and the RPLIDAR A1 emulator on two
// pseudo-terminals, in one simulated world on the wall clock, as tripodal-board-sim does; the
// robot opens the ptys through its hardware "board" (port, lidar_port) as it would /dev/ttyUSB0.
// Tagged [threads]: scripts/tsan.sh runs it under ThreadSanitizer (the ThreadSanitizer tree builds
// no tools, hence the fork rather than the tool). The child is killed mid-run ("unplugged"): the
// sequencing layer sees the loss through the resource snapshot. Bounded waits only.
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <filesystem>
#include <memory>
#include <string>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/board_hardware.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/rplidar_emulator.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";

// The device process: the board and the lidar on `board_pty` and `lidar_pty` (opened before the
// fork), the robot's motion simulated behind the board, until killed or `max` has passed.
// It writes a byte to `ready` once both devices answer (loading the world takes a while under
// ThreadSanitizer: the lidar's driver waits only 0.5 s for GET_INFO).
[[noreturn]] void run_devices(board::PseudoTerminal& board_pty, board::PseudoTerminal& lidar_pty, int ready, Duration max) {
  int code = 0;
  try {
    SteadyClock clock;
    ControllerConfig base;
    base.type = "differential";
    base.differential = {0.42, 0.09};
    sim::Simulator simulator(sim::load_world(kConfigs / "worlds" / "workspace.yaml"), base, 1, clock.now());
    sim::SimBoardPlant plant(simulator, 0.09);
    board::FirmwareConfig config;
    board::BoardFirmware firmware(config, board_pty, plant, clock.now());
    sim::SimLidarScene scene(simulator);
    sim::RplidarEmulator lidar(lidar_pty, scene, sim::RplidarEmulatorConfig{}, clock.now());
    const char byte = 1;
    (void)::write(ready, &byte, 1);
    const Time end = clock.now() + max;
    Time next = clock.now();
    while (clock.now() < end && ::getppid() != 1) {
      next += 1ms;
      clock.sleep_until(next);
      firmware.run_until(clock.now());
      lidar.run_until(clock.now());
    }
  } catch (...) {
    code = 1;
  }
  ::_exit(code);
}

}  // namespace

TEST_CASE("the disinfection robot on its threads against its board and lidar in another process, unplugged mid-run",
          "[board][devices][threads]") {
  const SteadyClock wall;
  auto board_pty = std::make_unique<board::PseudoTerminal>(wall);
  auto lidar_pty = std::make_unique<board::PseudoTerminal>(wall);
  const std::string board_port = board_pty->slave_path().string();
  const std::string lidar_port = lidar_pty->slave_path().string();
  std::array<int, 2> ready{-1, -1};
  REQUIRE(::pipe(ready.data()) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) run_devices(*board_pty, *lidar_pty, ready[1], 60s);
  ::close(ready[1]);
  pollfd p{ready[0], POLLIN, 0};
  const bool devices_up = ::poll(&p, 1, 60000) == 1;  // bounded: a child that dies closes the pipe
  ::close(ready[0]);
  // Only the child holds the ptys now: killed, the host's ports hang up as a pulled cable's would.
  board_pty.reset();
  lidar_pty.reset();
  struct Reaper {
    pid_t pid;
    ~Reaper() {
      if (pid <= 0) return;
      ::kill(pid, SIGKILL);
      int status = 0;
      ::waitpid(pid, &status, 0);
    }
  } reaper{child};

  REQUIRE(devices_up);

  // The robot: the real board hardware on the child's ptys, the world's map loaded as a file.
  RobotProfile profile = load_robot_profile(kConfigs / "robots" / "disinfection_lidar.yaml");
  profile.hardware->parameters.insert_or_assign("port", board_port);
  profile.hardware->parameters.insert_or_assign("lidar_port", lidar_port);
  // A shared machine (and ThreadSanitizer) delays answers by tens of milliseconds: late ones are
  // tolerated; the killed device is still found at once, by its port hanging up.
  profile.hardware->parameters.insert_or_assign("response_timeout_s", "0.05");
  profile.hardware->parameters.insert_or_assign("max_missed", "3");
  RobotPlugins plugins;
  register_all(plugins);
  plugins.hardware = HardwareRegistry{"hardware type"};
  board::register_board_hardware(plugins.hardware);
  RobotOptions ro;
  ro.parameters.push_back({"maps", "map", (kConfigs / "worlds" / "workspace_map.yaml").string()});
  ro.parameters.push_back({"maps", "regions", (kConfigs / "worlds" / "workspace_regions.yaml").string()});
  ScaledClock clock(1.0);
  const auto robot = Robot::assemble(profile, plugins, clock, ro);
  if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(Pose2D{0.8, 0.8, 0.0});
  REQUIRE(robot->command("go to door_2111").accepted);

  // What the sequencing thread sees, through the snapshot, handed to this thread.
  std::atomic<bool> synced{false}, lost{false}, moving{false};
  std::atomic<std::uint64_t> scans{0};
  RealtimeOptions rto;
  rto.after_sequencing = [&](Time) {
    const ResourceTable& t = robot->sequencing_resources();
    if (const auto* link = t.find<board::BoardLinkReading>("board_link"); link != nullptr && link->has_reading()) {
      if (link->latest().synchronised) synced.store(true);
      if (link->latest().stats.link_losses > 0) lost.store(true);
    }
    if (const auto* laser = t.find<LaserScan>("laser")) scans.store(laser->sequence());
    if (robot->behavior_active("BhAutoMove")) moving.store(true);
  };
  robot->start(std::move(rto));
  const auto wait_for = [&](const std::atomic<bool>& flag, Duration limit) {
    const Time end = wall.now() + limit;
    while (!flag.load() && wall.now() < end) wall.sleep_until(wall.now() + 10ms);
    return flag.load();
  };
  const bool got_sync = wait_for(synced, 5s);
  const bool got_moving = wait_for(moving, 10s);
  wall.sleep_until(wall.now() + 2s);  // driving, scanning
  const std::uint64_t scans_before = scans.load();
  ::kill(child, SIGKILL);  // unplugged
  ::waitpid(child, nullptr, 0);
  reaper.pid = -1;
  const bool got_lost = wait_for(lost, 15s);  // a sequencing period is slow under ThreadSanitizer
  wall.sleep_until(wall.now() + 200ms);
  robot->stop();
  CHECK(got_sync);
  CHECK(got_moving);
  CHECK(got_lost);
  CHECK(scans_before >= 3);  // the A1 turns at 5.5 Hz
  board::BoardHardware& hw = dynamic_cast<board::BoardHost&>(*robot->hardware()).board();
  CHECK(hw.link().stats().requests > 50);       // 100 Hz, fewer under ThreadSanitizer on a loaded machine
  CHECK(hw.link().stats().port_failures >= 1);  // the kill: the pty hung up
  CHECK(hw.link().decoder_stats().errors() == 0);
  const std::array<double, 2> zeros{0.0, 0.0};
  CHECK_FALSE(hw.write_wheel_velocities(zeros));  // the link is lost: refused, the board's watchdog has stopped the motors
}
