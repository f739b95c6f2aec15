// An independent ROS 2 peer of the dds tests: Fast DDS (eProsima's, ROS 2's default middleware),
// not Cyclone, with the message types written here by hand from the public ROS 2 message
// definitions (.msg files of builtin_interfaces, std_msgs, geometry_msgs, sensor_msgs, tf2_msgs,
// rosgraph_msgs, rmw_dds_common) and serialised with Fast CDR, so that it shares no code with
// tripodal's transport. Its endpoints ask for what rclcpp's defaults ask for.
//   tripodal_ros2_peer graph <domain> <namespace> <limit_s> <laser_frame> <node>...
//       subscribes to /tf, /tf_static, /clock, <ns>/amcl_pose and ros_discovery_info; prints what it
//       sees and when; exits 0 once it saw map -> odom -> base_link on /tf, base_link ->
//       <laser_frame> on /tf_static (frames prefixed "<ns>/"), a /clock, an amcl_pose and every
//       <node> ("/ns/name") in ros_discovery_info.
//   tripodal_ros2_peer scan <domain> <topic> <beams> <count> <period_ms> <reliable|best_effort> <heartbeat_s>
//       a laser driver: once a reader matched, <count> LaserScans of <beams> beams on <topic>
//       (a ROS 2 name, "/scan"), range i of scan k = 1 + k + i / beams, stamped with the system
//       clock (CLOCK_REALTIME, which the test shares) at the write; the reliable writer's heartbeat
//       period (Fast DDS's default 3 s) is <heartbeat_s>.
// Exits 0 when done, 2 on a usage error, 3 when what it waits for did not come.
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastcdr::Cdr;
using eprosima::fastcdr::FastBuffer;
using namespace std::chrono_literals;

