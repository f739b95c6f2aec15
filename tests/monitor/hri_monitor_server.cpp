// Test program (monitor's Python tests): the PSR-2 on the simulator with an HRI module (TestHri)
// on a knowledge file, and the monitor serving it, held paused. It prints
// "monitor: http://127.0.0.1:PORT/?token=TOKEN" and serves until SIGTERM. The RKMS page and the
// touch page are tested against it (tests/monitor/rkms_browser_test.py, rkms_protocol_test.py).
//
// usage: tripodal_hri_monitor_server SOURCE_DIR KNOWLEDGE.xml
#include <chrono>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include "test_hri_module.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/monitor/robot_monitor.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int /*signal*/) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  using namespace tripodal;
  if (argc != 3) {
    std::cerr << "usage: tripodal_hri_monitor_server SOURCE_DIR KNOWLEDGE.xml\n";
    return 2;
  }
  try {
    const std::filesystem::path source = argv[1];
    RobotPlugins plugins;
    plugins.modules.add<testing_hri::TestHri>();
    register_all(plugins, std::make_shared<sim::World>(sim::load_world(source / "configs/worlds/workspace.yaml")));
    RobotProfile profile = load_robot_profile(source / "configs/robots/psr2.yaml");
    testing_hri::add_test_hri(profile, argv[2], source);
    SimClock clock;
    const auto robot = Robot::assemble(profile, plugins, clock);
    monitor::MonitorServer server(monitor::server_options("0"));
    monitor::RobotMonitor watch(*robot, clock, server, monitor::RobotMonitorOptions{.start_paused = true});
    server.start();
    std::signal(SIGTERM, on_signal);
    std::signal(SIGINT, on_signal);
    std::cout << "monitor: " << server.url() << std::endl;
    // The robot stays paused: only the operator's requests are answered, on this thread.
    while (g_stop == 0) {
      watch.update();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    server.stop();
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "tripodal_hri_monitor_server: " << e.what() << '\n';
    return 1;
  }
}
