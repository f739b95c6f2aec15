// The serial protocol of the SLAMTEC RPLIDAR A1 (the disinfection robot's laser, seed 001), as
// Slamtec's public interface protocol describes it: request packets `A5 CMD [SIZE PAYLOAD XOR]`,
// 7-byte response descriptors `A5 5A LEN(30 bit) MODE(2 bit) TYPE`, and the 5-byte measurement
// nodes SCAN streams. Pure encoding and decoding, no I/O: the driver (rplidar_a1.hpp) and the
// emulator (sim/rplidar_emulator.hpp) both speak through it. docs/lidar.md has the byte tables.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "tripodal/resources/readings.hpp"

namespace tripodal::board::rplidar {

inline constexpr std::uint8_t kRequestSync = 0xA5;      ///< every request's first byte
inline constexpr std::uint8_t kDescriptorSync1 = 0xA5;  ///< a response descriptor's two first bytes
inline constexpr std::uint8_t kDescriptorSync2 = 0x5A;
inline constexpr std::size_t kDescriptorBytes = 7;
inline constexpr std::size_t kNodeBytes = 5;
inline constexpr std::size_t kInfoBytes = 20;
inline constexpr std::size_t kHealthBytes = 3;
inline constexpr std::uint32_t kBaud = 115200;  ///< the A1's fixed line rate

/// Request commands (the A1's subset). A command with bit 7 set carries a payload.
enum class Command : std::uint8_t { stop = 0x25, reset = 0x40, scan = 0x20, get_info = 0x50, get_health = 0x52 };
/// Data types of response descriptors.
enum class AnswerType : std::uint8_t { device_info = 0x04, health = 0x06, measurement = 0x81 };
/// A descriptor's send mode: one response packet, or packets until the next request.
enum class SendMode : std::uint8_t { single = 0, multiple = 1 };
/// GET_HEALTH's status byte: error is the protection stop (the A1 refuses to scan).
enum class HealthStatus : std::uint8_t { good = 0, warning = 1, error = 2 };

/// Writes request `cmd` into `out`: `A5 cmd`, or with a payload `A5 cmd size payload checksum`
/// (checksum: XOR of every byte before it). Returns the bytes written; 0 when `out` is too small
/// or the payload longer than 255 bytes.
std::size_t encode_request(std::uint8_t cmd, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out) noexcept;

struct Descriptor {
  std::uint32_t length = 0;  ///< bytes of one response packet (30 bits)
  std::uint8_t mode = 0;     ///< SendMode (2 bits; 2 and 3 are reserved)
  std::uint8_t type = 0;     ///< AnswerType
  friend bool operator==(const Descriptor&, const Descriptor&) = default;
};
void encode_descriptor(const Descriptor& d, std::span<std::uint8_t, kDescriptorBytes> out) noexcept;
/// The descriptor in `bytes` (nullopt unless they start `A5 5A`).
[[nodiscard]] std::optional<Descriptor> decode_descriptor(std::span<const std::uint8_t, kDescriptorBytes> bytes) noexcept;
/// The descriptors the A1 sends for GET_INFO, GET_HEALTH and SCAN.
inline constexpr Descriptor kInfoDescriptor{kInfoBytes, 0, static_cast<std::uint8_t>(AnswerType::device_info)};
inline constexpr Descriptor kHealthDescriptor{kHealthBytes, 0, static_cast<std::uint8_t>(AnswerType::health)};
inline constexpr Descriptor kScanDescriptor{kNodeBytes, 1, static_cast<std::uint8_t>(AnswerType::measurement)};

/// One measurement of SCAN. Byte 0: bit 0 start flag S, bit 1 its inverse, bits 2-7 quality;
/// bytes 1-2 (little-endian): bit 0 check bit C (always 1), bits 1-15 angle_q6; bytes 3-4
/// (little-endian): distance_q2. The angle is the A1's: degrees clockwise from its front (the
/// cable side opposite), in 1/64 degree; the distance in 1/4 mm, 0 for no return.
struct Node {
  bool start = false;          ///< the first measurement of a new revolution
  std::uint8_t quality = 0;    ///< 0..63, 0 for no return
  std::uint16_t angle_q6 = 0;  ///< 0..32767 (a turn is 23040)
  std::uint16_t distance_q2 = 0;
  [[nodiscard]] double angle_deg() const noexcept { return angle_q6 / 64.0; }
  [[nodiscard]] double distance_m() const noexcept { return distance_q2 / 4000.0; }
  friend bool operator==(const Node&, const Node&) = default;
};
/// What is wrong with five bytes read as a node.
enum class NodeCheck : std::uint8_t { ok, start_bits, check_bit };
[[nodiscard]] NodeCheck check_node(std::span<const std::uint8_t, kNodeBytes> bytes) noexcept;
/// The node in `bytes`; meaningful only when check_node() is ok.
[[nodiscard]] Node decode_node(std::span<const std::uint8_t, kNodeBytes> bytes) noexcept;
/// Precondition: quality < 64, angle_q6 < 32768.
void encode_node(const Node& node, std::span<std::uint8_t, kNodeBytes> out) noexcept;

/// GET_INFO's 20 bytes: model, firmware minor then major, hardware, 16-byte serial number.
struct DeviceInfo {
  std::uint8_t model = 0;
  std::uint8_t firmware_minor = 0;
  std::uint8_t firmware_major = 0;
  std::uint8_t hardware = 0;
  std::array<std::uint8_t, 16> serial{};
  friend bool operator==(const DeviceInfo&, const DeviceInfo&) = default;
};
void encode_info(const DeviceInfo& info, std::span<std::uint8_t, kInfoBytes> out) noexcept;
[[nodiscard]] DeviceInfo decode_info(std::span<const std::uint8_t, kInfoBytes> bytes) noexcept;

/// GET_HEALTH's 3 bytes: status, error code (little-endian).
struct Health {
  std::uint8_t status = 0;  ///< HealthStatus
  std::uint16_t error_code = 0;
  friend bool operator==(const Health&, const Health&) = default;
};
void encode_health(const Health& health, std::span<std::uint8_t, kHealthBytes> out) noexcept;
[[nodiscard]] Health decode_health(std::span<const std::uint8_t, kHealthBytes> bytes) noexcept;

/// What a NodeDecoder saw.
struct NodeDecoderStats {
  std::uint64_t bytes = 0;          ///< fed
  std::uint64_t nodes = 0;          ///< delivered
  std::uint64_t errors = 0;         ///< runs of bytes that were no node (one per loss of sync)
  std::uint64_t skipped_bytes = 0;  ///< bytes dropped while out of sync
  std::uint64_t resyncs = 0;        ///< times sync was found again after an error
};

/// The SCAN stream after its descriptor, in reads of any size: five-byte nodes, each checked
/// (S and its inverse differ, C is 1). A node that fails loses sync: the decoder then drops one
/// byte at a time and takes sync again only where two checked nodes follow each other (one
/// node's 3 check bits pass garbage 1 time in 8; two in a row, 1 in 64). Fixed storage; no
/// allocation, never throws.
class NodeDecoder {
 public:
  /// Feeds `bytes`; calls on_node(const Node&) for every node found, in order.
  template <class OnNode>
  void feed(std::span<const std::uint8_t> bytes, OnNode&& on_node) {
    for (const std::uint8_t b : bytes) {
      ++stats_.bytes;
      window_[size_++] = b;
      drain(on_node);
    }
  }
  /// Forgets partial bytes (a new SCAN session); keeps the counts.
  void reset() noexcept {
    size_ = 0;
    synced_ = true;
  }
  [[nodiscard]] const NodeDecoderStats& stats() const noexcept { return stats_; }
  [[nodiscard]] bool synced() const noexcept { return synced_; }

