// The bytes Cyclone DDS puts on the wire for every message type, compared with the bytes computed
// by hand from the ROS 2 definitions and the XCDR1 rules (what rmw_cyclonedds writes and reads).
#include <catch2/catch.hpp>

#include <cstdio>
#include <string>
#include <thread>

#include "dds_test_support.hpp"
#include "tripodal/dds/endpoint.hpp"

using namespace tripodal::dds;
using namespace tripodal::dds::test;

namespace {

std::string hex(const std::vector<std::uint8_t>& bytes) {
  std::string out;
  char buf[4];
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%02x", bytes[i]);
    out += buf;
    out += (i % 16 == 15) ? '\n' : ' ';
  }
  return out;
}

// Writes the message and takes it back serialised, as the writer's serialiser produced it.
template <class T>
std::vector<std::uint8_t> wire_bytes(Participant& p, const T& message) {
  const std::string topic = ros_topic(std::string(MessageType<T>::ros.substr(MessageType<T>::ros.rfind('/') + 1)),
                                      test_namespace());
  Subscriber<T> sub(p, topic, {.kind = TopicKind::state});
  Publisher<T> pub(p, topic, {.kind = TopicKind::state});
  REQUIRE(pub.wait_for_subscribers(1, std::chrono::seconds(5)));
  pub.publish(message);
  for (int i = 0; i < 500; ++i) {
    auto taken = sub.take_serialized(1);
    if (!taken.empty()) return taken.front();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  FAIL("no sample of " << MessageType<T>::dds << " came back");
  return {};
}

// Cyclone pads the payload to a multiple of 4 and says how many bytes it added in the low two bits
// of the options (XTypes 1.3, 7.6.3.1.2); a reader skips them. The hand-computed bytes carry no
// padding; the comparison adds what Cyclone adds, and checks it is only zeros and the count.
std::vector<std::uint8_t> as_cyclone_pads(std::vector<std::uint8_t> expected, const std::vector<std::uint8_t>& wire) {
  const std::size_t pad = (4 - (expected.size() - 4) % 4) % 4;
  if (wire.size() == expected.size() + pad && pad > 0 && wire[3] == pad) {
    expected.resize(expected.size() + pad, 0);
    expected[3] = static_cast<std::uint8_t>(pad);
  }
  return expected;
}

template <class T>
void check_golden(Participant& p, const T& message, const std::vector<std::uint8_t>& expected) {
  const auto wire = wire_bytes(p, message);
  INFO(MessageType<T>::dds << "\nwire:\n" << hex(wire) << "\nexpected:\n" << hex(expected));
  REQUIRE(wire.size() >= 4);
  CHECK(wire[0] == 0x00);  // CDR_LE: XCDR1, little endian, as ROS 2 writes
  CHECK(wire[1] == 0x01);
  CHECK(wire == as_cyclone_pads(expected, wire));
}

}  // namespace

