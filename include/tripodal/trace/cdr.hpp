// CDR (OMG XCDR1, the serialisation of ROS 2 messages in rosbag2 bags) and the ROS 2 message types
// the bag importer decodes (docs/rosbag.md). Sits under the rosbag readers (rosbag.hpp): they hand
// each message's bytes here, and the decoded message becomes a trace record.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/trace/trace_record.hpp"  // TraceFormatError

namespace tripodal::trace {

/// Reads one CDR-encoded message: the 4-byte encapsulation header (CDR_BE 00 00 or CDR_LE 00 01),
/// then primitives aligned to their size (at most 8) counted from the byte after the header.
/// Every error throws TraceFormatError naming `file` and the byte `base_offset` + position, so a
/// message inside an MCAP chunk or a db3 row is located in the file it came from.
class CdrReader final {
 public:
  /// Throws TraceFormatError when the header is missing or names another encapsulation (PL_CDR,
  /// XCDR2, ...): only plain XCDR1 is decoded.
  CdrReader(std::span<const std::uint8_t> bytes, std::string_view file, std::uint64_t base_offset);

  [[nodiscard]] std::uint8_t u8();
  [[nodiscard]] std::int8_t i8() { return static_cast<std::int8_t>(u8()); }
  [[nodiscard]] bool boolean() { return u8() != 0; }
  [[nodiscard]] std::uint16_t u16();
  [[nodiscard]] std::uint32_t u32();
  [[nodiscard]] std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  [[nodiscard]] std::uint64_t u64();
  [[nodiscard]] std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
  [[nodiscard]] float f32();
  [[nodiscard]] double f64();
  /// A string: uint32 length counting the terminating NUL, the bytes, the NUL.
  [[nodiscard]] std::string string();
  /// A sequence length, checked against the bytes left (each element at least `min_element_bytes`).
  [[nodiscard]] std::uint32_t sequence_length(std::size_t min_element_bytes);
  [[nodiscard]] std::vector<float> f32_sequence();
  [[nodiscard]] std::vector<double> f64_sequence();
  [[nodiscard]] std::vector<std::int8_t> i8_sequence();
  template <std::size_t N>
  [[nodiscard]] std::array<double, N> f64_array() {
    std::array<double, N> a{};
    for (auto& v : a) v = f64();
    return a;
  }

  [[nodiscard]] bool little_endian() const noexcept { return little_; }
  /// Bytes of the message not read yet (ROS messages may carry trailing padding).
  [[nodiscard]] std::size_t remaining() const noexcept { return bytes_.size() - pos_; }
  /// Throws TraceFormatError at `pos` (relative to the message) with `what`.
  [[noreturn]] void fail(std::size_t pos, const std::string& what) const;

 private:
  void align(std::size_t n);
  const std::uint8_t* take(std::size_t n, std::string_view what);