namespace {

// --- the messages, from their .msg definitions -------------------------------------------------

struct Time {  // builtin_interfaces/Time
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  void write(Cdr& c) const { c << sec << nanosec; }
  void read(Cdr& c) { c >> sec >> nanosec; }
};

struct Header {  // std_msgs/Header
  Time stamp;
  std::string frame_id;
  void write(Cdr& c) const {
    stamp.write(c);
    c << frame_id;
  }
  void read(Cdr& c) {
    stamp.read(c);
    c >> frame_id;
  }
};

struct TransformStamped {  // geometry_msgs/TransformStamped: Transform = Vector3 + Quaternion
  Header header;
  std::string child_frame_id;
  std::array<double, 3> translation{};
  std::array<double, 4> rotation{0, 0, 0, 1};
  void write(Cdr& c) const {
    header.write(c);
    c << child_frame_id;
    c.serializeArray(translation.data(), translation.size());
    c.serializeArray(rotation.data(), rotation.size());
  }
  void read(Cdr& c) {
    header.read(c);
    c >> child_frame_id;
    c.deserializeArray(translation.data(), translation.size());
    c.deserializeArray(rotation.data(), rotation.size());
  }
};

struct TFMessage {  // tf2_msgs/TFMessage
  static constexpr const char* kType = "tf2_msgs::msg::dds_::TFMessage_";
  std::vector<TransformStamped> transforms;
  void write(Cdr& c) const {
    c << static_cast<std::uint32_t>(transforms.size());
    for (const auto& t : transforms) t.write(c);
  }
  void read(Cdr& c) {
    std::uint32_t n = 0;
    c >> n;
    transforms.resize(n);
    for (auto& t : transforms) t.read(c);
  }
};

struct Clock {  // rosgraph_msgs/Clock
  static constexpr const char* kType = "rosgraph_msgs::msg::dds_::Clock_";
  Time clock;
  void write(Cdr& c) const { clock.write(c); }
  void read(Cdr& c) { clock.read(c); }
};

struct PoseWithCovarianceStamped {  // geometry_msgs: Header + Pose (Point, Quaternion) + double[36]
  static constexpr const char* kType = "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_";
  Header header;
  std::array<double, 7> pose{};
  std::array<double, 36> covariance{};
  void write(Cdr& c) const {
    header.write(c);
    c.serializeArray(pose.data(), pose.size());
    c.serializeArray(covariance.data(), covariance.size());
  }
  void read(Cdr& c) {
    header.read(c);
    c.deserializeArray(pose.data(), pose.size());
    c.deserializeArray(covariance.data(), covariance.size());
  }
};

using Gid = std::array<std::uint8_t, 16>;  // rmw_dds_common/Gid (Iron and later): uint8[16]

struct NodeEntitiesInfo {  // rmw_dds_common/NodeEntitiesInfo
  std::string node_namespace, node_name;
  std::vector<Gid> readers, writers;
  static void write_gids(Cdr& c, const std::vector<Gid>& gids) {
    c << static_cast<std::uint32_t>(gids.size());
    for (const Gid& g : gids) c.serializeArray(g.data(), g.size());
  }
  static void read_gids(Cdr& c, std::vector<Gid>& gids) {
    std::uint32_t n = 0;
    c >> n;
    gids.resize(n);
    for (Gid& g : gids) c.deserializeArray(g.data(), g.size());
  }
  void write(Cdr& c) const {
    c << node_namespace << node_name;
    write_gids(c, readers);
    write_gids(c, writers);
  }
  void read(Cdr& c) {
    c >> node_namespace >> node_name;
    read_gids(c, readers);
    read_gids(c, writers);
  }
};

struct ParticipantEntitiesInfo {  // rmw_dds_common/ParticipantEntitiesInfo
  static constexpr const char* kType = "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_";
  Gid gid{};
  std::vector<NodeEntitiesInfo> nodes;
  void write(Cdr& c) const {
    c.serializeArray(gid.data(), gid.size());
    c << static_cast<std::uint32_t>(nodes.size());
    for (const auto& n : nodes) n.write(c);
  }
  void read(Cdr& c) {
    c.deserializeArray(gid.data(), gid.size());
    std::uint32_t n = 0;
    c >> n;
    nodes.resize(n);
    for (auto& node : nodes) node.read(c);
  }
};

struct LaserScan {  // sensor_msgs/LaserScan
  static constexpr const char* kType = "sensor_msgs::msg::dds_::LaserScan_";
  Header header;
  float angle_min = 0, angle_max = 0, angle_increment = 0, time_increment = 0, scan_time = 0, range_min = 0, range_max = 0;
  std::vector<float> ranges, intensities;
  void write(Cdr& c) const {
    header.write(c);
    c << angle_min << angle_max << angle_increment << time_increment << scan_time << range_min << range_max;
    c << ranges << intensities;
  }
  void read(Cdr& c) {
    header.read(c);
    c >> angle_min >> angle_max >> angle_increment >> time_increment >> scan_time >> range_min >> range_max;
    c >> ranges >> intensities;
  }
};

// A Fast DDS type support over one of the structs above: plain XCDR1, little endian, no key.
template <class T>
class HandType final : public fdds::TopicDataType {
 public:
  HandType() {
    setName(T::kType);
    m_typeSize = 4 + 1024;  // grown per sample: the size provider serialises it first
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->max_size);
    Cdr c(buffer, Cdr::LITTLE_ENDIANNESS, Cdr::DDS_CDR);
    payload->encapsulation = CDR_LE;
    c.serialize_encapsulation();
    try {
      static_cast<const T*>(data)->write(c);
    } catch (const std::exception&) {
      return false;
    }
    payload->length = static_cast<std::uint32_t>(c.getSerializedDataLength());
    return true;
  }
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->length);
    Cdr c(buffer, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR);
    try {
      c.read_encapsulation();
      static_cast<T*>(data)->read(c);
    } catch (const std::exception&) {
      return false;
    }
    return true;
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] {
      FastBuffer buffer;  // grows
      Cdr c(buffer, Cdr::LITTLE_ENDIANNESS, Cdr::DDS_CDR);
      c.serialize_encapsulation();
      static_cast<const T*>(data)->write(c);
      return static_cast<std::uint32_t>(c.getSerializedDataLength()) + 4;
    };
  }
  void* createData() override { return new T(); }
  void deleteData(void* data) override { delete static_cast<T*>(data); }
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

