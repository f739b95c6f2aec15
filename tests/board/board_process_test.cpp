// A board that stops answering because its process was killed, and comes back (issue 17's fault
// list): the real tripodal-board-sim behind a pseudo-terminal, the host's BoardLink on the
// symbolic link the simulator keeps to it, in real time as on the robot. Bounded waits only.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "tripodal/board/board_link.hpp"
#include "tripodal/board/rplidar_a1.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/board/tcp_stream.hpp"
#include "tripodal/core/clock.hpp"

extern char** environ;

using namespace tripodal;
using namespace tripodal::board;
using namespace std::chrono_literals;

namespace {

// tripodal-board-sim on the workspace, its pseudo-terminal also reachable at `link`.
// With `tcp_port`, on TCP (the ESP8266 backup link) at 127.0.0.1:tcp_port instead.
pid_t start_board(const std::filesystem::path& link, int tcp_port = -1, const std::filesystem::path& lidar = {}) {
  const std::string exe = TRIPODAL_BOARD_SIM_EXE;
  const std::string world = (std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs" / "worlds" / "workspace.yaml").string();
  std::vector<std::string> args{exe, "--world", world, "--duration-s", "60", "--link-timeout-s", "2"};
  if (tcp_port >= 0) {
    args.insert(args.end(), {"--tcp", std::to_string(tcp_port)});
  } else {
    args.insert(args.end(), {"--link", link.string()});
  }
  if (!lidar.empty()) args.insert(args.end(), {"--lidar", lidar.string()});
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  REQUIRE(::posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ) == 0);
  return pid;
}

void stop_board(pid_t pid) {
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
}

// Runs the host's 100 Hz control cycle until `done` or `max_cycles`; returns the cycles it took
// (max_cycles + 1 when never).
template <class Done>
int cycle_until(BoardLink& link, const SteadyClock& clock, int max_cycles, const Done& done) {
  Time next = clock.now();
  for (int i = 1; i <= max_cycles; ++i) {
    next += 10ms;
    clock.sleep_until(next);
    link.cycle(clock.now(), WheelSpeeds{50, 50});
    if (done()) return i;
  }
  return max_cycles + 1;
}

}  // namespace

TEST_CASE("a board whose process is killed: link lost at once, restarted: the port reopens and resynchronises",
          "[board][process]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tripodal-board-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path device = dir / "board";
  const SteadyClock clock;

  pid_t board = start_board(device);
  // The simulator makes the link before it serves: wait for it (at most 10 s, in 10 ms steps).
  for (int i = 0; i < 1000 && !std::filesystem::exists(device); ++i) clock.sleep_until(clock.now() + 10ms);
  REQUIRE(std::filesystem::exists(device));

  SerialPort port(device, clock);
  // Both processes share two loaded cores without real-time priority: a response may come a few
  // periods late, which is not what this test is about; the timeout of the robot (10 ms) is
  // tested on simulated time (board_link_test.cpp), and so is the board's watchdog (2 s here).
  LinkConfig config;
  config.response_timeout = 200ms;
  BoardLink link(port, config);
  REQUIRE(cycle_until(link, clock, 300, [&] { return link.synchronised() && link.has_drive(); }) <= 300);
  (void)link.take_link_lost();
  const std::uint64_t losses_before = link.stats().link_losses;

  stop_board(board);
  // The master's end is gone: the next read fails, the request is missed and the link lost.
  const int to_loss = cycle_until(link, clock, 100, [&] { return link.take_link_lost(); });
  CHECK(to_loss <= 2);
  CHECK_FALSE(link.synchronised());
  // While it is away, nothing to open: the link keeps trying (every 0.5 s), posting no new loss.
  CHECK(cycle_until(link, clock, 60, [&] { return link.synchronised(); }) == 61);
  CHECK_FALSE(link.take_link_lost());

  board = start_board(device);  // a new pseudo-terminal behind the same link
  const int to_sync = cycle_until(link, clock, 1000, [&] { return link.synchronised() && link.stats().reopens > 0; });
  CHECK(to_sync <= 1000);
  CHECK(link.stats().link_losses == losses_before + 1);
  // Driving again: DRIVE answered period after period (on a loaded machine a late answer may
  // cost another resynchronisation on the way; the link comes back each time).
  const std::uint64_t responses = link.stats().responses;
  const LinkStats& st = link.stats();
  const int to_drive = cycle_until(link, clock, 500, [&] { return link.synchronised() && st.responses >= responses + 20; });
  INFO("missed " << st.missed << ", error responses " << st.error_responses << ", losses " << st.link_losses << ", reopens "
                 << st.reopens << ", resyncs " << st.resyncs << ", requests " << st.requests << ", responses " << st.responses);
  CHECK(to_drive <= 500);
  CHECK(st.reopens >= 1);

  stop_board(board);
  std::filesystem::remove_all(dir);
}

