// The whole disinfection robot on its own threads (Robot::start) against its devices in another
// process: a forked child runs the control board's firmware and the RPLIDAR A1 emulator on two
// pseudo-terminals, in one simulated world on the wall clock, as tripodal-board-sim does; the
// robot opens the ptys through its hardware "board" (port, lidar_port) as it would /dev/ttyUSB0.
// Tagged [threads]: scripts/tsan.sh runs it under ThreadSanitizer (the ThreadSanitizer tree builds
// no tools, hence the fork rather than the tool). The child is killed mid-run ("unplugged"): the
// sequencing layer sees the loss through the resource snapshot; or it stops the lidar's motor: the
// laser's fault reaches the supervisor within the driver's timeout. Bounded waits only.
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <csignal>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/board_hardware.hpp"
#include "tripodal/board/rplidar_a1.hpp"
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
// ThreadSanitizer: the lidar's driver waits only 0.5 s for GET_INFO). SIGUSR1 stops the lidar's
// motor for good (a stuck rotor: a pty carries no DTR for the host to restart it).
volatile std::sig_atomic_t g_stop_lidar = 0;
void on_stop_lidar(int /*sig*/) {
  g_stop_lidar = 1;
}

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
    std::signal(SIGUSR1, on_stop_lidar);
    const char byte = 1;
    (void)::write(ready, &byte, 1);
    const Time end = clock.now() + max;
    Time next = clock.now();
    while (clock.now() < end && ::getppid() != 1) {
      next += 1ms;
      clock.sleep_until(next);
      firmware.run_until(clock.now());
      if (g_stop_lidar != 0 && lidar.motor_on()) lidar.set_motor(false, clock.now());
      lidar.run_until(clock.now());
    }
  } catch (...) {
    code = 1;
  }
  ::_exit(code);
}

// The device process forked with its two ptys; only the child holds them once it is up, so that
// killed, the host's ports hang up as a pulled cable's would. Killed at the end in any case.
struct DeviceProcess {
  pid_t pid = -1;
  std::string board_port, lidar_port;
  bool up = false;

  DeviceProcess() {
    const SteadyClock wall;
    auto board_pty = std::make_unique<board::PseudoTerminal>(wall);
    auto lidar_pty = std::make_unique<board::PseudoTerminal>(wall);
    board_port = board_pty->slave_path().string();
    lidar_port = lidar_pty->slave_path().string();
    std::array<int, 2> ready{-1, -1};
    if (::pipe(ready.data()) != 0) return;
    pid = ::fork();
    if (pid == 0) run_devices(*board_pty, *lidar_pty, ready[1], 60s);
    ::close(ready[1]);
    pollfd p{ready[0], POLLIN, 0};
    up = pid > 0 && ::poll(&p, 1, 60000) == 1;  // bounded: a child that dies closes the pipe
    ::close(ready[0]);
  }
  DeviceProcess(const DeviceProcess&) = delete;
  DeviceProcess& operator=(const DeviceProcess&) = delete;
  ~DeviceProcess() { kill(); }

  void kill() noexcept {
    if (pid <= 0) return;
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
    pid = -1;
  }
};

// The robot: the real board hardware on the child's ptys, the world's map loaded as a file. The
// plugins outlive the robot that creates its behaviors from them.
struct DevicesRobot {
  RobotPlugins plugins;
  std::unique_ptr<Robot> robot;

  DevicesRobot(const DeviceProcess& devices, Clock& clock, const std::string& lidar_timeout_s = "1") {
    RobotProfile profile = load_robot_profile(kConfigs / "robots" / "disinfection_lidar.yaml");
    profile.hardware->parameters.insert_or_assign("port", devices.board_port);
    profile.hardware->parameters.insert_or_assign("lidar_port", devices.lidar_port);
    profile.hardware->parameters.insert_or_assign("lidar_timeout_s", lidar_timeout_s);
    // A shared machine (and ThreadSanitizer) delays answers by tens of milliseconds: late ones are
    // tolerated; the killed device is still found at once, by its port hanging up.
    profile.hardware->parameters.insert_or_assign("response_timeout_s", "0.05");
    profile.hardware->parameters.insert_or_assign("max_missed", "3");
    register_all(plugins);
    plugins.hardware = HardwareRegistry{"hardware type"};
    board::register_board_hardware(plugins.hardware);
    RobotOptions ro;
    ro.parameters.push_back({"maps", "map", (kConfigs / "worlds" / "workspace_map.yaml").string()});
    ro.parameters.push_back({"maps", "regions", (kConfigs / "worlds" / "workspace_regions.yaml").string()});
    robot = Robot::assemble(profile, plugins, clock, ro);
    if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(Pose2D{0.8, 0.8, 0.0});
  }
  DevicesRobot(const DevicesRobot&) = delete;
  DevicesRobot& operator=(const DevicesRobot&) = delete;
  ~DevicesRobot() = default;
};