// --- the participant ---------------------------------------------------------------------------

const auto kStart = std::chrono::steady_clock::now();
double elapsed_ms() { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - kStart).count(); }

std::mutex out_mutex;
template <class... A>
void say(const char* format, A... a) {
  std::lock_guard lock(out_mutex);
  std::printf(format, a...);
  std::fflush(stdout);
}

// Fast DDS on loopback only, discovering by unicast the participant indices tripodal's loopback
// configuration uses (Cyclone's ParticipantIndex auto, ports 7410 + 250 * domain + 2 * index).
fdds::DomainParticipant* make_participant(std::uint32_t domain) {
  fdds::DomainParticipantQos q;
  q.name("tripodal_ros2_peer");
  q.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.emplace_back("127.0.0.1");
  q.transport().user_transports.push_back(udp);
  for (std::uint32_t i = 0; i < 32; ++i) {
    eprosima::fastrtps::rtps::Locator_t peer;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(peer, 127, 0, 0, 1);
    peer.port = 7400 + 250 * domain + 10 + 2 * i;
    q.wire_protocol().builtin.initialPeersList.push_back(peer);
  }
  return fdds::DomainParticipantFactory::get_instance()->create_participant(domain, q);
}

fdds::DataReaderQos reader_qos(fdds::ReliabilityQosPolicyKind reliability, fdds::DurabilityQosPolicyKind durability,
                               std::int32_t depth) {
  fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = reliability;
  q.durability().kind = durability;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return q;
}

// Takes every sample as it comes and hands it to `on_sample`.
template <class T>
class Listener final : public fdds::DataReaderListener {
 public:
  Listener(std::string topic, std::function<void(const T&)> on_sample) : topic_(std::move(topic)), on_sample_(std::move(on_sample)) {}
  void on_data_available(fdds::DataReader* reader) override {
    T sample;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) on_sample_(sample);
    }
  }
  void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& s) override {
    if (s.current_count_change > 0) say("matched %s after %.1f ms\n", topic_.c_str(), elapsed_ms());
  }
  void on_requested_incompatible_qos(fdds::DataReader*, const fdds::RequestedIncompatibleQosStatus& s) override {
    say("incompatible qos on %s (policy %u)\n", topic_.c_str(), static_cast<unsigned>(s.last_policy_id));
  }

 private:
  std::string topic_;
  std::function<void(const T&)> on_sample_;
};

struct Reader {
  std::unique_ptr<fdds::DataReaderListener> listener;
  fdds::DataReader* reader = nullptr;
};

template <class T>
Reader subscribe(fdds::DomainParticipant* p, fdds::Subscriber* sub, const std::string& topic, const fdds::DataReaderQos& qos,
                 std::function<void(const T&)> on_sample) {
  fdds::TypeSupport type(new HandType<T>());
  type.register_type(p);
  fdds::Topic* t = p->create_topic(topic, T::kType, fdds::TOPIC_QOS_DEFAULT);
  Reader r;
  r.listener = std::make_unique<Listener<T>>(topic, std::move(on_sample));
  r.reader = sub->create_datareader(t, qos, r.listener.get());
  return r;
}

std::string gid_text(const Gid& g) {
  std::string s;
  char b[3];
  for (const std::uint8_t v : g) {
    std::snprintf(b, sizeof b, "%02x", v);
    s += b;
  }
  return s;
}

