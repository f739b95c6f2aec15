// tripodal as a citizen of the ROS 2 graph, checked by an independent peer: tests/dds/ros2_peer.cpp
// on Fast DDS (ROS 2's default middleware) with types written by hand from the ROS 2 message
// definitions and rclcpp's default QoS. It must see the robot's /tf, /tf_static, /clock, amcl_pose
// and its nodes in ros_discovery_info; its LaserScans on /scan must reach a robot whose profile
// names a DdsLaser, the first one at once even when it is larger than a datagram.
// Built only when Fast DDS is installed (tests/dds/CMakeLists.txt says so when it is not).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "child_process.hpp"
#include "dds_test_support.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/dds/robot_bridge.hpp"
#include "tripodal/dds/robot_modules.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
const std::filesystem::path kData = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "tests/dds/data";

std::string read_text(const std::filesystem::path& f) {
  std::ifstream in(f);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string log_path(const std::string& what) {
  return (std::filesystem::temp_directory_path() / ("tripodal_ros2_peer_" + what + "_" + std::to_string(::getpid()) + ".log")).string();
}

struct Ros2Peer : ChildProcess {
  Ros2Peer(std::vector<std::string> args, const std::string& what) : ChildProcess(TRIPODAL_ROS2_PEER, std::move(args), log_path(what)) {}
};

}  // namespace