TEST_CASE("dds: the type names are those ROS 2 registers", "[dds]") {
  CHECK(MessageType<msg::Twist>::dds == "geometry_msgs::msg::dds_::Twist_");
  CHECK(MessageType<msg::Twist>::ros == "geometry_msgs/msg/Twist");
  CHECK(MessageType<msg::Odometry>::dds == "nav_msgs::msg::dds_::Odometry_");
  CHECK(MessageType<msg::LaserScan>::dds == "sensor_msgs::msg::dds_::LaserScan_");
  CHECK(MessageType<msg::OccupancyGrid>::dds == "nav_msgs::msg::dds_::OccupancyGrid_");
  CHECK(MessageType<msg::PoseWithCovarianceStamped>::dds == "geometry_msgs::msg::dds_::PoseWithCovarianceStamped_");
  CHECK(MessageType<msg::String>::dds == "std_msgs::msg::dds_::String_");
  CHECK(MessageType<msg::Event>::dds == "tripodal_msgs::msg::dds_::Event_");
  CHECK(MessageType<msg::JointState>::dds == "sensor_msgs::msg::dds_::JointState_");
  CHECK(MessageType<msg::Clock>::dds == "rosgraph_msgs::msg::dds_::Clock_");
  CHECK(MessageType<msg::SimStep>::dds == "tripodal_msgs::msg::dds_::SimStep_");
  CHECK(MessageType<msg::SimState>::dds == "tripodal_msgs::msg::dds_::SimState_");
  CHECK(MessageType<msg::TFMessage>::dds == "tf2_msgs::msg::dds_::TFMessage_");
  CHECK(MessageType<msg::Imu>::dds == "sensor_msgs::msg::dds_::Imu_");
  CHECK(MessageType<msg::ParticipantEntitiesInfo>::dds == "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_");
  CHECK(ros_topic("cmd_vel") == "rt/cmd_vel");
  CHECK(ros_topic("/cmd_vel", "/robot1/") == "rt/robot1/cmd_vel");
  CHECK(ros_seconds(ros_time(-1.25)) == Approx(-1.25));
  CHECK(ros_time(-1.25).sec == -2);
  CHECK(ros_time(-1.25).nanosec == 750000000U);
  // A tripodal Time converts to the nanosecond, both ways.
  const tripodal::Time t{std::chrono::nanoseconds(-1'250'000'001)};
  CHECK(ros_time(t) == msg::Time{-2, 749'999'999});
  CHECK(tripodal_time(ros_time(t)) == t);
  CHECK(tripodal_time(msg::Time{78, 900'000'000}) == tripodal::Time{std::chrono::milliseconds(78'900)});
}

TEST_CASE("dds: golden CDR bytes of every message type", "[dds]") {
  Participant p(test_options(0));

  SECTION("std_msgs/String, written out byte by byte") {
    // header | length 15 (14 characters and the NUL) | "hello tripodal\0"
    const std::vector<std::uint8_t> expected{0x00, 0x01, 0x00, 0x00, 0x0f, 0x00, 0x00, 0x00, 'h', 'e', 'l', 'l',
                                             'o',  ' ',  't',  'r',  'i',  'p',  'o',  'd',  'a', 'l', 0x00};
    check_golden(p, sample_string(), expected);
  }
  SECTION("geometry_msgs/Twist, written out byte by byte") {
    // six float64: 0.35, -0.05, 0, 0, 0, 0.7 (IEEE 754, little endian); no padding after the header
    const std::vector<std::uint8_t> expected{
        0x00, 0x01, 0x00, 0x00,                          //
        0x66, 0x66, 0x66, 0x66, 0x66, 0x66, 0xd6, 0x3f,  // 0.35
        0x9a, 0x99, 0x99, 0x99, 0x99, 0x99, 0xa9, 0xbf,  // -0.05
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // 0
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // 0
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // 0
        0x66, 0x66, 0x66, 0x66, 0x66, 0x66, 0xe6, 0x3f,  // 0.7
    };
    check_golden(p, sample_twist(), expected);
  }
  SECTION("geometry_msgs/PoseWithCovarianceStamped") {
    const auto m = sample_pose();
    // header: sec, nanosec, "map" (4 + 4 bytes) end at 16; the pose's doubles align to 16: no gap
    check_golden(p, m, CdrWriter().header(m.header).pose(m.pose.pose).f64s(m.pose.covariance).bytes());
  }
  SECTION("nav_msgs/Odometry") {
    const auto m = sample_odometry();
    // "odom" ends at 17, "base_link" aligns to 20 and ends at 34, the pose aligns to 40
    check_golden(p, m,
                 CdrWriter()
                     .header(m.header)
                     .str(m.child_frame_id)
                     .pose(m.pose.pose)
                     .f64s(m.pose.covariance)
                     .twist(m.twist.twist)
                     .f64s(m.twist.covariance)
                     .bytes());
  }
  SECTION("sensor_msgs/LaserScan") {
    const auto m = sample_scan();
    CdrWriter w;
    w.header(m.header).f32(m.angle_min).f32(m.angle_max).f32(m.angle_increment).f32(m.time_increment);
    w.f32(m.scan_time).f32(m.range_min).f32(m.range_max);
    w.u32(static_cast<std::uint32_t>(m.ranges.size()));
    for (float r : m.ranges) w.f32(r);
    w.u32(static_cast<std::uint32_t>(m.intensities.size()));
    for (float r : m.intensities) w.f32(r);
    check_golden(p, m, w.bytes());
  }
  SECTION("sensor_msgs/JointState") {
    const auto m = sample_joint_state();
    // "base" ends at 17; the names' count aligns to 20, each name to 4; the doubles to 8
    CdrWriter w;
    w.header(m.header).u32(static_cast<std::uint32_t>(m.name.size()));
    for (const std::string& n : m.name) w.str(n);
    for (const auto* v : {&m.position, &m.velocity, &m.effort}) w.u32(static_cast<std::uint32_t>(v->size())).f64s(*v);
    check_golden(p, m, w.bytes());
  }
  SECTION("rosgraph_msgs/Clock") {
    const msg::Clock m{{78, 900000000}};
    check_golden(p, m, CdrWriter().time(m.clock).bytes());
  }
  SECTION("tf2_msgs/TFMessage") {
    msg::TFMessage m;
    m.transforms.push_back({{{12, 5}, "psr2/odom"}, "psr2/base_link", {{1.5, -2.0, 0.0}, {0.0, 0.0, 0.6, 0.8}}});
    m.transforms.push_back({{{12, 5}, "psr2/map"}, "psr2/odom", {{0.25, 0.0, 0.0}, {}}});
    // the count, then per transform: header, child frame, translation and rotation (doubles at 8)
    CdrWriter w;
    w.u32(2);
    for (const auto& t : m.transforms) {
      w.header(t.header).str(t.child_frame_id);
      w.f64(t.transform.translation.x).f64(t.transform.translation.y).f64(t.transform.translation.z);
      w.f64(t.transform.rotation.x).f64(t.transform.rotation.y).f64(t.transform.rotation.z).f64(t.transform.rotation.w);
    }
    check_golden(p, m, w.bytes());
  }
  SECTION("sensor_msgs/Imu") {
    msg::Imu m;
    m.header = {{3, 7}, "imu_link"};
    m.orientation = {0.0, 0.0, 0.6, 0.8};
    m.orientation_covariance[0] = 0.01;
    m.angular_velocity = {0.0, 0.0, 0.5};
    m.linear_acceleration = {0.1, 0.0, 9.81};
    m.linear_acceleration_covariance[8] = -1.0;
    CdrWriter w;
    w.header(m.header).f64(m.orientation.x).f64(m.orientation.y).f64(m.orientation.z).f64(m.orientation.w);
    w.f64s(m.orientation_covariance).f64(0.0).f64(0.0).f64(0.5).f64s(m.angular_velocity_covariance);
    w.f64(0.1).f64(0.0).f64(9.81).f64s(m.linear_acceleration_covariance);
    check_golden(p, m, w.bytes());
  }
  SECTION("rmw_dds_common/ParticipantEntitiesInfo") {
    msg::ParticipantEntitiesInfo m;
    for (std::uint8_t i = 0; i < 16; ++i) m.gid[i] = i;
    msg::Gid reader{};
    reader.fill(0xaa);
    m.node_entities_info_seq.push_back({"/psr2", "tripodal", {reader}, {}});
    // the gid's 16 bytes, the node count, the two names (bounded strings are written as strings),
    // one reader gid, no writer gid
    CdrWriter w;
    for (const auto b : m.gid) w.u8(b);
    w.u32(1).str("/psr2").str("tripodal").u32(1);
    for (const auto b : reader) w.u8(b);
    w.u32(0);
    check_golden(p, m, w.bytes());
  }
  SECTION("nav_msgs/OccupancyGrid") {
    const auto m = sample_grid();
    CdrWriter w;
    w.header(m.header).time(m.info.map_load_time).f32(m.info.resolution).u32(m.info.width).u32(m.info.height);
    w.pose(m.info.origin).u32(static_cast<std::uint32_t>(m.data.size()));
    for (std::int8_t c : m.data) w.i8(c);
    check_golden(p, m, w.bytes());
  }
  SECTION("tripodal_msgs/Event and TaskCommand") {
    const auto e = sample_event();
    check_golden(p, e,
                 CdrWriter().time(e.stamp).str(e.robot).str(e.source).str(e.kind).str(e.detail).u8(e.severity).bytes());
    const auto t = sample_task();
    check_golden(p, t, CdrWriter().time(t.stamp).str(t.robot).u32(t.id).str(t.command).str(t.task).bytes());
  }
  SECTION("tripodal_msgs/SimStep and SimState") {
    const auto s = sample_sim_step();
    // the twist's doubles align to 8 right after the 8-byte time
    // then the joints' targets: the length, then a double aligned to 8
    check_golden(p, s, CdrWriter().time(s.until).twist(s.cmd_vel).u32(s.step).u32(1).f64(s.joint_targets[0]).bytes());
    const auto t = sample_sim_state();
    check_golden(p, t,
                 CdrWriter()
                     .time(t.stamp)
                     .f64(t.x)
                     .f64(t.y)
                     .f64(t.theta)
                     .f64(t.distance)
                     .u32(t.step)
                     .u32(t.scans)
                     .u32(t.joint_states)
                     .u32(t.collisions)
                     // the sensors: doubles at offset 56 (aligned), four uint32 (the charging flag
                     // one of them), then the cliff sequence: its length and its three bytes
                     .f64(t.gyro_yaw_rate)
                     .f64(t.gyro_yaw)
                     .f64(t.battery_voltage)
                     .f64(t.battery_current)
                     .f64(t.battery_percentage)
                     .u32(t.bumpers_pressed)
                     .u32(t.bumper_count)
                     .u32(t.sensors)
                     .u32(t.battery_charging ? 1 : 0)
                     .u32(3)
                     .u8(0)
                     .u8(1)
                     .u8(0)
                     // the joints (names, then a double each aligned to 8) and the buttons pressed
                     .u32(1)
                     .str("neck")
                     .u32(1)
                     .f64(t.joint_position[0])
                     .u32(1)
                     .f64(t.joint_velocity[0])
                     .u32(1)
                     .f64(t.joint_target[0])
                     .u32(2)
                     .str("hello")
                     .str("help")
                     .bytes());
  }
}
