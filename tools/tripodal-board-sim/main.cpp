// tripodal-board-sim: the disinfection robot's control board (seed 001, chapter 3) simulated
// behind a pseudo-terminal. It prints the slave device; a host opens it as it would the real
// board's UART (/dev/ttyUSB0) and speaks the protocol of docs/board-protocol.md byte for byte. The
// board's wheels move the embedded simulator's robot in the given world in real time. It speaks
// the protocol profile given (--protocol; the thesis's by default), over the pseudo-terminal or,
// with --tcp, over TCP on loopback as the board's ESP8266 backup link would. With --speed S its
// time runs S times the wall clock's — the plant, the firmware's tick and watchdog, the lidar's
// rotation and its nodes' byte timing — for a host that runs at the same speed (tripodal run
// --realtime S): a whole task against the device processes in a fraction of its time.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "cli_tool.hpp"
#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/protocol_profile.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/board/tcp_stream.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/sim/rplidar_emulator.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int /*sig*/) { g_stop.store(true); }
// SIGUSR1: the lidar's motor stops (a stuck rotor; a pty carries no DTR to restart it), or turns again.
std::atomic<bool> g_toggle_lidar_motor{false};
void on_toggle_lidar_motor(int /*sig*/) {
  g_toggle_lidar_motor.store(true);
}

// The default world: the installed one (PREFIX/share/tripodal/configs, beside PREFIX/bin where
// this program is), else the source tree's (a build tree's program), else ./configs.
std::filesystem::path default_world() {
  const std::filesystem::path rel = std::filesystem::path("worlds") / "workspace.yaml";
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  std::vector<std::filesystem::path> candidates;
  if (!ec) candidates.push_back(exe.parent_path().parent_path() / TRIPODAL_CONFIGS_INSTALL_DIR / rel);
  candidates.push_back(std::filesystem::path(TRIPODAL_SOURCE_CONFIGS_DIR) / rel);
  candidates.push_back(std::filesystem::path("configs") / rel);
  for (const auto& c : candidates) {
    if (std::filesystem::is_regular_file(c, ec)) return c;
  }
  return {};
}

// --pose-file: the robot's pose as "x_m y_m theta_rad", read at start when the file is there (the
// board restarted under a robot that stays where it stood), written every 100 ms while it runs.
std::optional<tripodal::Pose2D> read_pose(const std::filesystem::path& file) {
  std::ifstream in(file);
  tripodal::Pose2D p;
  if (in >> p.x_m >> p.y_m >> p.theta_rad) return p;
  return std::nullopt;
}
void write_pose(const std::filesystem::path& file, const tripodal::Pose2D& p) {
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out.precision(9);
    out << p.x_m << ' ' << p.y_m << ' ' << p.theta_rad << '\n';
  }
  std::error_code ignored;
  std::filesystem::rename(tmp, file, ignored);  // whole or not at all, for a reader after a kill
}

// A device's transmitter does not wait for its reader: what does not fit in the pseudo-terminal
// now is dropped, as a UART's bytes are lost when the host's buffer is full. PseudoTerminal::write
// waits up to 1 ms for room, which for the lidar's nodes (one write each) starved the board's
// firmware on this same thread behind a host that read late, so that the devices fell behind
// their own clock (the host then saw no revolution for seconds).
class DeviceTransmitter final : public tripodal::board::ByteStream {
 public:
  explicit DeviceTransmitter(tripodal::board::PseudoTerminal& pty) noexcept : pty_(pty) {}
  bool write(std::span<const std::uint8_t> bytes) noexcept override {
    const ssize_t n = ::write(pty_.master_fd(), bytes.data(), bytes.size());  // the master is non-blocking
    return n == static_cast<ssize_t>(bytes.size());
  }
  std::ptrdiff_t read(std::span<std::uint8_t> out, tripodal::Time deadline) noexcept override { return pty_.read(out, deadline); }

 private:
  tripodal::board::PseudoTerminal& pty_;
};

constexpr std::string_view kExitCodes =
    "exit codes: 0 ok, 1 the board could not start (bad world or protocol profile), 2 bad command line, 3 "
    "the world file cannot "
    "be read";

