// Two processes on loopback: this one and tests/dds/dds_peer.cpp, started with posix_spawn.
#include <catch2/catch.hpp>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "child_process.hpp"
#include "dds_test_support.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/dds/robot_modules.hpp"
#include "tripodal/robot/robot.hpp"

using namespace tripodal;
using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {

// The peer process (tests/dds/dds_peer.cpp).
class Peer : public ChildProcess {
 public:
  explicit Peer(std::vector<std::string> args) : ChildProcess(TRIPODAL_DDS_PEER, std::move(args)) {}
};

template <class T>
void echo_round_trip(Participant& p, const T& message, TopicKind kind) {
  const auto ros = MessageType<T>::ros;
  const std::string name(ros.substr(ros.rfind('/') + 1));
  Subscriber<T> pong(p, ros_topic(name + "_pong", test_namespace()), {.kind = kind});
  Publisher<T> ping(p, ros_topic(name + "_ping", test_namespace()), {.kind = kind});
  INFO(MessageType<T>::dds);
  REQUIRE(ping.wait_for_subscribers(1, 10s));
  REQUIRE(pong.wait_for_publishers(1, 10s));
  ping.publish(message);
  const auto got = pong.take_one(5s);
  REQUIRE(got.has_value());
  CHECK(*got == message);
}

}  // namespace

TEST_CASE("dds: cmd_vel published by another process is received on loopback", "[dds][process]") {
  Participant p(test_options(10));
  // A command subscriber keeps only the latest sample (the base wants the newest command); this
  // one keeps them all, to check that each of the ten arrives, in order.
  Qos keep_all = qos_for(TopicKind::command, Role::subscriber);
  keep_all.depth = 16;
  Subscriber<msg::Twist> cmd_vel(p, ros_topic("cmd_vel", test_namespace()), {.qos = keep_all});
  Peer peer({"cmd-vel", std::to_string(test_domain(10)), test_namespace(), "10"});
  std::vector<msg::Twist> got;
  const auto until = std::chrono::steady_clock::now() + 15s;
  while (got.size() < 10 && std::chrono::steady_clock::now() < until) {
    if (auto t = cmd_vel.take_one(100ms)) got.push_back(*t);
  }
  REQUIRE(got.size() == 10);
  for (std::size_t i = 0; i < got.size(); ++i) {
    CHECK(got[i].linear.x == Approx(0.1 * static_cast<double>(i + 1)));
    CHECK(got[i].angular.z == Approx(-0.1 * static_cast<double>(i + 1)));
  }
  CHECK(peer.wait(10s) == 0);
}

TEST_CASE("dds: every message type makes a round trip through another process", "[dds][process]") {
  Participant p(test_options(11));
  Peer peer({"echo", std::to_string(test_domain(11)), test_namespace()});
  echo_round_trip(p, sample_string(), TopicKind::event);
  echo_round_trip(p, sample_twist(), TopicKind::state);
  echo_round_trip(p, sample_pose(), TopicKind::state);
  echo_round_trip(p, sample_odometry(), TopicKind::state);
  echo_round_trip(p, sample_scan(), TopicKind::state);
  echo_round_trip(p, sample_grid(), TopicKind::map);
  echo_round_trip(p, sample_event(), TopicKind::event);
  echo_round_trip(p, sample_task(), TopicKind::state);
  peer.kill(SIGTERM);
  CHECK(peer.wait(10s) == 0);
}

TEST_CASE("dds: a killed process is reported silent within its lease", "[dds][process]") {
  Participant p(test_options(12));
  std::mutex m;
  std::condition_variable cv;
  std::optional<std::chrono::steady_clock::time_point> alive;
  std::optional<std::chrono::steady_clock::time_point> lost;
  Subscriber<msg::Event> events(p, ros_topic("events", test_namespace()),
                                {.kind = TopicKind::event, .on_status = [&](const StatusEvent& e) {
                                   std::lock_guard lock(m);
                                   if (e.kind == StatusKind::liveliness_regained) alive = e.at;
                                   if (e.kind == StatusKind::liveliness_lost) lost = e.at;
                                   cv.notify_all();
                                 }});
  constexpr auto lease = 500ms;
  Peer peer({"alive", std::to_string(test_domain(12)), test_namespace(), std::to_string(lease.count())});
  {
    std::unique_lock lock(m);
    REQUIRE(cv.wait_for(lock, 10s, [&] { return alive.has_value(); }));
  }
  REQUIRE(events.take_one(5s).has_value());
  peer.kill(SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  CHECK(peer.wait(5s) == 128 + SIGKILL);
  std::unique_lock lock(m);
  REQUIRE(cv.wait_for(lock, 5s, [&] { return lost.has_value(); }));
  const auto after = std::chrono::duration_cast<std::chrono::milliseconds>(*lost - killed);
  INFO("a killed peer reported silent " << after.count() << " ms after SIGKILL (lease 500 ms)");
  CHECK(after <= lease + 200ms);
}

// The laser of a robot in another process: killed, its DdsLaser resource is the robot's fault once
// the peer's participant lease runs out (the robot's supervisor sees it, "laser.fault" is posted).
TEST_CASE("dds: a robot's DdsLaser whose process is killed is a fault within the lease", "[dds][process]") {
  const std::uint32_t domain = test_domain(13);
  const RobotProfile profile = load_robot_profile_from_string(
      "robot: {name: lidar}\nresources:\n  - {name: laser, type: DdsLaser, parameters: {namespace: " + test_namespace() +
          ", domain_id: " + std::to_string(domain) + "}}\n",
      "lidar.yaml", ".");
  RobotPlugins plugins = builtin_plugins();
  register_dds_modules(plugins.resources, plugins.controllers);
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  struct Faults final : SupervisorObserver {
    std::vector<std::string> seen;
    void on_fault(std::string_view source, std::string_view reason, Time) override {
      seen.push_back(std::string(source) + ": " + std::string(reason));
    }
  } faults;
  robot->supervisor().add_observer(faults);
  auto* laser = dynamic_cast<DdsLaserResource*>(robot->resources().find("laser"));
  REQUIRE(laser != nullptr);

  constexpr auto lease = 500ms;
  Peer peer({"scan", std::to_string(domain), test_namespace(), std::to_string(lease.count())});
  for (int i = 0; i < 1000 && !laser->has_reading(); ++i) {
    std::this_thread::sleep_for(5ms);
    laser->poll(clock.now());
  }
  REQUIRE(laser->has_reading());
  robot->run_for(200ms);
  CHECK(faults.seen.empty());

  peer.kill(SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  CHECK(peer.wait(5s) == 128 + SIGKILL);
  while (faults.seen.empty() && std::chrono::steady_clock::now() - killed < 5s) {
    robot->run_for(50ms);  // one sequencing period: the resource's faults taken and reported
    std::this_thread::sleep_for(5ms);
  }
  const auto after = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - killed);
  INFO("the killed laser was the robot's fault " << after.count() << " ms after SIGKILL (lease 500 ms)");
  REQUIRE(faults.seen.size() == 1);
  CHECK_THAT(faults.seen.front(), Catch::StartsWith("laser: the publisher of " + ros_topic("scan", test_namespace()) + " went silent"));
  CHECK(after <= lease + 300ms);
  robot->supervisor().remove_observer(faults);
}