int graph(std::uint32_t domain, const std::string& ns, int limit_s, const std::string& laser, const std::set<std::string>& nodes) {
  fdds::DomainParticipant* p = make_participant(domain);
  if (p == nullptr) return 3;
  fdds::Subscriber* sub = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  std::mutex m;
  std::set<std::string> seen;  // "tf parent child", "tf_static ...", "clock", "amcl_pose", node names
  auto note = [&](const std::string& what) {
    std::lock_guard lock(m);
    if (seen.insert(what).second) say("seen %s after %.1f ms\n", what.c_str(), elapsed_ms());
  };
  std::vector<Reader> readers;
  // rclcpp's default QoS: reliable, volatile, keep last 10; tf2's static listener: transient local.
  const auto dflt = reader_qos(fdds::RELIABLE_RELIABILITY_QOS, fdds::VOLATILE_DURABILITY_QOS, 10);
  readers.push_back(subscribe<TFMessage>(p, sub, "rt/tf", dflt, [&](const TFMessage& tf) {
    for (const auto& t : tf.transforms) note("tf " + t.header.frame_id + " " + t.child_frame_id);
  }));
  readers.push_back(subscribe<TFMessage>(
      p, sub, "rt/tf_static", reader_qos(fdds::RELIABLE_RELIABILITY_QOS, fdds::TRANSIENT_LOCAL_DURABILITY_QOS, 1),
      [&](const TFMessage& tf) {
        for (const auto& t : tf.transforms) note("tf_static " + t.header.frame_id + " " + t.child_frame_id);
      }));
  // rclcpp::ClockQoS: best effort, keep last 1.
  readers.push_back(subscribe<Clock>(p, sub, "rt/clock", reader_qos(fdds::BEST_EFFORT_RELIABILITY_QOS, fdds::VOLATILE_DURABILITY_QOS, 1),
                                     [&](const Clock&) { note("clock"); }));
  // Nav2's subscribers of amcl_pose: reliable, transient local.
  readers.push_back(subscribe<PoseWithCovarianceStamped>(
      p, sub, "rt/" + ns + "/amcl_pose", reader_qos(fdds::RELIABLE_RELIABILITY_QOS, fdds::TRANSIENT_LOCAL_DURABILITY_QOS, 1),
      [&](const PoseWithCovarianceStamped& pose) { note("amcl_pose " + pose.header.frame_id); }));
  // rmw's graph reader: reliable, transient local.
  readers.push_back(subscribe<ParticipantEntitiesInfo>(
      p, sub, "ros_discovery_info", reader_qos(fdds::RELIABLE_RELIABILITY_QOS, fdds::TRANSIENT_LOCAL_DURABILITY_QOS, 100),
      [&](const ParticipantEntitiesInfo& info) {
        for (const auto& n : info.nodes) {
          const std::string name = (n.node_namespace == "/" ? "" : n.node_namespace) + "/" + n.node_name;
          {
            std::lock_guard lock(out_mutex);
            std::printf("node %s of participant %s: %zu readers, %zu writers\n", name.c_str(), gid_text(info.gid).c_str(),
                        n.readers.size(), n.writers.size());
          }
          if (!n.writers.empty()) note("node " + name);
        }
      }));
  std::set<std::string> wanted = {"tf " + ns + "/map " + ns + "/odom", "tf " + ns + "/odom " + ns + "/base_link",
                                  "tf_static " + ns + "/base_link " + ns + "/" + laser, "clock", "amcl_pose " + ns + "/map"};
  for (const auto& n : nodes) wanted.insert("node " + n);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(limit_s);
  int rc = 3;
  while (std::chrono::steady_clock::now() < until) {
    {
      std::lock_guard lock(m);
      if (std::includes(seen.begin(), seen.end(), wanted.begin(), wanted.end())) {
        rc = 0;
        break;
      }
    }
    std::this_thread::sleep_for(10ms);
  }
  if (rc != 0) {
    std::lock_guard lock(m);
    for (const auto& w : wanted) {
      if (seen.count(w) == 0) say("missing %s\n", w.c_str());
    }
  } else {
    say("all seen after %.1f ms\n", elapsed_ms());
  }
  for (auto& r : readers) sub->delete_datareader(r.reader);
  p->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(p);
  return rc;
}

