// `tripodal sim-server` and a robot on hardware "dds" (`tripodal run --hardware dds`): two processes
// on loopback DDS in lock-step, against the same robot on the in-process simulator; and the server
// killed mid-task, which the robot must report as a fault and end on, not hang.
#include <signal.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "dds_test_support.hpp"
#include "tripodal/dds/dds_hardware.hpp"
#include "tripodal/dds/endpoint.hpp"

using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {

const std::string kTool = TRIPODAL_TOOL;
const std::string kRobot = std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/psr2.yaml";
const std::string kWorld = std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace.yaml";

// A `tripodal` process, its output (stdout and stderr) in a file.
class Tool : public ChildProcess {
 public:
  Tool(std::vector<std::string> args, std::string log)
      : ChildProcess(kTool, std::move(args), std::move(log)) {}
};

std::string log_file(const std::string& name) {
  return "/tmp/" + test_namespace() + "_" + name + ".log";
}

// "78.25 s simulated" of `tripodal run`'s last line.
double simulated_s(const std::string& out) {
  std::smatch m;
  REQUIRE(std::regex_search(out, m, std::regex(R"(; ([0-9.]+) s simulated;)")));
  return std::stod(m[1].str());
}

}  // namespace

TEST_CASE("dds: a robot runs its task against tripodal sim-server as on the in-process simulator",
          "[dds][sim_server]") {
  const std::string ns = test_namespace();
  const std::string domain = std::to_string(test_domain(40));
  const std::string task = "patrol rooms 2111 and 2133";
  Tool server({"sim-server", "--robot", kRobot, "--world", kWorld, "--namespace", ns, "--domain", domain,
               "--seed", "1", "--wait-s", "60"},
              log_file("server"));
  const auto start = std::chrono::steady_clock::now();
  Tool robot({"run", "--robot", kRobot, "--world", kWorld, "--task", task, "--seed", "1", "--hardware", "dds",
              "--hardware-param", "namespace=" + ns, "--hardware-param", "domain_id=" + domain},
             log_file("robot"));
  const int robot_exit = robot.wait(60s);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string out = robot.output();
  INFO(out);
  REQUIRE(robot_exit == 0);
  CHECK(out.find("task patrol succeeded") != std::string::npos);
  // The robot leaving ends the server, with its report.
  REQUIRE(server.wait(15s) == 0);
  const std::string served = server.output();
  INFO(served);
  CHECK(std::regex_search(
      served,
      std::regex(
          R"(sim-server ended: the robot left.*; [0-9]+ steps served; [0-9.]+ s simulated; distance [0-9.]+ m; 0 collisions)")));

  // The same robot and seed in one process: the same task, about the same time.
  Tool local({"run", "--robot", kRobot, "--world", kWorld, "--task", task, "--seed", "1"}, log_file("local"));
  REQUIRE(local.wait(60s) == 0);
  const std::string local_out = local.output();
  CHECK(local_out.find("task patrol succeeded") != std::string::npos);
  const double remote_s = simulated_s(out);
  const double local_s = simulated_s(local_out);
  CHECK(remote_s == Approx(local_s).margin(1.0));
  WARN("over DDS: " << remote_s << " s simulated in " << wall_s
                    << " s of wall time (robot and server started); in process: " << local_s
                    << " s simulated");
}

