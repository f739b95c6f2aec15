// The transport between two participants of one process: every type round trip, QoS per kind,
// and the statuses a robot turns into fault events (a silent publisher, a missed deadline).
#include <catch2/catch.hpp>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "dds_test_support.hpp"
#include "tripodal/dds/endpoint.hpp"

using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {

template <class T>
void round_trip(Participant& a, Participant& b, const T& message, TopicKind kind) {
  const std::string topic = ros_topic(std::string(MessageType<T>::ros), test_namespace());
  Subscriber<T> sub(b, topic, {.kind = kind});
  Publisher<T> pub(a, topic, {.kind = kind});
  REQUIRE(pub.wait_for_subscribers(1, 5s));
  pub.publish(message);
  const auto got = sub.take_one(5s);
  INFO(MessageType<T>::dds);
  REQUIRE(got.has_value());
  CHECK(*got == message);
}

// Status events collected from a Cyclone thread, waited for by the test.
class StatusLog {
 public:
  StatusCallback callback() {
    return [this](const StatusEvent& e) {
      std::lock_guard lock(mutex_);
      events_.push_back(e);
      changed_.notify_all();
    };
  }
  std::optional<StatusEvent> wait_for(StatusKind kind, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    std::optional<StatusEvent> found;
    changed_.wait_for(lock, timeout, [&] {
      for (const auto& e : events_) {
        if (e.kind == kind) {
          found = e;
          return true;
        }
      }
      return false;
    });
    return found;
  }
  void clear() {
    std::lock_guard lock(mutex_);
    events_.clear();
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<StatusEvent> events_;
};

}  // namespace

TEST_CASE("dds: every message type makes a round trip between two participants", "[dds]") {
  Participant a(test_options(1));
  Participant b(test_options(1));
  round_trip(a, b, sample_string(), TopicKind::event);
  round_trip(a, b, sample_twist(), TopicKind::command);
  round_trip(a, b, sample_pose(), TopicKind::state);
  round_trip(a, b, sample_odometry(), TopicKind::state);
  round_trip(a, b, sample_scan(), TopicKind::scan);
  round_trip(a, b, sample_grid(), TopicKind::map);
  round_trip(a, b, sample_event(), TopicKind::event);
  round_trip(a, b, sample_task(), TopicKind::command);
  round_trip(a, b, sample_joint_state(), TopicKind::state);
  round_trip(a, b, msg::Clock{{78, 900000000}}, TopicKind::state);
  round_trip(a, b, sample_sim_step(), TopicKind::state);
  round_trip(a, b, sample_sim_state(), TopicKind::state);
  // Empty strings and sequences travel as well (a zero length, no buffer).
  round_trip(a, b, msg::LaserScan{}, TopicKind::scan);
  round_trip(a, b, msg::OccupancyGrid{}, TopicKind::map);
  round_trip(a, b, msg::JointState{}, TopicKind::state);
}

TEST_CASE("dds: QoS per kind of topic", "[dds]") {
  const auto cmd_pub = qos_for(TopicKind::command, Role::publisher);
  const auto cmd_sub = qos_for(TopicKind::command, Role::subscriber);
  CHECK(cmd_pub.reliability == Reliability::reliable);
  CHECK(cmd_pub.durability == Durability::transient_local);
  CHECK(cmd_sub.durability == Durability::volatile_);  // matches ROS 2's volatile teleop publishers
  CHECK(qos_for(TopicKind::event, Role::subscriber).durability == Durability::transient_local);
  CHECK(qos_for(TopicKind::map, Role::publisher).durability == Durability::transient_local);
  CHECK(qos_for(TopicKind::scan, Role::publisher).reliability == Reliability::best_effort);
  CHECK(qos_for(TopicKind::scan, Role::subscriber).reliability == Reliability::best_effort);
  CHECK(qos_for(TopicKind::state, Role::publisher).reliability == Reliability::reliable);
  CHECK(to_string(TopicKind::scan) == "scan");

  Participant a(test_options(2));
  Participant b(test_options(2));
  SECTION("a map published before its subscriber exists reaches it (transient local)") {
    const auto topic = ros_topic("map", test_namespace());
    Publisher<msg::OccupancyGrid> pub(a, topic, {.kind = TopicKind::map});
    pub.publish(sample_grid());
    Subscriber<msg::OccupancyGrid> late(b, topic, {.kind = TopicKind::map});
    const auto got = late.take_one(5s);
    REQUIRE(got.has_value());
    CHECK(*got == sample_grid());
  }
  SECTION("a best-effort scan publisher does not match a reliable subscriber (as in ROS 2)") {
    const auto topic = ros_topic("scan", test_namespace());
    Publisher<msg::LaserScan> pub(a, topic, {.kind = TopicKind::scan});
    Subscriber<msg::LaserScan> reliable(b, topic, {.kind = TopicKind::state});
    Subscriber<msg::LaserScan> best_effort(b, topic, {.kind = TopicKind::scan});
    REQUIRE(pub.wait_for_subscribers(1, 5s));
    std::this_thread::sleep_for(200ms);
    CHECK(pub.matched_subscribers() == 1);
    CHECK(reliable.matched_publishers() == 0);
  }
}

TEST_CASE("dds: a data callback gets every sample on arrival", "[dds]") {
  Participant a(test_options(3));
  Participant b(test_options(3));
  const auto topic = ros_topic("cmd_vel", test_namespace());
  std::mutex m;
  std::condition_variable cv;
  std::vector<double> speeds;
  Subscriber<msg::Twist> sub(b, topic, {.kind = TopicKind::command}, [&](const msg::Twist& t) {
    std::lock_guard lock(m);
    speeds.push_back(t.linear.x);
    cv.notify_all();
  });
  Publisher<msg::Twist> pub(a, topic, {.kind = TopicKind::command});
  REQUIRE(pub.wait_for_subscribers(1, 5s));
  for (int i = 1; i <= 20; ++i) pub.publish({{0.01 * i, 0.0, 0.0}, {}});
  std::unique_lock lock(m);
  REQUIRE(cv.wait_for(lock, 5s, [&] { return speeds.size() == 20; }));
  CHECK(speeds.front() == Approx(0.01));
  CHECK(speeds.back() == Approx(0.20));
  CHECK_THROWS_WITH(sub.take_one(1ms), Catch::Contains("has a data callback"));
}

TEST_CASE("dds: a publisher that stops asserting is reported lost within its lease", "[dds]") {
  Participant a(test_options(4));
  Participant b(test_options(4));
  const auto topic = ros_topic("pose", test_namespace());
  constexpr auto lease = 300ms;
  Qos qos = qos_for(TopicKind::state, Role::publisher);
  qos.liveliness = Liveliness::manual_by_topic;
  qos.lease = lease;
  StatusLog log;
  Subscriber<msg::PoseWithCovarianceStamped> sub(b, topic, {.qos = qos, .on_status = log.callback()});
  Publisher<msg::PoseWithCovarianceStamped> pub(a, topic, {.qos = qos});
  REQUIRE(pub.wait_for_subscribers(1, 5s));
  // Alive while it publishes faster than the lease...
  for (int i = 0; i < 6; ++i) {
    pub.publish(sample_pose());
    std::this_thread::sleep_for(100ms);
  }
  REQUIRE(log.wait_for(StatusKind::liveliness_regained, 1s).has_value());
  log.clear();
  // ...and an assertion without data keeps it alive too.
  pub.assert_liveliness();
  const auto last_sign = std::chrono::steady_clock::now();
  const auto lost = log.wait_for(StatusKind::liveliness_lost, 3s);
  REQUIRE(lost.has_value());
  const auto after = std::chrono::duration_cast<std::chrono::milliseconds>(lost->at - last_sign);
  INFO("liveliness lost reported " << after.count() << " ms after the last sign of life (lease 300 ms)");
  CHECK(after >= lease - 50ms);
  CHECK(after <= lease + 150ms);
  CHECK(lost->topic == topic);
  CHECK(lost->current_count == 0);
  // Publishing again brings it back.
  log.clear();
  pub.publish(sample_pose());
  CHECK(log.wait_for(StatusKind::liveliness_regained, 1s).has_value());
}

TEST_CASE("dds: a deleted publisher is reported gone at once", "[dds]") {
  Participant a(test_options(5));
  Participant b(test_options(5));
  const auto topic = ros_topic("odom", test_namespace());
  StatusLog log;
  Subscriber<msg::Odometry> sub(b, topic, {.kind = TopicKind::state, .on_status = log.callback()});
  {
    Publisher<msg::Odometry> pub(a, topic, {.kind = TopicKind::state});
    REQUIRE(pub.wait_for_subscribers(1, 5s));
    pub.publish(sample_odometry());
    REQUIRE(log.wait_for(StatusKind::liveliness_regained, 1s).has_value());
    log.clear();
  }
  const auto lost = log.wait_for(StatusKind::liveliness_lost, 1s);
  REQUIRE(lost.has_value());
  CHECK(lost->current_count == 0);
  CHECK(sub.matched_publishers() == 0);
}

TEST_CASE("dds: a missed deadline is reported to both sides", "[dds]") {
  Participant a(test_options(6));
  Participant b(test_options(6));
  const auto topic = ros_topic("cmd_vel", test_namespace());
  Qos qos = qos_for(TopicKind::command, Role::subscriber);
  qos.deadline = 100ms;
  StatusLog reader_log;
  StatusLog writer_log;
  Subscriber<msg::Twist> sub(b, topic, {.qos = qos, .on_status = reader_log.callback()});
  Qos offered = qos_for(TopicKind::command, Role::publisher);
  offered.deadline = 100ms;
  Publisher<msg::Twist> pub(a, topic, {.qos = offered, .on_status = writer_log.callback()});
  REQUIRE(pub.wait_for_subscribers(1, 5s));
  pub.publish(sample_twist());
  const auto start = std::chrono::steady_clock::now();
  const auto missed = reader_log.wait_for(StatusKind::deadline_missed, 2s);
  REQUIRE(missed.has_value());
  CHECK(missed->at - start <= 300ms);
  CHECK(writer_log.wait_for(StatusKind::deadline_missed, 2s).has_value());
  // A subscriber that asks for a shorter deadline than offered does not match.
  Qos strict = qos;
  strict.deadline = 10ms;
  Subscriber<msg::Twist> impatient(b, topic, {.qos = strict});
  std::this_thread::sleep_for(200ms);
  CHECK(impatient.matched_publishers() == 0);
}

TEST_CASE("dds: errors name the operation and the domain or topic", "[dds]") {
  ParticipantOptions bad;
  bad.domain_id = 300;
  CHECK_THROWS_WITH(Participant(bad), Catch::Contains("domain 300") && Catch::Contains("0..232"));
  Participant a(test_options(7));
  CHECK_THROWS_WITH(Publisher<msg::Twist>(a, ""), Catch::Contains("needs a name"));
  CHECK_THROWS_WITH(Publisher<msg::Twist>(a, "rt/bad name"),
                    Catch::Contains("'rt/bad name'") && Catch::Contains("dds_create_topic"));
  ParticipantOptions other = test_options(7);
  other.participant_lease = 2s;
  CHECK_THROWS_WITH(Participant(other), Catch::Contains("another configuration"));
  const auto config = loopback_config(test_options(7));
  CHECK_THAT(config, Catch::Contains("<AllowMulticast>false</AllowMulticast>") &&
                         Catch::Contains("<NetworkInterface address=\"127.0.0.1\"/>") &&
                         Catch::Contains("<Peer address=\"127.0.0.1\"/>"));
}