TEST_CASE("dds: a ROS 2 peer on Fast DDS sees the robot's tf, tf_static, clock, amcl_pose and nodes", "[dds][ros2]") {
  const std::uint32_t domain = test_domain(60);
  const std::string ns = "psr2_" + std::to_string(::getpid());
  const std::string yaml = read_text(kConfigs / "robots/psr2.yaml") + "\ndds:\n  domain_id: " + std::to_string(domain) +
                           "\n  namespace: " + ns + "\n  participant_lease_s: 1\n  period_s: 0.1\n";
  const RobotProfile profile = load_robot_profile_from_string(yaml, "psr2-dds.yaml", kConfigs / "robots");
  RobotPlugins plugins;
  register_all(plugins, std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml")));
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  RobotBridge bridge(*robot, clock, *profile.dds, RobotBridgeOptions{.simulated_time = true});
  CHECK(bridge.frame("base_link") == ns + "/base_link");
  CHECK(bridge.topic("tf") == "rt/tf");
  CHECK(bridge.topic("clock") == "rt/clock");

  // The peer asks for the node by the name `ros2 node list` would print.
  Ros2Peer peer({"graph", std::to_string(domain), ns, "20", "front_laser", "/" + ns + "/tripodal"}, "graph");
  int rc = -1;
  // The robot runs on simulated time while the peer listens, as `tripodal run` drives it.
  for (int i = 0; i < 4000 && rc < 0; ++i) {
    robot->run_for(std::chrono::milliseconds(50));
    bridge.update();
    std::this_thread::sleep_for(5ms);
    rc = peer.wait(1ms);  // checks once whether it ended
  }
  if (rc < 0) rc = peer.wait(25s);
  INFO(peer.output());
  REQUIRE(rc == 0);
  const std::string out = peer.output();
  CHECK_THAT(out, Catch::Contains("seen node /" + ns + "/tripodal"));
  // PSR-2's laser resource: its frame is the resource's name, at the base's origin (no dds frames).
  CHECK_THAT(out, Catch::Contains("seen tf_static " + ns + "/base_link " + ns + "/front_laser"));
  CHECK_THAT(out, Catch::Contains("seen amcl_pose " + ns + "/map"));
  CHECK_THAT(out, !Catch::Contains("incompatible qos"));
  CHECK(bridge.count("clock") > 0);
  CHECK(bridge.count("tf") > 0);
  CHECK(bridge.count("tf_static") == 1);
  WARN("Fast DDS peer: " << out.substr(out.rfind("all seen")));
}

TEST_CASE("dds: ros_discovery_info lists the node's readers and writers by their gids", "[dds][ros2]") {
  Participant p(test_options(61));
  p.declare_node("tripodal", "robot_a");
  Publisher<msg::Odometry> odom(p, ros_topic("odom", "robot_a"));
  Subscriber<msg::Twist> cmd(p, ros_topic("cmd_vel", "robot_a"), {.kind = TopicKind::command});
  msg::ParticipantEntitiesInfo info = p.graph_info();
  CHECK(info.gid == p.gid());
  REQUIRE(info.node_entities_info_seq.size() == 1);
  const msg::NodeEntitiesInfo& node = info.node_entities_info_seq.front();
  CHECK(node.node_namespace == "/robot_a");
  CHECK(node.node_name == "tripodal");
  CHECK(node.writer_gid_seq == std::vector<msg::Gid>{odom.gid()});
  CHECK(node.reader_gid_seq == std::vector<msg::Gid>{cmd.gid()});
  // The gid's prefix is the participant's (a DDS GUID: 12-byte prefix, 4-byte entity id).
  const msg::Gid writer = odom.gid();
  const msg::Gid participant = p.gid();
  CHECK(std::equal(writer.begin(), writer.begin() + 12, participant.begin()));
  CHECK(writer != participant);
  CHECK_THROWS_WITH(p.declare_node("9lives"), Catch::Contains("'9lives' is not a ROS 2 node name"));
  CHECK_THROWS_WITH(p.declare_node("ok", "/a/b-c"), Catch::Contains("'/a/b-c' is not a ROS 2 namespace"));

  // Another participant reads it as a ROS 2 tool does: reliable, transient local, after the fact.
  Participant tool(test_options(61));
  Subscriber<msg::ParticipantEntitiesInfo> graph(tool, "ros_discovery_info",
                                                 {.qos = Qos{Reliability::reliable, Durability::transient_local, 100, {}, Liveliness::automatic, {}}});
  bool seen = false;
  for (int i = 0; i < 100 && !seen; ++i) {
    if (auto m = graph.take_one(100ms); m && m->gid == p.gid()) seen = m->node_entities_info_seq.size() == 1;
  }
  CHECK(seen);
}

TEST_CASE("dds: a ROS 2 laser driver on Fast DDS feeds a robot whose profile names a DdsLaser", "[dds][ros2]") {
  const std::uint32_t domain = test_domain(62);
  RobotProfile profile = load_robot_profile(kData / "ros2_lidar_robot.yaml");
  REQUIRE(profile.dds);
  profile.dds->domain_id = domain;
  RobotPlugins plugins = builtin_plugins();
  register_dds_modules(plugins.resources, plugins.controllers);
  SimClock clock;
  RobotOptions ro;
  ro.parameters.push_back({"laser", "domain_id", std::to_string(domain)});
  const auto robot = Robot::assemble(profile, plugins, clock, ro);
  auto* laser = dynamic_cast<DdsLaserResource*>(robot->resources().find("laser"));
  REQUIRE(laser != nullptr);
  CHECK(laser->topic() == "rt/scan");

  // 10000 beams of ranges and intensities: 80 kB, more than one datagram (Fast DDS fragments above
  // 64 kB). A driver's default QoS (reliable), written as
  // soon as the driver's writer matched the robot's reader, and a heartbeat so rare that only the
  // reader's own request (its pre-emptive ACKNACK on discovering the writer) can repair a first
  // sample the robot dropped because it had not discovered the driver yet.
  const int beams = 10000;
  // One scan only: it is the first sample of its writer.
  Ros2Peer peer({"scan", std::to_string(domain), "/scan", std::to_string(beams), "1", "0", "reliable", "60"}, "scan");
  for (int i = 0; i < 4000 && laser->received() == 0; ++i) std::this_thread::sleep_for(5ms);
  INFO(peer.output());
  REQUIRE(laser->received() == 1);
  laser->poll(clock.now());
  const LaserScan& scan = laser->latest();
  REQUIRE(scan.ranges_m.size() == static_cast<std::size_t>(beams));
  CHECK(scan.ranges_m.front() == 1.0F);  // range i = 1 + i / beams
  CHECK(scan.ranges_m[beams / 2] == 1.5F);
  CHECK(scan.intensities.size() == static_cast<std::size_t>(beams));
  CHECK(peer.wait(20s) == 0);
}

// Not run by default (a measurement, not a test): the latency of a Fast DDS writer's first sample
// (written as soon as the writer matched the robot's reader, with Fast DDS's default 3 s heartbeat
// period), to a reader of each reliability, for docs/distribution.md. Run with
//   TRIPODAL_LATENCY_REPEAT=20 tripodal_dds_ros2_tests "[.ros2-latency]" -s
TEST_CASE("dds: first-sample latency from a Fast DDS laser driver", "[.ros2-latency]") {
  const char* env = std::getenv("TRIPODAL_LATENCY_REPEAT");
  const int repeat = env != nullptr ? std::atoi(env) : 5;
  for (const bool reliable_reader : {false, true}) {
    for (const int beams : {100, 2000, 10000}) {
      std::vector<double> firsts_ms;
      int lost = 0;
      int lost_unmatched = 0;  // of those lost, the robot's reader never matched the driver's writer
      for (int r = 0; r < repeat; ++r) {
        const std::uint32_t domain = test_domain(63);
        ParticipantOptions po;
        po.domain_id = domain;
        Participant p(po);
        Qos q = qos_for(TopicKind::scan, Role::subscriber);
        if (reliable_reader) q.reliability = Reliability::reliable;
        std::mutex m;
        std::optional<double> first_ms;
        Subscriber<msg::LaserScan> sub(p, "rt/scan", {.qos = q}, [&](const msg::LaserScan& s) {
          const auto now = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
          const auto sent = static_cast<std::int64_t>(s.header.stamp.sec) * 1'000'000'000 + s.header.stamp.nanosec;
          std::lock_guard lock(m);
          if (!first_ms) first_ms = static_cast<double>(now - sent) * 1e-6;
        });
        Ros2Peer peer({"scan", std::to_string(domain), "/scan", std::to_string(beams), "1", "0", "reliable", "3"}, "latency");
        std::size_t matched = 0;
        for (int i = 0; i < 800; ++i) {
          std::this_thread::sleep_for(10ms);
          matched = std::max(matched, sub.matched_publishers());
          std::lock_guard lock(m);
          if (first_ms) break;
        }
        CHECK(peer.wait(30s) == 0);
        std::lock_guard lock(m);
        if (first_ms) {
          firsts_ms.push_back(*first_ms);
        } else {
          ++lost;
          if (matched == 0) ++lost_unmatched;
        }
      }
      std::sort(firsts_ms.begin(), firsts_ms.end());
      const auto at = [&](double f) { return firsts_ms.empty() ? -1.0 : firsts_ms[static_cast<std::size_t>(f * static_cast<double>(firsts_ms.size() - 1))]; };
      WARN((reliable_reader ? "reliable" : "best effort") << " reader, " << beams << " beams (" << 8 * beams + 64
                                                          << " bytes), first sample of " << repeat << " writers: min " << at(0.0)
                                                          << " ms, median " << at(0.5) << " ms, max " << at(1.0) << " ms, "
                                                          << lost << " not within 8 s (" << lost_unmatched
                                                          << " of them never matched)");
    }
  }
}
