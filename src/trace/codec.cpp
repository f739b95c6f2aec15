#include "codec.hpp"

#include <stdexcept>

namespace tripodal::trace::detail {

namespace {

constexpr std::array<std::uint32_t, 256> make_crc_table() noexcept {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) != 0 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}

constexpr auto kCrcTable = make_crc_table();

void head(std::vector<std::uint8_t>& out, std::uint8_t type, ChannelId channel, Time stamp) {
  ByteWriter w(out);
  w.u8(type);
  w.u16(channel);
  w.i64(to_ns(stamp));
}

void floats(ByteWriter& w, const std::vector<float>& v) {
  w.u32(static_cast<std::uint32_t>(v.size()));
  for (const float x : v) w.f32(x);
}

void read_floats(ByteReader& in, std::vector<float>& v, const char* field) {
  const std::uint32_t n = in.count(4, field);
  v.resize(n);
  for (auto& x : v) x = in.f32();
}

// Returns the alternative T of `data`, switching to it (value-initialised) if it holds another.
template <typename T>
T& hold(RecordData& data) {
  if (auto* p = std::get_if<T>(&data)) return *p;
  return data.emplace<T>();
}

}  // namespace

std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc) noexcept {
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = kCrcTable[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

void ByteWriter::str16(std::string_view s) {
  if (s.size() > 0xFFFF) throw std::length_error("trace string longer than 65535 bytes");
  u16(static_cast<std::uint16_t>(s.size()));
  out_.insert(out_.end(), s.begin(), s.end());
}

std::uint64_t ByteReader::get(std::size_t bytes, const char* type) {
  if (remaining() < bytes) {
    throw DecodeError{pos_, std::string("record ends inside a field (") + type + " needs " + std::to_string(bytes) +
                                " bytes, " + std::to_string(remaining()) + " left)"};
  }
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(data_[pos_ + i]) << (8 * i);
  pos_ += bytes;
  return v;
}

std::string ByteReader::str16(const char* field) {
  const std::size_t at = pos_;
  const std::uint16_t n = u16();
  if (remaining() < n) {
    throw DecodeError{at, std::string(field) + " length " + std::to_string(n) + " exceeds the " +
                              std::to_string(remaining()) + " bytes left in the record"};
  }
  std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
  pos_ += n;
  return s;
}

std::uint32_t ByteReader::count(std::size_t element_bytes, const char* field) {
  const std::size_t at = pos_;
  const std::uint32_t n = u32();
  if (static_cast<std::uint64_t>(n) * element_bytes > remaining()) {
    throw DecodeError{at, std::string(field) + " count " + std::to_string(n) + " needs " +
                              std::to_string(static_cast<std::uint64_t>(n) * element_bytes) + " bytes, " +
                              std::to_string(remaining()) + " left in the record"};
  }
  return n;
}

void encode(ChannelId channel, const LaserScan& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kLaser), channel, r.stamp);
  ByteWriter w(out);
  w.f64(r.angle_min_rad);
  w.f64(r.angle_max_rad);
  w.f64(r.angle_increment_rad);
  w.f64(r.time_increment_s);
  w.f64(r.scan_time_s);
  w.f64(r.range_min_m);
  w.f64(r.range_max_m);
  floats(w, r.ranges_m);
  floats(w, r.intensities);
}

void encode(ChannelId channel, const OdometryReading& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kOdometry), channel, r.stamp);
  ByteWriter w(out);
  w.f64(r.pose.x_m);
  w.f64(r.pose.y_m);
  w.f64(r.pose.theta_rad);
  w.f64(r.twist.vx_m_s);
  w.f64(r.twist.vy_m_s);
  w.f64(r.twist.wz_rad_s);
}

void encode(ChannelId channel, const SonarReading& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kSonar), channel, r.stamp);
  ByteWriter w(out);
  w.f64(r.field_of_view_rad);
  w.f64(r.range_min_m);
  w.f64(r.range_max_m);
  floats(w, r.ranges_m);
}

void encode(ChannelId channel, const InfraredReading& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kInfrared), channel, r.stamp);
  ByteWriter w(out);
  w.u32(static_cast<std::uint32_t>(r.cliff.size()));
  out.insert(out.end(), r.cliff.begin(), r.cliff.end());
  floats(w, r.wall_ranges_m);
}

void encode(ChannelId channel, const BumperReading& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kBumper), channel, r.stamp);
  ByteWriter w(out);
  w.u32(r.count);
  w.u32(r.pressed_mask);
}

void encode(ChannelId channel, const BatteryReading& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kBattery), channel, r.stamp);
  ByteWriter w(out);
  w.f64(r.voltage_v);
  w.f64(r.current_a);
  w.f64(r.percentage);
  w.u8(r.charging ? 1 : 0);
}

