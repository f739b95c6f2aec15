// Private to the dds area: how each C++ message of messages.hpp maps onto the C type idlc
// generated from the IDL, in both directions.
#pragma once

#include <dds/dds.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "ros2_messages.h"
#include "tripodal/dds/messages.hpp"
#include "tripodal_messages.h"

namespace tripodal::dds::detail {

// Writing builds a C view of the C++ message, pointing into its strings and vectors: dds_write
// only reads the sample, so nothing is copied before serialisation. The const_casts only satisfy
// the C types' non-const pointers.
inline char* view(const std::string& s) { return const_cast<char*>(s.c_str()); }
inline std::string text(const char* s) { return s != nullptr ? std::string(s) : std::string(); }

template <class Seq, class V>
Seq view_sequence(const std::vector<V>& v) {
  Seq s{};
  s._maximum = static_cast<uint32_t>(v.size());
  s._length = static_cast<uint32_t>(v.size());
  s._buffer = const_cast<V*>(v.data());
  s._release = false;
  return s;
}
template <class V, class Seq>
std::vector<V> copy_sequence(const Seq& s) {
  if (s._buffer == nullptr) return {};
  return std::vector<V>(s._buffer, s._buffer + s._length);
}

inline builtin_interfaces_msg_dds__Time_ to_c(const msg::Time& t) { return {t.sec, t.nanosec}; }
inline msg::Time from_c(const builtin_interfaces_msg_dds__Time_& t) { return {t.sec, t.nanosec}; }

inline std_msgs_msg_dds__Header_ to_c(const msg::Header& h) { return {to_c(h.stamp), view(h.frame_id)}; }
inline msg::Header from_c(const std_msgs_msg_dds__Header_& h) { return {from_c(h.stamp), text(h.frame_id)}; }

inline geometry_msgs_msg_dds__Vector3_ to_c(const msg::Vector3& v) { return {v.x, v.y, v.z}; }
inline msg::Vector3 from_c(const geometry_msgs_msg_dds__Vector3_& v) { return {v.x, v.y, v.z}; }

inline geometry_msgs_msg_dds__Pose_ to_c(const msg::Pose& p) {
  return {{p.position.x, p.position.y, p.position.z},
          {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w}};
}
inline msg::Pose from_c(const geometry_msgs_msg_dds__Pose_& p) {
  return {{p.position.x, p.position.y, p.position.z},
          {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w}};
}

inline geometry_msgs_msg_dds__PoseWithCovariance_ to_c(const msg::PoseWithCovariance& p) {
  geometry_msgs_msg_dds__PoseWithCovariance_ c{};
  c.pose = to_c(p.pose);
  std::copy(p.covariance.begin(), p.covariance.end(), c.covariance);
  return c;
}
inline msg::PoseWithCovariance from_c(const geometry_msgs_msg_dds__PoseWithCovariance_& c) {
  msg::PoseWithCovariance p;
  p.pose = from_c(c.pose);
  std::copy(std::begin(c.covariance), std::end(c.covariance), p.covariance.begin());
  return p;
}

inline geometry_msgs_msg_dds__Twist_ to_c(const msg::Twist& t) { return {to_c(t.linear), to_c(t.angular)}; }
inline msg::Twist from_c(const geometry_msgs_msg_dds__Twist_& t) { return {from_c(t.linear), from_c(t.angular)}; }

inline geometry_msgs_msg_dds__TwistWithCovariance_ to_c(const msg::TwistWithCovariance& t) {
  geometry_msgs_msg_dds__TwistWithCovariance_ c{};
  c.twist = to_c(t.twist);
  std::copy(t.covariance.begin(), t.covariance.end(), c.covariance);
  return c;
}
inline msg::TwistWithCovariance from_c(const geometry_msgs_msg_dds__TwistWithCovariance_& c) {
  msg::TwistWithCovariance t;
  t.twist = from_c(c.twist);
  std::copy(std::begin(c.covariance), std::end(c.covariance), t.covariance.begin());
  return t;
}

// TypeSupport<T>: the generated C type and descriptor of a message, and its conversions.
template <class T>
struct TypeSupport;

template <>
struct TypeSupport<msg::String> {
  using C = std_msgs_msg_dds__String_;
  static const dds_topic_descriptor_t* descriptor() { return &std_msgs_msg_dds__String__desc; }
  static C to_c(const msg::String& m) { return {view(m.data)}; }
  static msg::String from_c(const C& c) { return {text(c.data)}; }
};

template <>
struct TypeSupport<msg::Twist> {
  using C = geometry_msgs_msg_dds__Twist_;
  static const dds_topic_descriptor_t* descriptor() { return &geometry_msgs_msg_dds__Twist__desc; }
  static C to_c(const msg::Twist& m) { return detail::to_c(m); }
  static msg::Twist from_c(const C& c) { return detail::from_c(c); }
};

template <>
struct TypeSupport<msg::PoseWithCovarianceStamped> {
  using C = geometry_msgs_msg_dds__PoseWithCovarianceStamped_;
  static const dds_topic_descriptor_t* descriptor() { return &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc; }
  static C to_c(const msg::PoseWithCovarianceStamped& m) { return {detail::to_c(m.header), detail::to_c(m.pose)}; }
  static msg::PoseWithCovarianceStamped from_c(const C& c) { return {detail::from_c(c.header), detail::from_c(c.pose)}; }
};

template <>
struct TypeSupport<msg::Odometry> {
  using C = nav_msgs_msg_dds__Odometry_;
  static const dds_topic_descriptor_t* descriptor() { return &nav_msgs_msg_dds__Odometry__desc; }
  static C to_c(const msg::Odometry& m) {
    return {detail::to_c(m.header), view(m.child_frame_id), detail::to_c(m.pose), detail::to_c(m.twist)};
  }
  static msg::Odometry from_c(const C& c) {
    return {detail::from_c(c.header), text(c.child_frame_id), detail::from_c(c.pose), detail::from_c(c.twist)};
  }
};

template <>
struct TypeSupport<msg::LaserScan> {
  using C = sensor_msgs_msg_dds__LaserScan_;
  static const dds_topic_descriptor_t* descriptor() { return &sensor_msgs_msg_dds__LaserScan__desc; }
  static C to_c(const msg::LaserScan& m) {
    return {detail::to_c(m.header), m.angle_min, m.angle_max, m.angle_increment, m.time_increment,
            m.scan_time, m.range_min, m.range_max, view_sequence<dds_sequence_float>(m.ranges),
            view_sequence<dds_sequence_float>(m.intensities)};
  }
  static msg::LaserScan from_c(const C& c) {
    return {detail::from_c(c.header), c.angle_min, c.angle_max, c.angle_increment, c.time_increment,
            c.scan_time, c.range_min, c.range_max, copy_sequence<float>(c.ranges),
            copy_sequence<float>(c.intensities)};
  }
};

template <>
struct TypeSupport<msg::JointState> {
  using C = sensor_msgs_msg_dds__JointState_;
  using Scratch = std::vector<char*>;  // the names' pointers, alive until the write returns
  static const dds_topic_descriptor_t* descriptor() { return &sensor_msgs_msg_dds__JointState__desc; }
  static C to_c(const msg::JointState& m, Scratch& names) {
    names.clear();
    for (const std::string& n : m.name) names.push_back(view(n));
    return {detail::to_c(m.header), view_sequence<dds_sequence_string>(names), view_sequence<dds_sequence_double>(m.position),
            view_sequence<dds_sequence_double>(m.velocity), view_sequence<dds_sequence_double>(m.effort)};
  }
  static msg::JointState from_c(const C& c) {
    msg::JointState m{detail::from_c(c.header), {}, copy_sequence<double>(c.position), copy_sequence<double>(c.velocity),
                      copy_sequence<double>(c.effort)};
    if (c.name._buffer != nullptr) {
      for (std::uint32_t i = 0; i < c.name._length; ++i) m.name.push_back(text(c.name._buffer[i]));
    }
    return m;
  }
};

template <>
struct TypeSupport<msg::Clock> {
  using C = rosgraph_msgs_msg_dds__Clock_;
  static const dds_topic_descriptor_t* descriptor() { return &rosgraph_msgs_msg_dds__Clock__desc; }
  static C to_c(const msg::Clock& m) { return {detail::to_c(m.clock)}; }
  static msg::Clock from_c(const C& c) { return {detail::from_c(c.clock)}; }
};

inline geometry_msgs_msg_dds__Quaternion_ to_c(const msg::Quaternion& q) { return {q.x, q.y, q.z, q.w}; }
inline msg::Quaternion from_c(const geometry_msgs_msg_dds__Quaternion_& q) { return {q.x, q.y, q.z, q.w}; }

inline geometry_msgs_msg_dds__TransformStamped_ to_c(const msg::TransformStamped& t) {
  return {detail::to_c(t.header), view(t.child_frame_id),
          {detail::to_c(t.transform.translation), detail::to_c(t.transform.rotation)}};
}
inline msg::TransformStamped from_c(const geometry_msgs_msg_dds__TransformStamped_& c) {
  return {detail::from_c(c.header), text(c.child_frame_id),
          {detail::from_c(c.transform.translation), detail::from_c(c.transform.rotation)}};
}

template <>
struct TypeSupport<msg::TFMessage> {
  using C = tf2_msgs_msg_dds__TFMessage_;
  using Scratch = std::vector<geometry_msgs_msg_dds__TransformStamped_>;
  static const dds_topic_descriptor_t* descriptor() { return &tf2_msgs_msg_dds__TFMessage__desc; }
  static C to_c(const msg::TFMessage& m, Scratch& transforms) {
    transforms.clear();
    for (const msg::TransformStamped& t : m.transforms) transforms.push_back(detail::to_c(t));
    return {view_sequence<dds_sequence_geometry_msgs_msg_dds__TransformStamped_>(transforms)};
  }
  static msg::TFMessage from_c(const C& c) {
    msg::TFMessage m;
    if (c.transforms._buffer != nullptr) {
      for (std::uint32_t i = 0; i < c.transforms._length; ++i) m.transforms.push_back(detail::from_c(c.transforms._buffer[i]));
    }
    return m;
  }
};

template <>
struct TypeSupport<msg::Imu> {
  using C = sensor_msgs_msg_dds__Imu_;
  static const dds_topic_descriptor_t* descriptor() { return &sensor_msgs_msg_dds__Imu__desc; }
  static C to_c(const msg::Imu& m) {
    C c{};
    c.header = detail::to_c(m.header);
    c.orientation = detail::to_c(m.orientation);
    std::copy(m.orientation_covariance.begin(), m.orientation_covariance.end(), c.orientation_covariance);
    c.angular_velocity = detail::to_c(m.angular_velocity);
    std::copy(m.angular_velocity_covariance.begin(), m.angular_velocity_covariance.end(), c.angular_velocity_covariance);
    c.linear_acceleration = detail::to_c(m.linear_acceleration);
    std::copy(m.linear_acceleration_covariance.begin(), m.linear_acceleration_covariance.end(), c.linear_acceleration_covariance);
    return c;
  }
  static msg::Imu from_c(const C& c) {
    msg::Imu m;
    m.header = detail::from_c(c.header);
    m.orientation = detail::from_c(c.orientation);
    std::copy(std::begin(c.orientation_covariance), std::end(c.orientation_covariance), m.orientation_covariance.begin());
    m.angular_velocity = detail::from_c(c.angular_velocity);
    std::copy(std::begin(c.angular_velocity_covariance), std::end(c.angular_velocity_covariance), m.angular_velocity_covariance.begin());
    m.linear_acceleration = detail::from_c(c.linear_acceleration);
    std::copy(std::begin(c.linear_acceleration_covariance), std::end(c.linear_acceleration_covariance),
              m.linear_acceleration_covariance.begin());
    return m;
  }
};

// The graph's message holds fixed-size names and gid structs: copied into the scratch, which
// lives until the write returns.
template <>
struct TypeSupport<msg::ParticipantEntitiesInfo> {
  using C = rmw_dds_common_msg_dds__ParticipantEntitiesInfo_;
  using CGid = rmw_dds_common_msg_dds__Gid_;
  using CNode = rmw_dds_common_msg_dds__NodeEntitiesInfo_;
  struct Scratch {
    std::vector<CNode> nodes;
    std::vector<std::vector<CGid>> gids;
  };
  static const dds_topic_descriptor_t* descriptor() { return &rmw_dds_common_msg_dds__ParticipantEntitiesInfo__desc; }
  static CGid gid_to_c(const msg::Gid& g) {
    CGid c{};
    std::copy(g.begin(), g.end(), c.data);
    return c;
  }
  static msg::Gid gid_from_c(const CGid& c) {
    msg::Gid g{};
    std::copy(std::begin(c.data), std::end(c.data), g.begin());
    return g;
  }
  template <std::size_t N>
  static void copy_name(char (&to)[N], const std::string& from) {
    const std::size_t n = std::min(from.size(), N - 1);  // names are checked to fit before
    std::memcpy(to, from.data(), n);
    to[n] = '\0';
  }
  static dds_sequence_rmw_dds_common_msg_dds__Gid_ gids_to_c(const std::vector<msg::Gid>& from, Scratch& scratch) {
    std::vector<CGid>& held = scratch.gids.emplace_back();
    for (const msg::Gid& g : from) held.push_back(gid_to_c(g));
    return view_sequence<dds_sequence_rmw_dds_common_msg_dds__Gid_>(held);
  }
  static std::vector<msg::Gid> gids_from_c(const dds_sequence_rmw_dds_common_msg_dds__Gid_& c) {
    std::vector<msg::Gid> out;
    if (c._buffer != nullptr) {
      for (std::uint32_t i = 0; i < c._length; ++i) out.push_back(gid_from_c(c._buffer[i]));
    }
    return out;
  }
  static C to_c(const msg::ParticipantEntitiesInfo& m, Scratch& scratch) {
    scratch.nodes.clear();
    scratch.gids.clear();
    scratch.gids.reserve(2 * m.node_entities_info_seq.size());  // the views point into these vectors
    for (const msg::NodeEntitiesInfo& n : m.node_entities_info_seq) {
      CNode& c = scratch.nodes.emplace_back();
      copy_name(c.node_namespace, n.node_namespace);
      copy_name(c.node_name, n.node_name);
      c.reader_gid_seq = gids_to_c(n.reader_gid_seq, scratch);
      c.writer_gid_seq = gids_to_c(n.writer_gid_seq, scratch);
    }
    return {gid_to_c(m.gid), view_sequence<dds_sequence_rmw_dds_common_msg_dds__NodeEntitiesInfo_>(scratch.nodes)};
  }
  static msg::ParticipantEntitiesInfo from_c(const C& c) {
    msg::ParticipantEntitiesInfo m;
    m.gid = gid_from_c(c.gid);
    if (c.node_entities_info_seq._buffer != nullptr) {
      for (std::uint32_t i = 0; i < c.node_entities_info_seq._length; ++i) {
        const CNode& n = c.node_entities_info_seq._buffer[i];
        m.node_entities_info_seq.push_back({text(n.node_namespace), text(n.node_name), gids_from_c(n.reader_gid_seq),
                                            gids_from_c(n.writer_gid_seq)});
      }
    }
    return m;
  }
};

template <>
struct TypeSupport<msg::OccupancyGrid> {
  using C = nav_msgs_msg_dds__OccupancyGrid_;
  static const dds_topic_descriptor_t* descriptor() { return &nav_msgs_msg_dds__OccupancyGrid__desc; }
  static C to_c(const msg::OccupancyGrid& m) {
    nav_msgs_msg_dds__MapMetaData_ info{detail::to_c(m.info.map_load_time), m.info.resolution, m.info.width,
                                        m.info.height, detail::to_c(m.info.origin)};
    return {detail::to_c(m.header), info, view_sequence<dds_sequence_int8>(m.data)};
  }
  static msg::OccupancyGrid from_c(const C& c) {
    msg::MapMetaData info{detail::from_c(c.info.map_load_time), c.info.resolution, c.info.width, c.info.height,
                          detail::from_c(c.info.origin)};
    return {detail::from_c(c.header), info, copy_sequence<std::int8_t>(c.data)};
  }
};

template <>
struct TypeSupport<msg::Event> {
  using C = tripodal_msgs_msg_dds__Event_;
  static const dds_topic_descriptor_t* descriptor() { return &tripodal_msgs_msg_dds__Event__desc; }
  static C to_c(const msg::Event& m) {
    return {detail::to_c(m.stamp), view(m.robot), view(m.source), view(m.kind), view(m.detail), m.severity};
  }
  static msg::Event from_c(const C& c) {
    return {detail::from_c(c.stamp), text(c.robot), text(c.source), text(c.kind), text(c.detail), c.severity};
  }
};

template <>
struct TypeSupport<msg::TaskCommand> {
  using C = tripodal_msgs_msg_dds__TaskCommand_;
  static const dds_topic_descriptor_t* descriptor() { return &tripodal_msgs_msg_dds__TaskCommand__desc; }
  static C to_c(const msg::TaskCommand& m) {
    return {detail::to_c(m.stamp), view(m.robot), m.id, view(m.command), view(m.task)};
  }
  static msg::TaskCommand from_c(const C& c) {
    return {detail::from_c(c.stamp), text(c.robot), c.id, text(c.command), text(c.task)};
  }
};

template <>
struct TypeSupport<msg::SimStep> {
  using C = tripodal_msgs_msg_dds__SimStep_;
  static const dds_topic_descriptor_t* descriptor() { return &tripodal_msgs_msg_dds__SimStep__desc; }
  static C to_c(const msg::SimStep& m) {
    return {detail::to_c(m.until), detail::to_c(m.cmd_vel), m.step, view_sequence<dds_sequence_double>(m.joint_targets)};
  }
  static msg::SimStep from_c(const C& c) {
    return {detail::from_c(c.until), detail::from_c(c.cmd_vel), c.step, copy_sequence<double>(c.joint_targets)};
  }
};

template <>
struct TypeSupport<msg::SimState> {
  using C = tripodal_msgs_msg_dds__SimState_;
  struct Scratch {  // the string sequences' pointers, alive until the write returns
    std::vector<char*> joint_names, button_presses;
  };
  static const dds_topic_descriptor_t* descriptor() { return &tripodal_msgs_msg_dds__SimState__desc; }
  static C to_c(const msg::SimState& m, Scratch& scratch) {
    scratch.joint_names.clear();
    for (const std::string& n : m.joint_names) scratch.joint_names.push_back(view(n));
    scratch.button_presses.clear();
    for (const std::string& n : m.button_presses) scratch.button_presses.push_back(view(n));
    return {detail::to_c(m.stamp),
            m.x,
            m.y,
            m.theta,
            m.distance,
            m.step,
            m.scans,
            m.joint_states,
            m.collisions,
            m.gyro_yaw_rate,
            m.gyro_yaw,
            m.battery_voltage,
            m.battery_current,
            m.battery_percentage,
            m.bumpers_pressed,
            m.bumper_count,
            m.sensors,
            m.battery_charging ? 1U : 0U,
            view_sequence<dds_sequence_uint8>(m.cliff),
            view_sequence<dds_sequence_string>(scratch.joint_names),
            view_sequence<dds_sequence_double>(m.joint_position),
            view_sequence<dds_sequence_double>(m.joint_velocity),
            view_sequence<dds_sequence_double>(m.joint_target),
            view_sequence<dds_sequence_string>(scratch.button_presses)};
  }
  static msg::SimState from_c(const C& c) {
    const auto strings = [](const dds_sequence_string& q) {
      std::vector<std::string> out;
      if (q._buffer != nullptr) {
        for (std::uint32_t i = 0; i < q._length; ++i) out.push_back(text(q._buffer[i]));
      }
      return out;
    };
    return {detail::from_c(c.stamp),
            c.x,
            c.y,
            c.theta,
            c.distance,
            c.step,
            c.scans,
            c.joint_states,
            c.collisions,
            c.gyro_yaw_rate,
            c.gyro_yaw,
            c.battery_voltage,
            c.battery_current,
            c.battery_percentage,
            c.bumpers_pressed,
            c.bumper_count,
            c.sensors,
            c.battery_charging != 0,
            copy_sequence<std::uint8_t>(c.cliff),
            strings(c.joint_names),
            copy_sequence<double>(c.joint_position),
            copy_sequence<double>(c.joint_velocity),
            copy_sequence<double>(c.joint_target),
            strings(c.button_presses)};
  }
};

}  // namespace tripodal::dds::detail