  std::span<const std::uint8_t> bytes_;
  std::string file_;
  std::uint64_t base_offset_;
  std::size_t pos_ = 4;
  bool little_ = true;
};

/// Writes XCDR1 (little-endian by default); the counterpart of CdrReader for the MCAP exporter
/// and for tests that build messages byte by byte.
class CdrWriter final {
 public:
  explicit CdrWriter(bool little_endian = true);
  void u8(std::uint8_t v);
  void i8(std::int8_t v) { u8(static_cast<std::uint8_t>(v)); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void u16(std::uint16_t v);
  void u32(std::uint32_t v);
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void u64(std::uint64_t v);
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f32(float v);
  void f64(double v);
  void string(std::string_view s);
  void f32_sequence(const std::vector<float>& v);
  void f64_sequence(const std::vector<double>& v);
  void i8_sequence(const std::vector<std::int8_t>& v);
  template <std::size_t N>
  void f64_array(const std::array<double, N>& a) {
    for (double v : a) f64(v);
  }
  [[nodiscard]] const std::vector<std::uint8_t>& bytes() const noexcept { return bytes_; }
  [[nodiscard]] std::vector<std::uint8_t> take() noexcept { return std::move(bytes_); }

 private:
  void align(std::size_t n);
  void put(const void* v, std::size_t n);
  std::vector<std::uint8_t> bytes_;
  bool little_;
};

/// ROS 2 message types, field for field as their .msg definitions (units as ROS: SI).
namespace ros {

struct Time {  ///< builtin_interfaces/msg/Time
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  [[nodiscard]] std::int64_t ns() const noexcept { return std::int64_t{sec} * 1'000'000'000 + nanosec; }
  friend bool operator==(const Time&, const Time&) = default;
};
struct Header {  ///< std_msgs/msg/Header
  Time stamp;
  std::string frame_id;
  friend bool operator==(const Header&, const Header&) = default;
};
struct Vector3 {  ///< geometry_msgs/msg/Vector3 (also Point)
  double x = 0.0, y = 0.0, z = 0.0;
  friend bool operator==(const Vector3&, const Vector3&) = default;
};
struct Quaternion {  ///< geometry_msgs/msg/Quaternion
  double x = 0.0, y = 0.0, z = 0.0, w = 1.0;
  friend bool operator==(const Quaternion&, const Quaternion&) = default;
};
struct Pose {  ///< geometry_msgs/msg/Pose
  Vector3 position;
  Quaternion orientation;
  friend bool operator==(const Pose&, const Pose&) = default;
};
struct Twist {  ///< geometry_msgs/msg/Twist
  Vector3 linear;
  Vector3 angular;
  friend bool operator==(const Twist&, const Twist&) = default;
};
struct TwistStamped {  ///< geometry_msgs/msg/TwistStamped
  Header header;
  Twist twist;
  friend bool operator==(const TwistStamped&, const TwistStamped&) = default;
};
struct LaserScan {  ///< sensor_msgs/msg/LaserScan
  Header header;
  float angle_min = 0, angle_max = 0, angle_increment = 0, time_increment = 0, scan_time = 0, range_min = 0,
        range_max = 0;
  std::vector<float> ranges;
  std::vector<float> intensities;
  friend bool operator==(const LaserScan&, const LaserScan&) = default;
};
struct Odometry {  ///< nav_msgs/msg/Odometry
  Header header;
  std::string child_frame_id;
  Pose pose;
  std::array<double, 36> pose_covariance{};
  Twist twist;
  std::array<double, 36> twist_covariance{};
  friend bool operator==(const Odometry&, const Odometry&) = default;
};
struct Imu {  ///< sensor_msgs/msg/Imu
  Header header;
  Quaternion orientation;
  std::array<double, 9> orientation_covariance{};
  Vector3 angular_velocity;
  std::array<double, 9> angular_velocity_covariance{};
  Vector3 linear_acceleration;
  std::array<double, 9> linear_acceleration_covariance{};
  friend bool operator==(const Imu&, const Imu&) = default;
};
struct JointState {  ///< sensor_msgs/msg/JointState
  Header header;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
  friend bool operator==(const JointState&, const JointState&) = default;
};
struct TransformStamped {  ///< geometry_msgs/msg/TransformStamped
  Header header;
  std::string child_frame_id;
  Vector3 translation;
  Quaternion rotation;
  friend bool operator==(const TransformStamped&, const TransformStamped&) = default;
};
struct TFMessage {  ///< tf2_msgs/msg/TFMessage
  std::vector<TransformStamped> transforms;
  friend bool operator==(const TFMessage&, const TFMessage&) = default;
};
struct Clock {  ///< rosgraph_msgs/msg/Clock
  Time clock;
  friend bool operator==(const Clock&, const Clock&) = default;
};
struct OccupancyGrid {  ///< nav_msgs/msg/OccupancyGrid
  Header header;
  Time map_load_time;
  float resolution = 0;  ///< m/cell
  std::uint32_t width = 0, height = 0;
  Pose origin;
  std::vector<std::int8_t> data;  ///< row-major, -1 unknown, 0..100 occupancy
  friend bool operator==(const OccupancyGrid&, const OccupancyGrid&) = default;
};
struct String {  ///< std_msgs/msg/String
  std::string data;
  friend bool operator==(const String&, const String&) = default;
};

/// Decoders: each reads the whole message from `in` (trailing bytes are allowed, as CDR pads).
void decode(CdrReader& in, LaserScan& m);
void decode(CdrReader& in, Odometry& m);
void decode(CdrReader& in, Imu& m);
void decode(CdrReader& in, JointState& m);
void decode(CdrReader& in, Twist& m);
void decode(CdrReader& in, TwistStamped& m);
void decode(CdrReader& in, TFMessage& m);
void decode(CdrReader& in, Clock& m);
void decode(CdrReader& in, OccupancyGrid& m);
void decode(CdrReader& in, String& m);

/// Encoders, the inverse of decode().
void encode(CdrWriter& out, const LaserScan& m);
void encode(CdrWriter& out, const Odometry& m);
void encode(CdrWriter& out, const Imu& m);
void encode(CdrWriter& out, const JointState& m);
void encode(CdrWriter& out, const Twist& m);
void encode(CdrWriter& out, const TwistStamped& m);
void encode(CdrWriter& out, const TFMessage& m);
void encode(CdrWriter& out, const Clock& m);
void encode(CdrWriter& out, const OccupancyGrid& m);
void encode(CdrWriter& out, const String& m);

/// The decoded message of `T` from a whole CDR message (header included).
template <typename T>
[[nodiscard]] T decode_cdr(std::span<const std::uint8_t> bytes, std::string_view file = "cdr",
                           std::uint64_t base_offset = 0) {
  CdrReader in(bytes, file, base_offset);
  T m;
  decode(in, m);
  return m;
}
/// A whole CDR message (header included) holding `m`.
template <typename T>
[[nodiscard]] std::vector<std::uint8_t> encode_cdr(const T& m, bool little_endian = true) {
  CdrWriter out(little_endian);
  encode(out, m);
  return out.take();
}

/// Yaw (rad) of a rotation: the heading a planar robot's pose keeps.
[[nodiscard]] double yaw_of(const Quaternion& q) noexcept;
/// The rotation of `yaw_rad` about z.
[[nodiscard]] Quaternion quaternion_from_yaw(double yaw_rad) noexcept;

}  // namespace ros
}  // namespace tripodal::trace
