// XCDR1 reading and writing, and the ROS 2 message types of cdr.hpp.
#include "tripodal/trace/cdr.hpp"

#include <bit>
#include <cmath>
#include <cstring>

#include "tripodal/trace/trace_record.hpp"

namespace tripodal::trace {

namespace {
constexpr std::size_t kHeaderBytes = 4;

std::string hex2(std::uint8_t a, std::uint8_t b) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string s = "00 00";
  s[0] = kDigits[a >> 4];
  s[1] = kDigits[a & 15];
  s[3] = kDigits[b >> 4];
  s[4] = kDigits[b & 15];
  return s;
}
}  // namespace

CdrReader::CdrReader(std::span<const std::uint8_t> bytes, std::string_view file, std::uint64_t base_offset)
    : bytes_(bytes), file_(file), base_offset_(base_offset) {
  if (bytes_.size() < kHeaderBytes) {
    throw TraceFormatError(file_, base_offset_,
                           "CDR message of " + std::to_string(bytes_.size()) + " bytes has no 4-byte encapsulation header");
  }
  // 00 00: CDR big endian, 00 01: CDR little endian (the representation options bytes 2-3 are
  // ignored, as ROS 2 writes them as zero or padding counts).
  if (bytes_[0] != 0 || bytes_[1] > 1) {
    throw TraceFormatError(file_, base_offset_,
                           "CDR encapsulation " + hex2(bytes_[0], bytes_[1]) +
                               " is not plain XCDR1 (expected 00 00 big endian or 00 01 little endian)");
  }
  little_ = bytes_[1] == 1;
}

void CdrReader::fail(std::size_t pos, const std::string& what) const {
  throw TraceFormatError(file_, base_offset_ + pos, "CDR: " + what);
}

void CdrReader::align(std::size_t n) {
  const std::size_t rel = pos_ - kHeaderBytes;
  const std::size_t pad = (n - rel % n) % n;
  if (pad > bytes_.size() - pos_) fail(pos_, "alignment padding past the end of the message");
  pos_ += pad;
}

const std::uint8_t* CdrReader::take(std::size_t n, std::string_view what) {
  if (n > bytes_.size() - pos_) {
    fail(pos_, std::string(what) + " of " + std::to_string(n) + " bytes past the end of the message (" +
                   std::to_string(bytes_.size() - pos_) + " left)");
  }
  const std::uint8_t* p = bytes_.data() + pos_;
  pos_ += n;
  return p;
}

namespace {
template <typename T>
T swap_bytes(T v) noexcept {
  if constexpr (sizeof(T) == 2) return static_cast<T>(__builtin_bswap16(v));
  else if constexpr (sizeof(T) == 4) return static_cast<T>(__builtin_bswap32(v));
  else return static_cast<T>(__builtin_bswap64(v));
}
template <typename T>
T load(const std::uint8_t* p, bool little) {
  T v;
  std::memcpy(&v, p, sizeof v);
  if (little != (std::endian::native == std::endian::little)) v = swap_bytes(v);
  return v;
}
}  // namespace

std::uint8_t CdrReader::u8() { return *take(1, "uint8"); }
std::uint16_t CdrReader::u16() {
  align(2);
  return load<std::uint16_t>(take(2, "uint16"), little_);
}
std::uint32_t CdrReader::u32() {
  align(4);
  return load<std::uint32_t>(take(4, "uint32"), little_);
}
std::uint64_t CdrReader::u64() {
  align(8);
  return load<std::uint64_t>(take(8, "uint64"), little_);
}
float CdrReader::f32() { return std::bit_cast<float>(u32()); }
double CdrReader::f64() { return std::bit_cast<double>(u64()); }

std::string CdrReader::string() {
  const std::size_t at = pos_;
  const std::uint32_t n = u32();
  if (n == 0) return {};  // some writers omit the NUL of an empty string
  const std::uint8_t* p = take(n, "string");
  if (p[n - 1] != 0) fail(at, "string of length " + std::to_string(n) + " does not end with NUL");
  return std::string(reinterpret_cast<const char*>(p), n - 1);
}

std::uint32_t CdrReader::sequence_length(std::size_t min_element_bytes) {
  const std::size_t at = pos_;
  const std::uint32_t n = u32();
  if (min_element_bytes > 0 && n > remaining() / min_element_bytes) {
    fail(at, "sequence of " + std::to_string(n) + " elements is longer than the " + std::to_string(remaining()) +
                 " bytes left");
  }
  return n;
}

