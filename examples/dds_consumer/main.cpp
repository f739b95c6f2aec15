// A cmd_vel sent and received through the installed tripodal::dds, on loopback. Exits 0 when the
// command came back unchanged. Domain 199 unless given: tripodal_dds_consumer [domain]
#include <chrono>
#include <cstdio>
#include <string>

#include "tripodal/dds/endpoint.hpp"

int main(int argc, char** argv) {
  using namespace tripodal::dds;
  using namespace std::chrono_literals;
  try {
    ParticipantOptions options;
    options.domain_id = argc > 1 ? static_cast<std::uint32_t>(std::stoul(argv[1])) : 199U;
    Participant participant(options);
    const std::string topic = ros_topic("cmd_vel", "consumer");
    Subscriber<msg::Twist> base(participant, topic, {.kind = TopicKind::command});
    Publisher<msg::Twist> teleop(participant, topic, {.kind = TopicKind::command});
    if (!teleop.wait_for_subscribers(1, 5s)) {
      std::fprintf(stderr, "tripodal_dds_consumer: no subscriber matched on %s\n", topic.c_str());
      return 1;
    }
    const msg::Twist sent{{0.25, 0.0, 0.0}, {0.0, 0.0, 0.5}};
    teleop.publish(sent);
    const auto got = base.take_one(5s);
    if (!got || !(*got == sent)) {
      std::fprintf(stderr, "tripodal_dds_consumer: the cmd_vel did not come back\n");
      return 1;
    }
    std::printf("%s (%s): vx %.2f m/s, wz %.2f rad/s\n", topic.c_str(), std::string(MessageType<msg::Twist>::dds).c_str(),
                got->linear.x, got->angular.z);
    return 0;
  } catch (const DdsError& e) {
    std::fprintf(stderr, "tripodal_dds_consumer: %s\n", e.what());
    return 1;
  }
}