 private:
  template <class OnNode>
  void drain(OnNode& on_node) {
    const std::size_t need = synced_ ? kNodeBytes : 2 * kNodeBytes;
    if (size_ < need) return;
    const auto first = std::span<const std::uint8_t, kNodeBytes>(window_.data(), kNodeBytes);
    if (synced_) {
      if (check_node(first) == NodeCheck::ok) {
        deliver(on_node);
        return;
      }
      synced_ = false;
      ++stats_.errors;
      return;  // wait for a second node's bytes before judging again
    }
    const auto second = std::span<const std::uint8_t, kNodeBytes>(window_.data() + kNodeBytes, kNodeBytes);
    if (check_node(first) == NodeCheck::ok && check_node(second) == NodeCheck::ok) {
      synced_ = true;
      ++stats_.resyncs;
      deliver(on_node);
      deliver(on_node);
      return;
    }
    shift(1);
    ++stats_.skipped_bytes;
  }
  template <class OnNode>
  void deliver(OnNode& on_node) {
    const Node n = decode_node(std::span<const std::uint8_t, kNodeBytes>(window_.data(), kNodeBytes));
    shift(kNodeBytes);
    ++stats_.nodes;
    on_node(n);
  }
  void shift(std::size_t n) noexcept;

  std::array<std::uint8_t, 2 * kNodeBytes> window_{};
  std::size_t size_ = 0;
  bool synced_ = true;
  NodeDecoderStats stats_;
};

/// How nodes become LaserScans: `beams` bins over a full turn, beam i at -pi + i * 2 pi / beams
/// (counter-clockwise, the framework's and ROS's convention; the A1's clockwise angle a maps to
/// -a). A bin keeps its nearest return; a bin without one is +infinity (no return).
struct ScanAssemblerConfig {
  std::uint32_t beams = 360;
  double range_min_m = 0.15;  ///< the A1's
  double range_max_m = 12.0;
  double rate_hz = 5.5;          ///< nominal revolutions per second (LaserScan::scan_time_s)
  std::uint32_t min_nodes = 50;  ///< a revolution with fewer nodes is dropped (a partial one)
};

/// Collects one revolution's nodes and completes it at the next start flag.
class ScanAssembler {
 public:
  /// Allocates the bins once. Precondition: beams > 0.
  explicit ScanAssembler(const ScanAssemblerConfig& config);
  /// Adds a node received at `now`. True when it completed a revolution: scan() then holds it
  /// (stamped at its first node) until the next add().
  bool add(const Node& node, Time now) noexcept;
  [[nodiscard]] const LaserScan& scan() const noexcept { return done_; }
  /// Revolutions completed (scan() filled), and dropped for too few nodes (the first partial one).
  [[nodiscard]] std::uint64_t revolutions() const noexcept { return revolutions_; }
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_; }
  /// Forgets the revolution under way (a new SCAN session).
  void restart() noexcept;
  /// The bin of an A1 angle (degrees clockwise).
  [[nodiscard]] std::size_t bin_of(double a1_angle_deg) const noexcept;

 private:
  ScanAssemblerConfig config_;
  LaserScan building_;
  LaserScan done_;
  std::uint32_t nodes_ = 0;
  bool started_ = false;  // a start flag seen since restart()
  std::uint64_t revolutions_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace tripodal::board::rplidar