std::vector<float> CdrReader::f32_sequence() {
  const std::uint32_t n = sequence_length(4);
  std::vector<float> v(n);
  for (auto& x : v) x = f32();
  return v;
}
std::vector<double> CdrReader::f64_sequence() {
  const std::uint32_t n = sequence_length(8);
  std::vector<double> v(n);
  for (auto& x : v) x = f64();
  return v;
}
std::vector<std::int8_t> CdrReader::i8_sequence() {
  const std::uint32_t n = sequence_length(1);
  const std::uint8_t* p = take(n, "int8 sequence");
  return std::vector<std::int8_t>(reinterpret_cast<const std::int8_t*>(p), reinterpret_cast<const std::int8_t*>(p) + n);
}

// ---------------------------------------------------------------------------------------------
CdrWriter::CdrWriter(bool little_endian) : little_(little_endian) {
  bytes_ = {0, static_cast<std::uint8_t>(little_ ? 1 : 0), 0, 0};
}

void CdrWriter::align(std::size_t n) {
  while ((bytes_.size() - kHeaderBytes) % n != 0) bytes_.push_back(0);
}

void CdrWriter::put(const void* v, std::size_t n) {
  const auto* p = static_cast<const std::uint8_t*>(v);
  bytes_.insert(bytes_.end(), p, p + n);
}

namespace {
template <typename T>
T to_order(T v, bool little) {
  return little != (std::endian::native == std::endian::little) ? swap_bytes(v) : v;
}
}  // namespace

void CdrWriter::u8(std::uint8_t v) { bytes_.push_back(v); }
void CdrWriter::u16(std::uint16_t v) {
  align(2);
  v = to_order(v, little_);
  put(&v, 2);
}
void CdrWriter::u32(std::uint32_t v) {
  align(4);
  v = to_order(v, little_);
  put(&v, 4);
}
void CdrWriter::u64(std::uint64_t v) {
  align(8);
  v = to_order(v, little_);
  put(&v, 8);
}
void CdrWriter::f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
void CdrWriter::f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
void CdrWriter::string(std::string_view s) {
  u32(static_cast<std::uint32_t>(s.size() + 1));
  put(s.data(), s.size());
  bytes_.push_back(0);
}
void CdrWriter::f32_sequence(const std::vector<float>& v) {
  u32(static_cast<std::uint32_t>(v.size()));
  for (float x : v) f32(x);
}
void CdrWriter::f64_sequence(const std::vector<double>& v) {
  u32(static_cast<std::uint32_t>(v.size()));
  for (double x : v) f64(x);
}
void CdrWriter::i8_sequence(const std::vector<std::int8_t>& v) {
  u32(static_cast<std::uint32_t>(v.size()));
  put(v.data(), v.size());
}

