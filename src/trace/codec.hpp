// Internal: the byte-level encoding shared by the trace writer and reader (docs/trace-format.md).
// Little-endian, fixed-width fields; every read is bounds-checked so a damaged record cannot crash.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "tripodal/trace/trace_record.hpp"

namespace tripodal::trace::detail {

inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'T', 'R', 'P', 'T', 'R', 'C', '\n'};
inline constexpr std::uint16_t kFormatVersion = 1;
inline constexpr std::size_t kFileHeaderBytes = 16;  // magic, u16 version, u16 flags, u32 CRC-32
inline constexpr std::size_t kFrameHeadBytes = 8;    // u32 length, u32 length ^ 0xFFFFFFFF
inline constexpr std::size_t kFrameTailBytes = 4;    // u32 CRC-32 of the body
inline constexpr std::size_t kBodyHeadBytes = 11;    // u8 type, u16 channel, i64 stamp
inline constexpr std::uint8_t kChannelDeclaration = 0;

/// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320), as zlib and PNG compute it.
[[nodiscard]] std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0) noexcept;

class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}
  void u8(std::uint8_t v) { out_.push_back(v); }
  void u16(std::uint16_t v) { put(v, 2); }
  void u32(std::uint32_t v) { put(v, 4); }
  void u64(std::uint64_t v) { put(v, 8); }
  void i64(std::int64_t v) { put(static_cast<std::uint64_t>(v), 8); }
  void f32(float v) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &v, 4);
    put(bits, 4);
  }
  void f64(double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, 8);
    put(bits, 8);
  }
  void str16(std::string_view s);  // u16 length + bytes; throws std::length_error past 65535

 private:
  void put(std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) out_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  std::vector<std::uint8_t>& out_;
};

/// Thrown by ByteReader and decode(); `position` counts from the start of the record body.
struct DecodeError {
  std::size_t position;
  std::string what;
};

class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t u8() { return static_cast<std::uint8_t>(get(1, "u8")); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(get(2, "u16")); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(get(4, "u32")); }
  std::int64_t i64() { return static_cast<std::int64_t>(get(8, "i64")); }
  float f32() {
    const auto bits = static_cast<std::uint32_t>(get(4, "f32"));
    float v = 0;
    std::memcpy(&v, &bits, 4);
    return v;
  }
  double f64() {
    const std::uint64_t bits = get(8, "f64");
    double v = 0;
    std::memcpy(&v, &bits, 8);
    return v;
  }
  std::string str16(const char* field);
  /// Reads a u32 element count and checks that count * element_bytes fit in what is left.
  std::uint32_t count(std::size_t element_bytes, const char* field);
  [[nodiscard]] std::size_t position() const noexcept { return pos_; }
  [[nodiscard]] std::size_t remaining() const noexcept { return size_ - pos_; }

 private:
  std::uint64_t get(std::size_t bytes, const char* type);
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// The channel kind that carries records of type T.
template <typename T>
constexpr ChannelKind kind_for() noexcept {
  if constexpr (std::is_same_v<T, LaserScan>) return ChannelKind::kLaser;
  else if constexpr (std::is_same_v<T, OdometryReading>) return ChannelKind::kOdometry;
  else if constexpr (std::is_same_v<T, SonarReading>) return ChannelKind::kSonar;
  else if constexpr (std::is_same_v<T, InfraredReading>) return ChannelKind::kInfrared;
  else if constexpr (std::is_same_v<T, BumperReading>) return ChannelKind::kBumper;
  else if constexpr (std::is_same_v<T, BatteryReading>) return ChannelKind::kBattery;
  else if constexpr (std::is_same_v<T, GyroReading>) return ChannelKind::kGyro;
  else if constexpr (std::is_same_v<T, CommandRecord>) return ChannelKind::kCommand;
  else return ChannelKind::kEvent;
}

/// Appends the body of a data record (type, channel, stamp, payload) to `out`.
void encode(ChannelId channel, const LaserScan& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const OdometryReading& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const SonarReading& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const InfraredReading& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const BumperReading& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const BatteryReading& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const GyroReading& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const CommandRecord& r, std::vector<std::uint8_t>& out);
void encode(ChannelId channel, const EventRecord& r, std::vector<std::uint8_t>& out);
void encode_declaration(const ChannelInfo& channel, std::vector<std::uint8_t>& out);

/// Decodes a data-record payload of `kind` (the reader has consumed the body head) into `data`,
/// reusing its storage when it already holds that alternative. Throws DecodeError.
void decode_payload(ChannelKind kind, Time stamp, ByteReader& in, RecordData& data);

}  // namespace tripodal::trace::detail