TEST_CASE("the board's process on TCP (the ESP8266 link): connected, killed, restarted: reconnected and resynchronised",
          "[board][process][tcp]") {
  const SteadyClock clock;
  // A free port: one the kernel gives a listener, released for the board's process to take.
  std::uint16_t port = 0;
  {
    TcpServerStream probe(clock);
    port = probe.port();
  }
  const std::string spec = "tcp://127.0.0.1:" + std::to_string(port);
  const auto connect = [&] {
    // The process listens once it has loaded its world: try for at most 10 s, in 10 ms steps.
    for (int i = 0; i < 1000; ++i) {
      try {
        return std::make_unique<TcpStream>(spec, clock);
      } catch (const std::runtime_error&) {
        clock.sleep_until(clock.now() + 10ms);
      }
    }
    FAIL("the board never listened on " << spec);
    return std::unique_ptr<TcpStream>();
  };
  pid_t board = start_board({}, port);
  const std::unique_ptr<TcpStream> stream = connect();
  LinkConfig config;
  config.response_timeout = 200ms;  // two processes on two loaded cores (see above)
  BoardLink link(*stream, config);
  REQUIRE(cycle_until(link, clock, 300, [&] { return link.synchronised() && link.has_drive(); }) <= 300);
  (void)link.take_link_lost();

  stop_board(board);
  CHECK(cycle_until(link, clock, 100, [&] { return link.take_link_lost(); }) <= 2);
  board = start_board({}, port);  // the module back, on the same port
  const int to_sync = cycle_until(link, clock, 1000, [&] { return link.synchronised() && link.stats().reopens > 0; });
  CHECK(to_sync <= 1000);
  const std::uint64_t responses = link.stats().responses;
  CHECK(cycle_until(link, clock, 500, [&] { return link.synchronised() && link.stats().responses >= responses + 20; }) <= 500);
  CHECK(link.stats().port_failures >= 1);
  stop_board(board);
}

TEST_CASE(
    "the lidar beside the board in tripodal-board-sim: scans of the world, its process killed: a fault, restarted: scans again",
    "[board][process][rplidar]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tripodal-lidar-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path board_link = dir / "board";
  const std::filesystem::path lidar_link = dir / "lidar";
  const SteadyClock clock;
  const auto wait_for_link = [&] {
    for (int i = 0; i < 1000 && !std::filesystem::exists(lidar_link); ++i) clock.sleep_until(clock.now() + 10ms);
    REQUIRE(std::filesystem::exists(lidar_link));
  };
  // The control loop: the lidar polled at 100 Hz until `done` (at most `max_cycles`).
  const auto poll_until = [&](RplidarA1& lidar, int max_cycles, const auto& done) {
    Time next = clock.now();
    for (int i = 0; i < max_cycles && !done(); ++i) {
      next += 10ms;
      clock.sleep_until(next);
      lidar.poll(clock.now());
    }
  };

  pid_t sim = start_board(board_link, -1, lidar_link);
  wait_for_link();
  RplidarConfig config;
  config.timeout = 500ms;
  std::unique_ptr<RplidarA1> lidar;
  REQUIRE_NOTHROW(lidar = RplidarA1::open("laser", lidar_link, config, clock));
  CHECK(lidar->device_info().model == 0x18);
  poll_until(*lidar, 300, [&] { return lidar->stats().scans >= 5; });
  CHECK(lidar->stats().scans >= 5);
  CHECK(lidar->stats().decoder_errors == 0);
  std::size_t returns = 0;
  for (const float r : lidar->latest().ranges_m) returns += std::isfinite(r) ? 1 : 0;
  CHECK(returns > 300);  // the workspace's walls all round the start pose
  CHECK(lidar->take_faults().empty());

  // Unplugged: the emulator's process dies, the port hangs up.
  stop_board(sim);
  poll_until(*lidar, 200,
             [&] { return lidar->state() == RplidarA1::State::failed || lidar->state() == RplidarA1::State::stalled; });
  const std::vector<std::string> faults = lidar->take_faults();
  REQUIRE(faults.size() == 1);
  CHECK_THAT(faults[0], Catch::Contains("serial port is gone") || Catch::Contains("no revolution"));

  // Replugged: the device simulator starts again behind the same path; the driver reopens it.
  sim = start_board(board_link, -1, lidar_link);
  wait_for_link();
  const std::uint64_t scans = lidar->stats().scans;
  poll_until(*lidar, 500, [&] { return lidar->stats().scans >= scans + 3; });
  CHECK(lidar->stats().scans >= scans + 3);
  CHECK(lidar->stats().restarts >= 1);
  lidar.reset();
  stop_board(sim);
  std::filesystem::remove_all(dir);
}