// ---------------------------------------------------------------------------------------------
namespace ros {
namespace {
void decode(CdrReader& in, Time& t) {
  t.sec = in.i32();
  t.nanosec = in.u32();
}
void decode(CdrReader& in, Header& h) {
  decode(in, h.stamp);
  h.frame_id = in.string();
}
void decode(CdrReader& in, Vector3& v) {
  v.x = in.f64();
  v.y = in.f64();
  v.z = in.f64();
}
void decode(CdrReader& in, Quaternion& q) {
  q.x = in.f64();
  q.y = in.f64();
  q.z = in.f64();
  q.w = in.f64();
}
void decode(CdrReader& in, Pose& p) {
  decode(in, p.position);
  decode(in, p.orientation);
}
void decode(CdrReader& in, TransformStamped& t) {
  decode(in, t.header);
  t.child_frame_id = in.string();
  decode(in, t.translation);
  decode(in, t.rotation);
}

void encode(CdrWriter& out, const Time& t) {
  out.i32(t.sec);
  out.u32(t.nanosec);
}
void encode(CdrWriter& out, const Header& h) {
  encode(out, h.stamp);
  out.string(h.frame_id);
}
void encode(CdrWriter& out, const Vector3& v) {
  out.f64(v.x);
  out.f64(v.y);
  out.f64(v.z);
}
void encode(CdrWriter& out, const Quaternion& q) {
  out.f64(q.x);
  out.f64(q.y);
  out.f64(q.z);
  out.f64(q.w);
}
void encode(CdrWriter& out, const Pose& p) {
  encode(out, p.position);
  encode(out, p.orientation);
}
void encode(CdrWriter& out, const TransformStamped& t) {
  encode(out, t.header);
  out.string(t.child_frame_id);
  encode(out, t.translation);
  encode(out, t.rotation);
}
}  // namespace

void decode(CdrReader& in, LaserScan& m) {
  decode(in, m.header);
  m.angle_min = in.f32();
  m.angle_max = in.f32();
  m.angle_increment = in.f32();
  m.time_increment = in.f32();
  m.scan_time = in.f32();
  m.range_min = in.f32();
  m.range_max = in.f32();
  m.ranges = in.f32_sequence();
  m.intensities = in.f32_sequence();
}
void decode(CdrReader& in, Odometry& m) {
  decode(in, m.header);
  m.child_frame_id = in.string();
  decode(in, m.pose);
  m.pose_covariance = in.f64_array<36>();
  decode(in, m.twist);
  m.twist_covariance = in.f64_array<36>();
}
void decode(CdrReader& in, Imu& m) {
  decode(in, m.header);
  decode(in, m.orientation);
  m.orientation_covariance = in.f64_array<9>();
  decode(in, m.angular_velocity);
  m.angular_velocity_covariance = in.f64_array<9>();
  decode(in, m.linear_acceleration);
  m.linear_acceleration_covariance = in.f64_array<9>();
}
void decode(CdrReader& in, JointState& m) {
  decode(in, m.header);
  const std::uint32_t n = in.sequence_length(4);  // each name at least its length field
  m.name.resize(n);
  for (auto& s : m.name) s = in.string();
  m.position = in.f64_sequence();
  m.velocity = in.f64_sequence();
  m.effort = in.f64_sequence();
}
void decode(CdrReader& in, Twist& m) {
  decode(in, m.linear);
  decode(in, m.angular);
}
void decode(CdrReader& in, TwistStamped& m) {
  decode(in, m.header);
  decode(in, m.twist);
}
void decode(CdrReader& in, TFMessage& m) {
  // A transform is at least a header (8 + 4), a child frame (4) and 7 doubles.
  const std::uint32_t n = in.sequence_length(16 + 56);
  m.transforms.resize(n);
  for (auto& t : m.transforms) decode(in, t);
}
void decode(CdrReader& in, Clock& m) { decode(in, m.clock); }
void decode(CdrReader& in, OccupancyGrid& m) {
  decode(in, m.header);
  decode(in, m.map_load_time);
  m.resolution = in.f32();
  m.width = in.u32();
  m.height = in.u32();
  decode(in, m.origin);
  m.data = in.i8_sequence();
}
void decode(CdrReader& in, String& m) { m.data = in.string(); }

void encode(CdrWriter& out, const LaserScan& m) {
  encode(out, m.header);
  for (float v : {m.angle_min, m.angle_max, m.angle_increment, m.time_increment, m.scan_time, m.range_min, m.range_max})
    out.f32(v);
  out.f32_sequence(m.ranges);
  out.f32_sequence(m.intensities);
}
void encode(CdrWriter& out, const Odometry& m) {
  encode(out, m.header);
  out.string(m.child_frame_id);
  encode(out, m.pose);
  out.f64_array(m.pose_covariance);
  encode(out, m.twist.linear);
  encode(out, m.twist.angular);
  out.f64_array(m.twist_covariance);
}
void encode(CdrWriter& out, const Imu& m) {
  encode(out, m.header);
  encode(out, m.orientation);
  out.f64_array(m.orientation_covariance);
  encode(out, m.angular_velocity);
  out.f64_array(m.angular_velocity_covariance);
  encode(out, m.linear_acceleration);
  out.f64_array(m.linear_acceleration_covariance);
}
void encode(CdrWriter& out, const JointState& m) {
  encode(out, m.header);
  out.u32(static_cast<std::uint32_t>(m.name.size()));
  for (const auto& s : m.name) out.string(s);
  out.f64_sequence(m.position);
  out.f64_sequence(m.velocity);
  out.f64_sequence(m.effort);
}
void encode(CdrWriter& out, const Twist& m) {
  encode(out, m.linear);
  encode(out, m.angular);
}
void encode(CdrWriter& out, const TwistStamped& m) {
  encode(out, m.header);
  encode(out, m.twist);
}
void encode(CdrWriter& out, const TFMessage& m) {
  out.u32(static_cast<std::uint32_t>(m.transforms.size()));
  for (const auto& t : m.transforms) encode(out, t);
}
void encode(CdrWriter& out, const Clock& m) { encode(out, m.clock); }
void encode(CdrWriter& out, const OccupancyGrid& m) {
  encode(out, m.header);
  encode(out, m.map_load_time);
  out.f32(m.resolution);
  out.u32(m.width);
  out.u32(m.height);
  encode(out, m.origin);
  out.i8_sequence(m.data);
}
void encode(CdrWriter& out, const String& m) { out.string(m.data); }

double yaw_of(const Quaternion& q) noexcept {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}
Quaternion quaternion_from_yaw(double yaw_rad) noexcept {
  return Quaternion{0.0, 0.0, std::sin(yaw_rad / 2.0), std::cos(yaw_rad / 2.0)};
}

}  // namespace ros
}  // namespace tripodal::trace