int scan(std::uint32_t domain, const std::string& topic, std::size_t beams, int count, int period_ms, bool reliable,
         int heartbeat_s) {
  fdds::DomainParticipant* p = make_participant(domain);
  if (p == nullptr) return 3;
  fdds::TypeSupport type(new HandType<LaserScan>());
  type.register_type(p);
  fdds::Topic* t = p->create_topic("rt/" + topic.substr(topic.front() == '/' ? 1 : 0), LaserScan::kType, fdds::TOPIC_QOS_DEFAULT);
  fdds::Publisher* pub = p->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
  q.reliability().kind = reliable ? fdds::RELIABLE_RELIABILITY_QOS : fdds::BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind = fdds::VOLATILE_DURABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = 10;
  q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  q.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(heartbeat_s, 0);
  fdds::DataWriter* w = pub->create_datawriter(t, q);
  if (w == nullptr) return 3;
  const auto until = std::chrono::steady_clock::now() + 20s;
  fdds::PublicationMatchedStatus status;
  while (w->get_publication_matched_status(status) == ReturnCode_t::RETCODE_OK && status.current_count == 0) {
    if (std::chrono::steady_clock::now() > until) return 3;
    std::this_thread::sleep_for(2ms);
  }
  say("matched after %.1f ms\n", elapsed_ms());
  LaserScan s;
  s.header.frame_id = "laser";
  s.angle_min = -3.14159265F;
  s.angle_increment = 6.28318531F / static_cast<float>(beams);
  s.angle_max = s.angle_min + s.angle_increment * static_cast<float>(beams - 1);
  s.scan_time = static_cast<float>(period_ms) / 1000.0F;
  s.range_min = 0.05F;
  s.range_max = 30.0F;
  s.ranges.resize(beams);
  s.intensities.resize(beams);
  for (int k = 0; k < count; ++k) {
    for (std::size_t i = 0; i < beams; ++i) {
      s.ranges[i] = 1.0F + static_cast<float>(k) + static_cast<float>(i) / static_cast<float>(beams);
      s.intensities[i] = static_cast<float>(k);
    }
    const auto now = std::chrono::system_clock::now().time_since_epoch();
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(now).count();
    s.header.stamp = {static_cast<std::int32_t>(ns / 1'000'000'000), static_cast<std::uint32_t>(ns % 1'000'000'000)};
    w->write(&s);
    std::this_thread::sleep_for(std::chrono::milliseconds(period_ms));
  }
  if (reliable) w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(5, 0));
  p->delete_contained_entities();
  fdds::DomainParticipantFactory::get_instance()->delete_participant(p);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "graph" && argc >= 6) {
      const std::set<std::string> nodes(argv + 6, argv + argc);
      return graph(static_cast<std::uint32_t>(std::stoul(argv[2])), argv[3], std::stoi(argv[4]), argv[5], nodes);
    }
    if (mode == "scan" && argc == 9) {
      return scan(static_cast<std::uint32_t>(std::stoul(argv[2])), argv[3], std::stoul(argv[4]), std::stoi(argv[5]),
                  std::stoi(argv[6]), std::string(argv[7]) == "reliable", std::stoi(argv[8]));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tripodal_ros2_peer: %s\n", e.what());
    return 2;
  }
  std::fprintf(stderr, "usage: tripodal_ros2_peer graph <domain> <namespace> <limit_s> <laser_frame> <node>... | "
                       "scan <domain> <topic> <beams> <count> <period_ms> <reliable|best_effort> <heartbeat_s>\n");
  return 2;
}