// The tool; main() only keeps what escapes it.
int run(int argc, char** argv) {
  using namespace tripodal;
  CLI::App app{
      "The disinfection robot's control board, simulated behind a pseudo-terminal (or, with --tcp, on a "
      "loopback\n"
      "TCP port): it prints the device a host opens as it would the board's UART. The board's wheels move "
      "the\n"
      "embedded simulator's robot in the world, in real time (docs/board-protocol.md).\n"};
  std::string world_file;
  std::string link;
  double wheel_radius_m = 0.09;
  double wheel_separation_m = 0.42;
  double duration_s = 0.0;
  double link_timeout_s = 0.2;
  double speed = 1.0;
  double tank_l = 1.5;
  std::string protocol = "thesis";
  int tcp_port = -1;
  std::string lidar_link;
  std::string pose_file;
  app.add_option("--world", world_file,
                 "WORLD.yaml: the simulator's map, start pose and sensors (default: the installed "
                 "configs/worlds/workspace.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("--link", link, "PATH: also make this path a symbolic link to the pseudo-terminal");
  app.add_option("--wheel-radius-m", wheel_radius_m, "M: wheel radius")
      ->check(tripodal::cli::positive_number())
      ->capture_default_str();
  app.add_option("--wheel-separation-m", wheel_separation_m, "M: wheel separation")
      ->check(tripodal::cli::positive_number())
      ->capture_default_str();
  app.add_option("--duration-s", duration_s, "S: stop after this many (simulated) seconds (0: at SIGINT or SIGTERM)")
      ->check(tripodal::cli::non_negative_number())
      ->capture_default_str();
  app.add_option("--speed", speed,
                 "S: the board's and the lidar's time runs S times the wall clock's (their byte timing, watchdog and "
                 "plant alike); the host must run at the same speed (tripodal run --realtime S)")
      ->check(CLI::Range(0.1, 50.0))
      ->capture_default_str();
  app.add_option("--link-timeout-s", link_timeout_s, "S: the board's link watchdog")
      ->check(tripodal::cli::positive_number())
      ->capture_default_str();
  app.add_option("--tank-l", tank_l, "L: disinfectant in the tank at power-on")
      ->check(tripodal::cli::non_negative_number())
      ->capture_default_str();
  app.add_option("--protocol", protocol, "NAME|FILE: protocol profile: thesis, tripodal-v1 or a YAML file (configs/board/)")
      ->capture_default_str();
  app.add_option("--tcp", tcp_port,
                 "PORT: serve the link over TCP on 127.0.0.1:PORT (0: any free port) instead of a pseudo-terminal")
      ->check(CLI::Range(0, 65535));
  app.add_option("--lidar", lidar_link,
                 "PATH: also serve an RPLIDAR A1 (docs/lidar.md) on a second pseudo-terminal, this path a symbolic link to it "
                 "(SIGUSR1 stops its motor, and starts it again); "
                 "it scans the same world");
  app.add_option("--pose-file", pose_file,
                 "FILE: start the robot at the pose in FILE (x_m y_m theta_rad) when it is there, and keep the robot's pose "
                 "in it while running: a board restarted under a robot starts where the robot stands");
  if (auto code = tripodal::cli::parse_command_line(app, "tripodal-board-sim", kExitCodes, argc, argv)) return *code;
  if (world_file.empty()) {
    world_file = default_world().string();
    if (world_file.empty()) {
      std::cerr << "tripodal-board-sim: no world given and none installed "
                   "(share/tripodal/configs/worlds/workspace.yaml); "
                   "give --world FILE\n";
      return tripodal::cli::kIoError;
    }
  }

  try {
    // One clock for the plant, the firmware and the lidar: at --speed S everything the devices time
    // (ticks, watchdog, the lidar's samples, the motors) runs S times faster, alike.
    ScaledClock clock(speed);
    sim::World world = sim::load_world(world_file);
    if (!pose_file.empty()) {
      if (const auto p = read_pose(pose_file)) world.start_pose = *p;
    }
    ControllerConfig base;
    base.type = "differential";
    base.differential = {wheel_separation_m, wheel_radius_m};
    sim::Simulator simulator(std::move(world), base, 1, clock.now());
    sim::SimBoardPlant plant(simulator, wheel_radius_m);
    std::unique_ptr<board::PseudoTerminal> pty;
    std::unique_ptr<DeviceTransmitter> pty_out;
    std::unique_ptr<board::TcpServerStream> tcp;
    board::ByteStream* line = nullptr;
    if (tcp_port >= 0) {
      tcp = std::make_unique<board::TcpServerStream>(clock, static_cast<std::uint16_t>(tcp_port));
      line = tcp.get();
    } else {
      pty = std::make_unique<board::PseudoTerminal>(clock);
      pty_out = std::make_unique<DeviceTransmitter>(*pty);
      line = pty_out.get();
    }
    board::FirmwareConfig config;
    config.link_timeout = from_seconds(link_timeout_s);
    config.tank_initial_l = tank_l;
    config.protocol = board::resolve_protocol_profile(protocol, std::filesystem::current_path());
    board::BoardFirmware firmware(config, *line, plant, clock.now());
    if (!link.empty() && pty) {
      std::filesystem::remove(link);
      std::filesystem::create_symlink(pty->slave_path(), link);
    }
    // The lidar: the A1 emulated on its own pseudo-terminal, its ranges cast in the world the
    // board's wheels move the robot in, on the same clock.
    std::unique_ptr<board::PseudoTerminal> lidar_pty;
    std::unique_ptr<DeviceTransmitter> lidar_out;
    std::unique_ptr<sim::SimLidarScene> lidar_scene;
    std::unique_ptr<sim::RplidarEmulator> lidar;
    if (!lidar_link.empty()) {
      lidar_pty = std::make_unique<board::PseudoTerminal>(clock);
      lidar_scene = std::make_unique<sim::SimLidarScene>(simulator);
      lidar_out = std::make_unique<DeviceTransmitter>(*lidar_pty);
      lidar = std::make_unique<sim::RplidarEmulator>(*lidar_out, *lidar_scene, sim::RplidarEmulatorConfig{}, clock.now());
      std::filesystem::remove(lidar_link);
      std::filesystem::create_symlink(lidar_pty->slave_path(), lidar_link);
      std::cout << "tripodal-board-sim: RPLIDAR A1 on " << lidar_pty->slave_path().string() << " (" << lidar_link
                << ", 115200 8N1)" << std::endl;
    }
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    std::signal(SIGUSR1, on_toggle_lidar_motor);
    if (tcp) {
      std::cout << "tripodal-board-sim: board on " << tcp->spec() << " (protocol " << config.protocol->summary() << ")" << std::endl;
    } else {
      std::cout << "tripodal-board-sim: board on " << pty->slave_path().string() << " (115200 8N1, protocol "
                << config.protocol->summary() << ")" << std::endl;
    }

    if (speed != 1.0) std::cout << "tripodal-board-sim: at " << speed << "x the wall clock" << std::endl;
    const Time end = duration_s > 0.0 ? clock.now() + from_seconds(duration_s) : Time::max();
    Time next = clock.now();
    Time next_pose = next;
    // A pass every millisecond of wall time: the firmware and the lidar run what is due by then
    // (several of their 1 ms ticks at a speed-up).
    const Duration pass = from_seconds(0.001 * speed);
    // The longest time between two passes: a pass takes about 1 ms, so a longer one is this
    // process not scheduled (a loaded host), which a host would read as a stalled board.
    Duration longest_pass{};
    Time pass_start = clock.now();
    while (!g_stop.load() && clock.now() < end) {
      const Time t = clock.now();
      longest_pass = std::max(longest_pass, t - pass_start);
      pass_start = t;
      next += pass;
      // Between passes, each request is answered as its bytes arrive (over TCP: at the next pass).
      while (board::serve_until(firmware, pty ? pty->master_fd() : -1, clock, next)) {
      }
      firmware.run_until(clock.now());
      if (lidar && g_toggle_lidar_motor.exchange(false)) {
        lidar->set_motor(!lidar->motor_on(), clock.now());
        std::cout << "tripodal-board-sim: lidar motor " << (lidar->motor_on() ? "on" : "stopped") << " (SIGUSR1)" << std::endl;
      }
      if (lidar) lidar->run_until(clock.now());
      if (!pose_file.empty() && clock.now() >= next_pose) {
        next_pose += std::chrono::milliseconds(100);
        write_pose(pose_file, simulator.pose());
      }
    }
    const auto& c = firmware.counters();
    const auto& d = firmware.decoder_stats();
    std::cout << "tripodal-board-sim: " << c.requests << " requests answered, " << c.error_responses << " error responses, "
              << d.errors() << " decoder errors, " << c.watchdog_trips << " watchdog trips, " << c.resyncs << " synchronisations"
              << std::endl;
    std::array<char, 32> longest_ms{};
    std::snprintf(longest_ms.data(), longest_ms.size(), "%.1f", to_seconds(longest_pass) / speed * 1000.0);
    std::cout << "tripodal-board-sim: longest pass " << longest_ms.data() << " ms of wall clock (1 ms when scheduled on time)"
              << std::endl;
    if (!link.empty() && pty) std::filesystem::remove(link);
    if (lidar) {
      const auto& l = lidar->counters();
      std::cout << "tripodal-board-sim: lidar " << l.requests << " requests, " << l.revolutions << " revolutions, " << l.nodes
                << " nodes sent, " << l.bytes_lost << " bytes lost" << std::endl;
      std::filesystem::remove(lidar_link);
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "tripodal-board-sim: error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (...) {
    std::cerr << "tripodal-board-sim: error: unexpected exception\n";
    return 1;
  }
}