void encode(ChannelId channel, const GyroReading& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kGyro), channel, r.stamp);
  ByteWriter w(out);
  w.f64(r.yaw_rate_rad_s);
  w.f64(r.yaw_rad);
}

void encode(ChannelId channel, const CommandRecord& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kCommand), channel, r.stamp);
  ByteWriter w(out);
  w.f64(r.twist.vx_m_s);
  w.f64(r.twist.vy_m_s);
  w.f64(r.twist.wz_rad_s);
  w.str16(r.source);
}

void encode(ChannelId channel, const EventRecord& r, std::vector<std::uint8_t>& out) {
  head(out, static_cast<std::uint8_t>(ChannelKind::kEvent), channel, r.stamp);
  ByteWriter w(out);
  w.str16(r.name);
}

void encode_declaration(const ChannelInfo& channel, std::vector<std::uint8_t>& out) {
  head(out, kChannelDeclaration, channel.id, Time{});
  ByteWriter w(out);
  w.u8(static_cast<std::uint8_t>(channel.kind));
  w.str16(channel.name);
}

void decode_payload(ChannelKind kind, Time stamp, ByteReader& in, RecordData& data) {
  switch (kind) {
    case ChannelKind::kLaser: {
      auto& r = hold<LaserScan>(data);
      r.stamp = stamp;
      r.angle_min_rad = in.f64();
      r.angle_max_rad = in.f64();
      r.angle_increment_rad = in.f64();
      r.time_increment_s = in.f64();
      r.scan_time_s = in.f64();
      r.range_min_m = in.f64();
      r.range_max_m = in.f64();
      read_floats(in, r.ranges_m, "range");
      read_floats(in, r.intensities, "intensity");
      break;
    }
    case ChannelKind::kOdometry: {
      auto& r = hold<OdometryReading>(data);
      r.stamp = stamp;
      r.pose.x_m = in.f64();
      r.pose.y_m = in.f64();
      r.pose.theta_rad = in.f64();
      r.twist.vx_m_s = in.f64();
      r.twist.vy_m_s = in.f64();
      r.twist.wz_rad_s = in.f64();
      break;
    }
    case ChannelKind::kSonar: {
      auto& r = hold<SonarReading>(data);
      r.stamp = stamp;
      r.field_of_view_rad = in.f64();
      r.range_min_m = in.f64();
      r.range_max_m = in.f64();
      read_floats(in, r.ranges_m, "sonar range");
      break;
    }
    case ChannelKind::kInfrared: {
      auto& r = hold<InfraredReading>(data);
      r.stamp = stamp;
      const std::uint32_t n = in.count(1, "cliff sensor");
      r.cliff.resize(n);
      for (auto& c : r.cliff) c = in.u8();
      read_floats(in, r.wall_ranges_m, "wall range");
      break;
    }
    case ChannelKind::kBumper: {
      auto& r = hold<BumperReading>(data);
      r.stamp = stamp;
      r.count = in.u32();
      r.pressed_mask = in.u32();
      break;
    }
    case ChannelKind::kBattery: {
      auto& r = hold<BatteryReading>(data);
      r.stamp = stamp;
      r.voltage_v = in.f64();
      r.current_a = in.f64();
      r.percentage = in.f64();
      const std::size_t at = in.position();
      const std::uint8_t charging = in.u8();
      if (charging > 1) throw DecodeError{at, "battery charging flag is " + std::to_string(charging) + ", expected 0 or 1"};
      r.charging = charging == 1;
      break;
    }
    case ChannelKind::kGyro: {
      auto& r = hold<GyroReading>(data);
      r.stamp = stamp;
      r.yaw_rate_rad_s = in.f64();
      r.yaw_rad = in.f64();
      break;
    }
    case ChannelKind::kCommand: {
      auto& r = hold<CommandRecord>(data);
      r.stamp = stamp;
      r.twist.vx_m_s = in.f64();
      r.twist.vy_m_s = in.f64();
      r.twist.wz_rad_s = in.f64();
      r.source = in.str16("command source");
      break;
    }
    case ChannelKind::kEvent: {
      auto& r = hold<EventRecord>(data);
      r.stamp = stamp;
      r.name = in.str16("event name");
      break;
    }
    default:
      throw DecodeError{0, "unknown record type " + std::to_string(static_cast<int>(kind))};
  }
  if (in.remaining() != 0) {
    throw DecodeError{in.position(), std::to_string(in.remaining()) + " unexpected bytes after the " +
                                         std::string(to_string(kind)) + " payload"};
  }
}

}  // namespace tripodal::trace::detail
