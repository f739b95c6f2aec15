// The monitor's load (docs/monitor.md, "Load"):
//  - BM_Monitor10Clients20Hz: the server thread and the publishing thread feeding 10 page clients at
//    20 updates per second (pose, markings, status; a laser scan at 5 Hz; a life cycle entry a second),
//    for 2 s of wall time. The clients read in a child process, so the counter cpu_pct_of_one_core
//    is what this process (the robot's side) spends: user + system CPU over wall time.
//  - BM_RobotMonitorUpdate: one RobotMonitor::update() on the PSR-2 demo robot mid-cleaning (the
//    JSON of every topic built on the robot's thread); at 20 Hz it costs 20 times this per second.
#include <arpa/inet.h>
#include <benchmark/benchmark.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "tripodal/builtin/register_all.hpp"
#include "tripodal/monitor/monitor_server.hpp"
#include "tripodal/monitor/robot_monitor.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

namespace {

using namespace tripodal;
using namespace tripodal::monitor;

double cpu_seconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec) * 1e-6;
}

// The child: `clients` WebSocket page clients that read and discard everything until the server goes.
[[noreturn]] void run_clients(std::uint16_t port, const std::string& token, int clients) {
  std::vector<pollfd> fds;
  for (int i = 0; i < clients; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) ::_exit(1);
    const std::string req = "GET /ws?token=" + token +
                            " HTTP/1.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n";
    if (::send(fd, req.data(), req.size(), 0) != static_cast<ssize_t>(req.size())) ::_exit(1);
    fds.push_back({fd, POLLIN, 0});
  }
  char buf[65536];
  for (std::size_t open = fds.size(); open > 0;) {
    if (::poll(fds.data(), fds.size(), 1000) < 0) break;
    for (pollfd& p : fds) {
      if (p.fd >= 0 && (p.revents & (POLLIN | POLLHUP | POLLERR)) != 0 && ::recv(p.fd, buf, sizeof buf, 0) <= 0) {
        ::close(p.fd);
        p.fd = -1;
        --open;
      }
    }
  }
  ::_exit(0);
}

// Messages of the sizes the demo robot publishes (its RPLIDAR A1's 1450-beam scan in millimetres at
// 5.5 Hz, published as it comes: every fourth update here; a status line).
std::string scan_json() {
  std::string ranges;
  for (int i = 0; i < 1450; ++i) ranges += (i ? "," : "") + std::to_string(1.0 + 0.001 * i).substr(0, 5);
  return R"({"timestamp":{"sec":12,"nsec":0},"frame_id":"map","pose":{"position":{"x":1,"y":2,"z":0},"orientation":{"x":0,"y":0,"z":0,"w":1}},"start_angle":-3.14,"end_angle":3.14,"ranges":[)" +
         ranges + R"(],"intensities":[]})";
}

void BM_Monitor10Clients20Hz(benchmark::State& state) {
  const int clients = static_cast<int>(state.range(0));
  MonitorServer server(MonitorServerOptions{.token = "bench-token-123"});
  const auto pose = server.advertise("/pose", "foxglove.PoseInFrame", "{}", Delivery::bulk);
  const auto laser = server.advertise("/laser", "foxglove.LaserScan", "{}", Delivery::bulk);
  const auto markings = server.advertise("/markings", "tripodal.Markings", "{}", Delivery::bulk);
  const auto status = server.advertise("/status", "tripodal.Status", "{}", Delivery::bulk);
  const auto life = server.advertise("/lifecycle", "tripodal.LifecycleEntry", "{}", Delivery::event);
  const pid_t child = ::fork();
  if (child == 0) run_clients(server.port(), server.token(), clients);
  server.start();
  while (server.stats().clients < static_cast<std::size_t>(clients)) std::this_thread::sleep_for(std::chrono::milliseconds(5));

  const std::string pose_json =
      R"({"timestamp":{"sec":12,"nsec":500000000},"frame_id":"map","pose":{"position":{"x":3.25,"y":7.5,"z":0},"orientation":{"x":0,"y":0,"z":0.38,"w":0.92}}})";
  const std::string scan = scan_json();
  const std::string marks = R"({"timestamp":{"sec":12,"nsec":0},"nets":[{"run":"task","net":"plan","marked":[{"place":"X1","tokens":1}],"last_firing":"X1.t0"},{"run":"X1","net":"PrCleaning","marked":[{"place":"P1","tokens":1},{"place":"P4","tokens":1}],"last_firing":"T1"}]})";
  const std::string stat(1500, ' ');
  const std::string status_json = R"({"time_s":12.5,"pad":")" + stat + R"("})";
  const std::string entry = R"({"time_s":12.5,"kind":"process","text":"process X1 PrCleaning(section=A) started"})";
  const auto period = std::chrono::milliseconds(50);
  double cpu_pct = 0.0;
  for (auto _ : state) {
    const auto wall0 = std::chrono::steady_clock::now();
    const double cpu0 = cpu_seconds();
    auto next = wall0;
    for (int i = 0; i < 40; ++i) {  // 2 s at 20 Hz
      const double t = i * 0.05;
      server.publish(pose, t, pose_json);
      if (i % 4 == 0) server.publish(laser, t, scan);
      server.publish(markings, t, marks);
      server.publish(status, t, status_json);
      if (i % 20 == 0) server.publish(life, t, entry);
      next += period;
      std::this_thread::sleep_until(next);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    cpu_pct = 100.0 * (cpu_seconds() - cpu0) / wall;
    state.SetIterationTime(wall);
  }
  const MonitorStats s = server.stats();
  state.counters["cpu_pct_of_one_core"] = cpu_pct;
  state.counters["clients"] = static_cast<double>(s.clients);
  state.counters["bulk_shed"] = static_cast<double>(s.bulk_shed);
  state.counters["MB_sent"] = static_cast<double>(s.bytes_sent) / 1e6;
  server.stop();
  ::kill(child, SIGTERM);
  ::waitpid(child, nullptr, 0);
}
BENCHMARK(BM_Monitor10Clients20Hz)->Arg(10)->UseManualTime()->Iterations(1)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond);

void BM_RobotMonitorUpdate(benchmark::State& state) {
  const std::filesystem::path configs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
  RobotPlugins plugins;
  register_all(plugins, std::make_shared<sim::World>(sim::load_world(configs / "worlds/workspace.yaml")));
  SimClock clock;
  const auto robot = Robot::assemble(load_robot_profile(configs / "robots/psr2.yaml"), plugins, clock);
  MonitorServer server(MonitorServerOptions{.token = "bench-token-123"});
  RobotMonitor watch(*robot, clock, server, RobotMonitorOptions{.min_interval_s = 0.0, .cleaned_interval_s = 1e9});
  server.start();
  if (!robot->command("clean the room 3211").accepted) state.SkipWithError("task refused");
  robot->run_for(std::chrono::seconds(30));  // into section A's cleaning
  watch.update();
  double total_s = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    watch.update();
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    total_s += dt;
    state.SetIterationTime(dt);
    robot->run_for(std::chrono::milliseconds(50));
    (void)server.take_requests();
  }
  // 20 updates a second of the mean update, as a share of one core.
  state.counters["cpu_pct_at_20Hz"] = 100.0 * 20.0 * total_s / static_cast<double>(state.iterations());
}
BENCHMARK(BM_RobotMonitorUpdate)->UseManualTime()->Iterations(2000)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