TEST_CASE("dds: a sim-server killed mid-task is a fault of the robot's hardware, which ends the task",
          "[dds][sim_server]") {
  const std::string ns = test_namespace();
  const std::string domain = std::to_string(test_domain(41));
  Tool server({"sim-server", "--robot", kRobot, "--world", kWorld, "--namespace", ns, "--domain", domain,
               "--lease-s", "1", "--wait-s", "60"},
              log_file("server_killed"));
  Tool robot({"run", "--robot", kRobot, "--world", kWorld, "--task", "clean the room 2111", "--hardware",
              "dds", "--hardware-param", "namespace=" + ns, "--hardware-param", "domain_id=" + domain,
              "--hardware-param", "step_timeout_s=5"},
             log_file("robot_killed"));
  // Killed once the robot is cleaning (its life cycle says so).
  const auto until = std::chrono::steady_clock::now() + 30s;
  while (robot.output().find("activate BhCleaning") == std::string::npos &&
         std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(20ms);
  }
  REQUIRE(robot.output().find("activate BhCleaning") != std::string::npos);
  std::this_thread::sleep_for(300ms);
  server.kill(SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  REQUIRE(server.wait(5s) == 128 + SIGKILL);
  const int robot_exit = robot.wait(20s);
  const double after_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
  const std::string out = robot.output();
  INFO(out);
  CHECK(robot_exit == 4);  // the task failed: no hang, no crash
  CHECK(out.find("fault hardware: ") != std::string::npos);
  CHECK(out.find("PrCleaning failed: module hardware failed: ") != std::string::npos);
  CHECK(out.find("task clean failed") != std::string::npos);
  // Seen within the server's 1 s lease (or the 5 s step timeout), and the run ends at once after.
  CHECK(after_s < 6.0);
  WARN("the robot ended " << after_s << " s after the server was killed");
}

TEST_CASE("dds: sim-server --realtime runs on its own, driven by cmd_vel, publishing clock",
          "[dds][sim_server]") {
  const std::string ns = test_namespace();
  const std::uint32_t domain = test_domain(44);
  Tool server({"sim-server", "--robot", kRobot, "--world", kWorld, "--namespace", ns, "--domain",
               std::to_string(domain), "--realtime", "5"},
              log_file("server_realtime"));
  tripodal::dds::ParticipantOptions po;
  po.domain_id = domain;
  tripodal::dds::Participant p(po);
  const tripodal::dds::BaseTopics topics(ns);
  tripodal::dds::Publisher<tripodal::dds::msg::Twist> cmd_vel(p, topics.cmd_vel,
                                                              {.kind = tripodal::dds::TopicKind::command});
  tripodal::dds::Subscriber<tripodal::dds::msg::Clock> clock(p, topics.clock,
                                                             {.kind = tripodal::dds::TopicKind::state});
  tripodal::dds::Subscriber<tripodal::dds::msg::SimState> state(p, topics.sim_state,
                                                                {.kind = tripodal::dds::TopicKind::state});
  REQUIRE(cmd_vel.wait_for_subscribers(1, 10s));
  REQUIRE(clock.wait_for_publishers(1, 10s));
  REQUIRE(state.wait_for_publishers(1, 10s));
  // Forward at 0.2 m/s for a second of wall time (about 5 s simulated at 5x).
  double start_x = -1.0;
  double last_x = 0.0;
  const auto until = std::chrono::steady_clock::now() + 1s;
  while (std::chrono::steady_clock::now() < until) {
    cmd_vel.publish({{0.2, 0.0, 0.0}, {0.0, 0.0, 0.0}});
    for (const auto& s : state.take()) {
      if (start_x < 0.0) start_x = s.x;
      last_x = s.x;
    }
    std::this_thread::sleep_for(50ms);
  }
  const auto ticks = clock.take(1000);
  REQUIRE(!ticks.empty());
  const double simulated_s = tripodal::dds::ros_seconds(ticks.back().clock);
  server.kill(SIGTERM);
  REQUIRE(server.wait(10s) == 0);
  const std::string out = server.output();
  INFO(out);
  CHECK(simulated_s > 0.5);        // it runs by itself (5 s at 5x on a quiet machine; a loaded one lags)
  CHECK(simulated_s < 10.0);       // and no faster than asked
  CHECK(last_x - start_x > 0.05);  // cmd_vel drove it (the start pose faces +x)
  CHECK(std::regex_search(
      out,
      std::regex(
          R"(sim-server ended: stopped; [0-9]+ periods; [0-9.]+ s simulated; distance [0-9.]+ m; 0 collisions)")));
  WARN("--realtime 5: " << simulated_s << " s simulated in about 1 s of wall time; moved " << last_x - start_x
                        << " m");
}
