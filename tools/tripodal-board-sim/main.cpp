// tripodal-board-sim: the disinfection robot's control board (seed 001, chapter 3) simulated
// behind a pseudo-terminal. It prints the slave device; a host opens it as it would the real
// board's UART (/dev/ttyUSB0) and speaks the protocol of docs/board-protocol.md byte for byte. The
// board's wheels move the embedded simulator's robot in the given world in real time. It speaks
// the protocol profile given (--protocol; the thesis's by default), over the pseudo-terminal or,
// with --tcp, over TCP on loopback as the board's ESP8266 backup link would.
#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/protocol_profile.hpp"
#include "tripodal/board/tcp_stream.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/sim/rplidar_emulator.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int /*sig*/) { g_stop.store(true); }

// The tool; main() only keeps what escapes it (CLI11's own errors are answered inside).
int run(int argc, char** argv) {
  using namespace tripodal;
  CLI::App app{"tripodal-board-sim: the disinfection robot's control board, simulated behind a pseudo-terminal"};
  std::string world_file = "configs/worlds/workspace.yaml";
  std::string link;
  double wheel_radius_m = 0.09;
  double wheel_separation_m = 0.42;
  double duration_s = 0.0;
  double link_timeout_s = 0.2;
  double tank_l = 1.5;
  std::string protocol = "thesis";
  int tcp_port = -1;
  std::string lidar_link;
  app.add_option("--world", world_file, "world file (the simulator's map, start pose, sensors)")->check(CLI::ExistingFile);
  app.add_option("--link", link, "also make this path a symbolic link to the pseudo-terminal");
  app.add_option("--wheel-radius-m", wheel_radius_m, "wheel radius (m)")->check(CLI::PositiveNumber);
  app.add_option("--wheel-separation-m", wheel_separation_m, "wheel separation (m)")->check(CLI::PositiveNumber);
  app.add_option("--duration-s", duration_s, "stop after this many seconds (0: at SIGINT or SIGTERM)")->check(CLI::NonNegativeNumber);
  app.add_option("--link-timeout-s", link_timeout_s, "the board's link watchdog (s)")->check(CLI::PositiveNumber);
  app.add_option("--tank-l", tank_l, "disinfectant in the tank at power-on (l)")->check(CLI::NonNegativeNumber);
  app.add_option("--protocol", protocol, "protocol profile: thesis, tripodal-v1 or a YAML file (configs/board/)");
  app.add_option("--tcp", tcp_port, "serve the link over TCP on 127.0.0.1:PORT (0: any free port) instead of a pseudo-terminal")
      ->check(CLI::Range(0, 65535));
  app.add_option("--lidar", lidar_link,
                 "also serve an RPLIDAR A1 (docs/lidar.md) on a second pseudo-terminal, this path a symbolic link to it; "
                 "it scans the same world");
  CLI11_PARSE(app, argc, argv);

  try {
    SteadyClock clock;
    sim::World world = sim::load_world(world_file);
    ControllerConfig base;
    base.type = "differential";
    base.differential = {wheel_separation_m, wheel_radius_m};
    sim::Simulator simulator(std::move(world), base, 1, clock.now());
    sim::SimBoardPlant plant(simulator, wheel_radius_m);
    std::unique_ptr<board::PseudoTerminal> pty;
    std::unique_ptr<board::TcpServerStream> tcp;
    board::ByteStream* line = nullptr;
    if (tcp_port >= 0) {
      tcp = std::make_unique<board::TcpServerStream>(clock, static_cast<std::uint16_t>(tcp_port));
      line = tcp.get();
    } else {
      pty = std::make_unique<board::PseudoTerminal>(clock);
      line = pty.get();
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
    std::unique_ptr<sim::SimLidarScene> lidar_scene;
    std::unique_ptr<sim::RplidarEmulator> lidar;
    if (!lidar_link.empty()) {
      lidar_pty = std::make_unique<board::PseudoTerminal>(clock);
      lidar_scene = std::make_unique<sim::SimLidarScene>(simulator);
      lidar = std::make_unique<sim::RplidarEmulator>(*lidar_pty, *lidar_scene, sim::RplidarEmulatorConfig{}, clock.now());
      std::filesystem::remove(lidar_link);
      std::filesystem::create_symlink(lidar_pty->slave_path(), lidar_link);
      std::cout << "tripodal-board-sim: RPLIDAR A1 on " << lidar_pty->slave_path().string() << " (" << lidar_link
                << ", 115200 8N1)" << std::endl;
    }
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    if (tcp) {
      std::cout << "tripodal-board-sim: board on " << tcp->spec() << " (protocol " << config.protocol->summary() << ")" << std::endl;
    } else {
      std::cout << "tripodal-board-sim: board on " << pty->slave_path().string() << " (115200 8N1, protocol "
                << config.protocol->summary() << ")" << std::endl;
    }

    const Time end = duration_s > 0.0 ? clock.now() + from_seconds(duration_s) : Time::max();
    Time next = clock.now();
    while (!g_stop.load() && clock.now() < end) {
      next += std::chrono::milliseconds(1);
      clock.sleep_until(next);
      firmware.run_until(clock.now());
      if (lidar) lidar->run_until(clock.now());
    }
    const auto& c = firmware.counters();
    const auto& d = firmware.decoder_stats();
    std::cout << "tripodal-board-sim: " << c.requests << " requests answered, " << c.error_responses << " error responses, "
              << d.errors() << " decoder errors, " << c.watchdog_trips << " watchdog trips, " << c.resyncs << " synchronisations"
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
