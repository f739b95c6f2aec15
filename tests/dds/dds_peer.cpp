// The other process of the dds two-process tests (tests/dds/two_process_test.cpp):
//   tripodal_dds_peer cmd-vel <domain> <namespace> <count> [KEYS_DIR IDENTITY]  publishes <count> cmd_vel,
//                                                        linear.x = 0.1 * i (secured with IDENTITY's files, security.hpp)
//   tripodal_dds_peer echo <domain> <namespace>             returns every message type: <type>_ping -> <type>_pong
//   tripodal_dds_peer alive <domain> <namespace> <lease_ms> a live event publisher, until killed
//   tripodal_dds_peer scan <domain> <namespace> <lease_ms>  a laser: a LaserScan on scan at 10 Hz, until killed
// Exits 0 when done, 2 on a usage error, 3 when no subscriber came, 4 on a DDS error.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "tripodal/dds/endpoint.hpp"

using namespace tripodal::dds;
using namespace std::chrono_literals;

namespace {

volatile std::sig_atomic_t stop = 0;
void on_signal(int) { stop = 1; }

template <class T>
struct Echo {
  Publisher<T> pong;
  Subscriber<T> ping;
  Echo(Participant& p, const std::string& ns, TopicKind kind)
      : pong(p, ros_topic(name() + "_pong", ns), {.kind = kind}),
        ping(p, ros_topic(name() + "_ping", ns), {.kind = kind}, [this](const T& m) { pong.publish(m); }) {}
  static std::string name() {
    const auto ros = MessageType<T>::ros;
    return std::string(ros.substr(ros.rfind('/') + 1));
  }
};

void wait_until_stopped(std::chrono::seconds limit) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (stop == 0 && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(10ms);
}

int run(int argc, char** argv) {
  if (argc < 4) return 2;
  const std::string mode = argv[1];
  ParticipantOptions options;
  options.domain_id = static_cast<std::uint32_t>(std::stoul(argv[2]));
  const std::string ns = argv[3];
  if (mode == "cmd-vel" && (argc == 5 || argc == 7)) {
    options.participant_lease = 1s;
    if (argc == 7) options.security = fleet_identity(argv[5], argv[6]);
    Participant p(options);
    // The command QoS keeps only the latest sample, which a writer cannot resend once replaced;
    // the test checks that every one of its samples arrives, so it keeps them all.
    Qos keep_all = qos_for(TopicKind::command, Role::publisher);
    keep_all.depth = 16;
    Publisher<msg::Twist> pub(p, ros_topic("cmd_vel", ns), {.qos = keep_all});
    if (!pub.wait_for_subscribers(1, 10s)) return 3;
    const int count = std::stoi(argv[4]);
    for (int i = 1; i <= count; ++i) pub.publish({{0.1 * i, 0.0, 0.0}, {0.0, 0.0, -0.1 * i}});
    return pub.wait_for_acknowledgments(5s) ? 0 : 3;
  }
  if (mode == "echo" && argc == 4) {
    options.participant_lease = 1s;
    Participant p(options);
    Echo<msg::String> e1(p, ns, TopicKind::event);
    Echo<msg::Twist> e2(p, ns, TopicKind::state);
    Echo<msg::PoseWithCovarianceStamped> e3(p, ns, TopicKind::state);
    Echo<msg::Odometry> e4(p, ns, TopicKind::state);
    Echo<msg::LaserScan> e5(p, ns, TopicKind::state);
    Echo<msg::OccupancyGrid> e6(p, ns, TopicKind::map);
    Echo<msg::Event> e7(p, ns, TopicKind::event);
    Echo<msg::TaskCommand> e8(p, ns, TopicKind::state);
    std::puts("ready");
    std::fflush(stdout);
    wait_until_stopped(120s);
    return 0;
  }
  if (mode == "alive" && argc == 5) {
    // Its participant's lease is what the other process waits before declaring it gone.
    options.participant_lease = std::chrono::milliseconds(std::stoi(argv[4]));
    Participant p(options);
    Qos qos = qos_for(TopicKind::event, Role::publisher);
    qos.lease = options.participant_lease;
    Publisher<msg::Event> pub(p, ros_topic("events", ns), {.qos = qos});
    if (!pub.wait_for_subscribers(1, 10s)) return 3;
    pub.publish({{}, "peer", "peer", "started", "", 0});
    wait_until_stopped(120s);
    return 0;
  }
  if (mode == "scan" && argc == 5) {
    options.participant_lease = std::chrono::milliseconds(std::stoi(argv[4]));
    Participant p(options);
    Publisher<msg::LaserScan> pub(p, ros_topic("scan", ns), {.kind = TopicKind::scan});
    if (!pub.wait_for_subscribers(1, 10s)) return 3;
    msg::LaserScan scan{{}, -1.5F, 1.5F, 0.5F, 0.0F, 0.1F, 0.05F, 10.0F, {2.0F, 2.0F, 2.0F, 2.0F, 2.0F, 2.0F, 2.0F}, {}};
    const auto until = std::chrono::steady_clock::now() + 120s;
    while (stop == 0 && std::chrono::steady_clock::now() < until) {
      pub.publish(scan);
      std::this_thread::sleep_for(100ms);
    }
    return 0;
  }
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  try {
    const int rc = run(argc, argv);
    if (rc == 2) std::fprintf(stderr, "usage: tripodal_dds_peer cmd-vel|echo|alive|scan <domain> <namespace> [count|lease_ms]\n");
    return rc;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tripodal_dds_peer: %s\n", e.what());
    return 4;
  }
}