bool wait_for(const std::atomic<bool>& flag, Duration limit) {
  const SteadyClock wall;
  const Time end = wall.now() + limit;
  while (!flag.load() && wall.now() < end) wall.sleep_until(wall.now() + 10ms);
  return flag.load();
}

}  // namespace

TEST_CASE("the disinfection robot on its threads against its board and lidar in another process, unplugged mid-run",
          "[board][devices][threads]") {
  const SteadyClock wall;
  DeviceProcess devices;
  REQUIRE(devices.up);
  ScaledClock clock(1.0);
  DevicesRobot assembled(devices, clock);
  Robot* const robot = assembled.robot.get();
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
  const bool got_sync = wait_for(synced, 5s);
  const bool got_moving = wait_for(moving, 10s);
  wall.sleep_until(wall.now() + 2s);  // driving, scanning
  const std::uint64_t scans_before = scans.load();
  devices.kill();                             // unplugged
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

namespace {

// The supervisor's faults as the sequencing thread reports them, read by the test's thread.
struct LaserFaults : SupervisorObserver {
  std::atomic<bool> seen{false};
  std::mutex mutex;
  std::string reason;
  void on_fault(std::string_view source, std::string_view why, Time /*now*/) override {
    if (source != "laser" || seen.load()) return;
    {
      const std::lock_guard lock(mutex);
      reason = why;
    }
    seen.store(true);
  }
};

}  // namespace

TEST_CASE(
    "the disinfection robot on its threads: a lidar that stops spinning is the laser's fault within its timeout, not a hang",
    "[board][devices][threads]") {
  const SteadyClock wall;
  DeviceProcess devices;
  REQUIRE(devices.up);
  ScaledClock clock(1.0);
  DevicesRobot assembled(devices, clock, "0.5");
  Robot* const robot = assembled.robot.get();
  LaserFaults faults;
  robot->supervisor().add_observer(faults);

  std::atomic<std::uint64_t> scans{0};
  std::atomic<bool> scanning{false};
  RealtimeOptions rto;
  rto.after_sequencing = [&](Time) {
    if (const auto* laser = robot->sequencing_resources().find<LaserScan>("laser")) scans.store(laser->sequence());
    if (scans.load() >= 3) scanning.store(true);
  };
  robot->start(std::move(rto));
  const bool got_scans = wait_for(scanning, 10s);
  const bool quiet_before = !faults.seen.load();
  ::kill(devices.pid, SIGUSR1);  // the device process stops the lidar's motor for good
  const Time stopped = wall.now();
  // The driver's timeout is 0.5 s; a sequencing period late under ThreadSanitizer on a loaded
  // machine is allowed for, a hang is not (the wait is bounded).
  const bool got_fault = wait_for(faults.seen, 10s);
  const Duration to_fault = wall.now() - stopped;
  const std::uint64_t scans_at_fault = scans.load();
  wall.sleep_until(wall.now() + 1s);  // stopped still: no more scans
  const std::uint64_t scans_later = scans.load();
  robot->stop();
  robot->supervisor().remove_observer(faults);
  CHECK(got_scans);
  CHECK(quiet_before);
  REQUIRE(got_fault);
  CHECK(to_fault >= 400ms);  // not before the timeout (minus a revolution already under way)
  CHECK(to_fault < 5s);
  WARN("lidar stopped -> laser fault seen by the supervisor: " << to_seconds(to_fault) << " s");
  {
    const std::lock_guard lock(faults.mutex);
    CHECK_THAT(faults.reason, Catch::Contains("no revolution"));
  }
  CHECK(scans_later == scans_at_fault);
  board::BoardHardware& hw = dynamic_cast<board::BoardHost&>(*robot->hardware()).board();
  REQUIRE(hw.lidar() != nullptr);
  CHECK(hw.lidar()->stats().faults == 1);  // one fault per loss, while the driver restarts its session
  CHECK(hw.lidar()->stats().restarts >= 1);
  CHECK(hw.link().stats().port_failures == 0);  // the board is still there: only the laser failed
}
