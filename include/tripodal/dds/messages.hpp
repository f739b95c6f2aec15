// The messages tripodal exchanges over DDS, as plain C++ values (tripodal::dds area, optional;
// docs/distribution.md): the ROS 2 messages it speaks and its own event and task topics.
#pragma once

#include <array>
#include <concepts>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/time.hpp"

namespace tripodal::dds {

// Field names, order and types follow the ROS 2 message definitions (the CDR bytes depend on
// order and types only). Defaults are ROS 2's (zero, identity quaternion).
namespace msg {

struct Time {  // builtin_interfaces/Time
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  bool operator==(const Time&) const = default;
};

struct Header {  // std_msgs/Header
  Time stamp;
  std::string frame_id;
  bool operator==(const Header&) const = default;
};

struct String {  // std_msgs/String
  std::string data;
  bool operator==(const String&) const = default;
};

struct Vector3 {  // geometry_msgs/Vector3
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  bool operator==(const Vector3&) const = default;
};

struct Point {  // geometry_msgs/Point
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  bool operator==(const Point&) const = default;
};

struct Quaternion {  // geometry_msgs/Quaternion
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  double w = 1.0;
  bool operator==(const Quaternion&) const = default;
};

struct Pose {  // geometry_msgs/Pose
  Point position;
  Quaternion orientation;
  bool operator==(const Pose&) const = default;
};

struct PoseWithCovariance {  // geometry_msgs/PoseWithCovariance; row-major 6x6 (x y z rotX rotY rotZ)
  Pose pose;
  std::array<double, 36> covariance{};
  bool operator==(const PoseWithCovariance&) const = default;
};

struct PoseWithCovarianceStamped {  // geometry_msgs/PoseWithCovarianceStamped
  Header header;
  PoseWithCovariance pose;
  bool operator==(const PoseWithCovarianceStamped&) const = default;
};

struct Twist {  // geometry_msgs/Twist
  Vector3 linear;
  Vector3 angular;
  bool operator==(const Twist&) const = default;
};

struct TwistWithCovariance {  // geometry_msgs/TwistWithCovariance
  Twist twist;
  std::array<double, 36> covariance{};
  bool operator==(const TwistWithCovariance&) const = default;
};

struct Transform {  // geometry_msgs/Transform
  Vector3 translation;
  Quaternion rotation;
  bool operator==(const Transform&) const = default;
};

// geometry_msgs/TransformStamped: parent_from_child, the parent being header.frame_id (tf2's way).
struct TransformStamped {
  Header header;
  std::string child_frame_id;
  Transform transform;
  bool operator==(const TransformStamped&) const = default;
};

struct TFMessage {  // tf2_msgs/TFMessage: what /tf and /tf_static carry
  std::vector<TransformStamped> transforms;
  bool operator==(const TFMessage&) const = default;
};

struct Imu {  // sensor_msgs/Imu; covariance row-major 3x3, element 0 = -1: that field is not given
  Header header;
  Quaternion orientation;
  std::array<double, 9> orientation_covariance{};
  Vector3 angular_velocity;  // rad/s
  std::array<double, 9> angular_velocity_covariance{};
  Vector3 linear_acceleration;  // m/s^2
  std::array<double, 9> linear_acceleration_covariance{};
  bool operator==(const Imu&) const = default;
};

// rmw_dds_common/Gid: a DDS entity's GUID (16 bytes; ROS 2 Iron and later).
using Gid = std::array<std::uint8_t, 16>;

struct NodeEntitiesInfo {  // rmw_dds_common/NodeEntitiesInfo; names at most 256 characters
  std::string node_namespace;
  std::string node_name;
  std::vector<Gid> reader_gid_seq;
  std::vector<Gid> writer_gid_seq;
  bool operator==(const NodeEntitiesInfo&) const = default;
};

// rmw_dds_common/ParticipantEntitiesInfo: the ROS 2 nodes of one DDS participant (ros_discovery_info).
struct ParticipantEntitiesInfo {
  Gid gid{};
  std::vector<NodeEntitiesInfo> node_entities_info_seq;
  bool operator==(const ParticipantEntitiesInfo&) const = default;
};

struct Odometry {  // nav_msgs/Odometry
  Header header;
  std::string child_frame_id;
  PoseWithCovariance pose;
  TwistWithCovariance twist;
  bool operator==(const Odometry&) const = default;
};

struct LaserScan {  // sensor_msgs/LaserScan
  Header header;
  float angle_min = 0.0F;
  float angle_max = 0.0F;
  float angle_increment = 0.0F;
  float time_increment = 0.0F;
  float scan_time = 0.0F;
  float range_min = 0.0F;
  float range_max = 0.0F;
  std::vector<float> ranges;
  std::vector<float> intensities;
  bool operator==(const LaserScan&) const = default;
};

struct JointState {  // sensor_msgs/JointState; position, velocity, effort empty or as long as name
  Header header;
  std::vector<std::string> name;
  std::vector<double> position;
  std::vector<double> velocity;
  std::vector<double> effort;
  bool operator==(const JointState&) const = default;
};

struct Clock {  // rosgraph_msgs/Clock: the simulated time (ROS 2's use_sim_time)
  Time clock;
  bool operator==(const Clock&) const = default;
};

struct MapMetaData {  // nav_msgs/MapMetaData
  Time map_load_time;
  float resolution = 0.0F;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  Pose origin;
  bool operator==(const MapMetaData&) const = default;
};

struct OccupancyGrid {  // nav_msgs/OccupancyGrid; data row-major from origin, -1 unknown, 0..100
  Header header;
  MapMetaData info;
  std::vector<std::int8_t> data;
  bool operator==(const OccupancyGrid&) const = default;
};

// tripodal_msgs/Event: something that happened in a robot (a fault, a silent peer, a task's end).
struct Event {
  Time stamp;
  std::string robot;
  std::string source;
  std::string kind;
  std::string detail;
  std::uint8_t severity = 0;  // 0 info, 1 warning, 2 error
  bool operator==(const Event&) const = default;
};

// tripodal_msgs/TaskCommand: a task given to a robot's planner.
struct TaskCommand {
  Time stamp;
  std::string robot;  // empty: any robot
  std::uint32_t id = 0;
  std::string command;  // start, cancel, pause, resume
  std::string task;
  bool operator==(const TaskCommand&) const = default;
};

// tripodal_msgs/SimStep: lock-step co-simulation, the robot's request to advance the simulator to
// `until` with the base driven by `cmd_vel` (tripodal sim-server).
struct SimStep {
  Time until;
  Twist cmd_vel;
  std::uint32_t step = 0;  // from 1
  // The joints' targets (rad) in the order of SimState::joint_names; empty: unchanged.
  std::vector<double> joint_targets;
  bool operator==(const SimStep&) const = default;
};

// tripodal_msgs/SimState: the simulator after a step: its time, its ground truth for the run's
// measures, the last step done and the samples published so far on scan and joint_states.
struct SimState {
  Time stamp;
  double x = 0.0;  // true map_from_base (m, m, rad)
  double y = 0.0;
  double theta = 0.0;
  double distance = 0.0;  // driven so far (m)
  std::uint32_t step = 0;
  std::uint32_t scans = 0;
  std::uint32_t joint_states = 0;
  std::uint32_t collisions = 0;
  // The robot's other simulated sensors after the step, those `sensors` flags (kSimGyro, ...):
  // what the hardware dds hands the robot as its gyro, bumpers, cliff and battery resources.
  double gyro_yaw_rate = 0.0;  // rad/s
  double gyro_yaw = 0.0;       // rad
  double battery_voltage = 0.0;
  double battery_current = 0.0;       // A, positive when charging
  double battery_percentage = 0.0;    // 0..1
  std::uint32_t bumpers_pressed = 0;  // bit i: bumper i
  std::uint32_t bumper_count = 0;
  std::uint32_t sensors = 0;
  bool battery_charging = false;    // a uint32 on the wire (no padding before the sequence)
  std::vector<std::uint8_t> cliff;  // 1: a cliff under sensor i
  // The robot's joints after the step (its world's, in order) and the LED buttons pressed during
  // it (names, oldest first): the hardware dds's joint resources and button panel.
  std::vector<std::string> joint_names;
  std::vector<double> joint_position;  // rad
  std::vector<double> joint_velocity;  // rad/s
  std::vector<double> joint_target;    // rad
  std::vector<std::string> button_presses;
  bool operator==(const SimState&) const = default;
};

// SimState::sensors' flags: the sensors the simulator's world gives the robot.
inline constexpr std::uint32_t kSimGyro = 1, kSimBumpers = 2, kSimCliff = 4, kSimBattery = 8;

}  // namespace msg

// The names a message type has: `ros` as ROS 2 tools print it, `dds` as ROS 2 registers it with
// DDS (what a topic's type name must be for a ROS 2 node to match it).
template <class T>
struct MessageType;

#define TRIPODAL_DDS_MESSAGE_TYPE(Type, package, name)                              \
  template <>                                                                       \
  struct MessageType<msg::Type> {                                                   \
    static constexpr std::string_view ros = package "/msg/" name;                   \
    static constexpr std::string_view dds = package "::msg::dds_::" name "_";       \
  }
TRIPODAL_DDS_MESSAGE_TYPE(String, "std_msgs", "String");
TRIPODAL_DDS_MESSAGE_TYPE(Twist, "geometry_msgs", "Twist");
TRIPODAL_DDS_MESSAGE_TYPE(PoseWithCovarianceStamped, "geometry_msgs", "PoseWithCovarianceStamped");
TRIPODAL_DDS_MESSAGE_TYPE(Odometry, "nav_msgs", "Odometry");
TRIPODAL_DDS_MESSAGE_TYPE(OccupancyGrid, "nav_msgs", "OccupancyGrid");
TRIPODAL_DDS_MESSAGE_TYPE(LaserScan, "sensor_msgs", "LaserScan");
TRIPODAL_DDS_MESSAGE_TYPE(JointState, "sensor_msgs", "JointState");
TRIPODAL_DDS_MESSAGE_TYPE(Clock, "rosgraph_msgs", "Clock");
TRIPODAL_DDS_MESSAGE_TYPE(TFMessage, "tf2_msgs", "TFMessage");
TRIPODAL_DDS_MESSAGE_TYPE(Imu, "sensor_msgs", "Imu");
TRIPODAL_DDS_MESSAGE_TYPE(ParticipantEntitiesInfo, "rmw_dds_common", "ParticipantEntitiesInfo");
TRIPODAL_DDS_MESSAGE_TYPE(Event, "tripodal_msgs", "Event");
TRIPODAL_DDS_MESSAGE_TYPE(TaskCommand, "tripodal_msgs", "TaskCommand");
TRIPODAL_DDS_MESSAGE_TYPE(SimStep, "tripodal_msgs", "SimStep");
TRIPODAL_DDS_MESSAGE_TYPE(SimState, "tripodal_msgs", "SimState");
#undef TRIPODAL_DDS_MESSAGE_TYPE

// A type that can be published: one of the above (the transport instantiates exactly these).
template <class T>
concept Message = requires {
  { MessageType<T>::dds } -> std::convertible_to<std::string_view>;
};

// The time of a message from seconds (ROS 2's convention: nanosec in [0, 1e9)).
msg::Time ros_time(double seconds);
double ros_seconds(const msg::Time& t);
// The same to and from a tripodal Time, to the nanosecond (lock-step co-simulation compares them).
msg::Time ros_time(Time t);
Time tripodal_time(const msg::Time& t);

}  // namespace tripodal::dds
