#include "tripodal/board/rplidar_protocol.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace tripodal::board::rplidar {

std::size_t encode_request(std::uint8_t cmd, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out) noexcept {
  const bool with_payload = (cmd & 0x80U) != 0 || !payload.empty();
  const std::size_t total = with_payload ? 4 + payload.size() : 2;
  if (payload.size() > 255 || out.size() < total) return 0;
  out[0] = kRequestSync;
  out[1] = cmd;
  if (!with_payload) return total;
  out[2] = static_cast<std::uint8_t>(payload.size());
  std::copy(payload.begin(), payload.end(), out.begin() + 3);
  std::uint8_t x = 0;
  for (std::size_t i = 0; i + 1 < total; ++i) x = static_cast<std::uint8_t>(x ^ out[i]);
  out[total - 1] = x;
  return total;
}

void encode_descriptor(const Descriptor& d, std::span<std::uint8_t, kDescriptorBytes> out) noexcept {
  const std::uint32_t word = (d.length & 0x3FFFFFFFU) | (static_cast<std::uint32_t>(d.mode & 0x3U) << 30);
  out[0] = kDescriptorSync1;
  out[1] = kDescriptorSync2;
  for (std::size_t i = 0; i < 4; ++i) out[2 + i] = static_cast<std::uint8_t>(word >> (8 * i));
  out[6] = d.type;
}

std::optional<Descriptor> decode_descriptor(std::span<const std::uint8_t, kDescriptorBytes> bytes) noexcept {
  if (bytes[0] != kDescriptorSync1 || bytes[1] != kDescriptorSync2) return std::nullopt;
  std::uint32_t word = 0;
  for (std::size_t i = 0; i < 4; ++i) word |= static_cast<std::uint32_t>(bytes[2 + i]) << (8 * i);
  return Descriptor{word & 0x3FFFFFFFU, static_cast<std::uint8_t>(word >> 30), bytes[6]};
}

NodeCheck check_node(std::span<const std::uint8_t, kNodeBytes> bytes) noexcept {
  const bool s = (bytes[0] & 0x01U) != 0;
  const bool not_s = (bytes[0] & 0x02U) != 0;
  if (s == not_s) return NodeCheck::start_bits;
  if ((bytes[1] & 0x01U) == 0) return NodeCheck::check_bit;
  return NodeCheck::ok;
}

Node decode_node(std::span<const std::uint8_t, kNodeBytes> bytes) noexcept {
  Node n;
  n.start = (bytes[0] & 0x01U) != 0;
  n.quality = static_cast<std::uint8_t>(bytes[0] >> 2);
  n.angle_q6 = static_cast<std::uint16_t>((bytes[1] | (bytes[2] << 8)) >> 1);
  n.distance_q2 = static_cast<std::uint16_t>(bytes[3] | (bytes[4] << 8));
  return n;
}

void encode_node(const Node& node, std::span<std::uint8_t, kNodeBytes> out) noexcept {
  out[0] = static_cast<std::uint8_t>((node.quality << 2) | (node.start ? 0x01U : 0x02U));
  const auto angle = static_cast<std::uint16_t>((node.angle_q6 << 1) | 0x01U);
  out[1] = static_cast<std::uint8_t>(angle & 0xFFU);
  out[2] = static_cast<std::uint8_t>(angle >> 8);
  out[3] = static_cast<std::uint8_t>(node.distance_q2 & 0xFFU);
  out[4] = static_cast<std::uint8_t>(node.distance_q2 >> 8);
}

void encode_info(const DeviceInfo& info, std::span<std::uint8_t, kInfoBytes> out) noexcept {
  out[0] = info.model;
  out[1] = info.firmware_minor;
  out[2] = info.firmware_major;
  out[3] = info.hardware;
  std::copy(info.serial.begin(), info.serial.end(), out.begin() + 4);
}

DeviceInfo decode_info(std::span<const std::uint8_t, kInfoBytes> bytes) noexcept {
  DeviceInfo info;
  info.model = bytes[0];
  info.firmware_minor = bytes[1];
  info.firmware_major = bytes[2];
  info.hardware = bytes[3];
  std::copy(bytes.begin() + 4, bytes.end(), info.serial.begin());
  return info;
}

void encode_health(const Health& health, std::span<std::uint8_t, kHealthBytes> out) noexcept {
  out[0] = health.status;
  out[1] = static_cast<std::uint8_t>(health.error_code & 0xFFU);
  out[2] = static_cast<std::uint8_t>(health.error_code >> 8);
}

Health decode_health(std::span<const std::uint8_t, kHealthBytes> bytes) noexcept {
  return Health{bytes[0], static_cast<std::uint16_t>(bytes[1] | (bytes[2] << 8))};
}

void NodeDecoder::shift(std::size_t n) noexcept {
  std::memmove(window_.data(), window_.data() + n, size_ - n);
  size_ -= n;
}

ScanAssembler::ScanAssembler(const ScanAssemblerConfig& config) : config_(config) {
  building_.angle_min_rad = -std::numbers::pi;
  building_.angle_increment_rad = 2.0 * std::numbers::pi / config_.beams;
  building_.angle_max_rad = building_.angle_min_rad + building_.angle_increment_rad * (config_.beams - 1.0);
  building_.scan_time_s = 1.0 / config_.rate_hz;
  building_.time_increment_s = building_.scan_time_s / config_.beams;
  building_.range_min_m = config_.range_min_m;
  building_.range_max_m = config_.range_max_m;
  building_.ranges_m.assign(config_.beams, std::numeric_limits<float>::infinity());
  done_ = building_;
}

std::size_t ScanAssembler::bin_of(double a1_angle_deg) const noexcept {
  // Counter-clockwise angle -a, measured from angle_min (-180 deg): 180 - a, in [0, 360).
  double from_min = std::fmod(180.0 - a1_angle_deg, 360.0);
  if (from_min < 0.0) from_min += 360.0;
  const auto i = static_cast<std::size_t>(std::lround(from_min / 360.0 * config_.beams));
  return i % config_.beams;
}

void ScanAssembler::restart() noexcept {
  started_ = false;
  nodes_ = 0;
  std::fill(building_.ranges_m.begin(), building_.ranges_m.end(), std::numeric_limits<float>::infinity());
}

bool ScanAssembler::add(const Node& node, Time now) noexcept {
  bool completed = false;
  if (node.start) {
    if (started_ && nodes_ >= config_.min_nodes) {
      done_.stamp = building_.stamp;
      std::swap(done_.ranges_m, building_.ranges_m);  // same sizes: no allocation
      ++revolutions_;
      completed = true;
    } else if (nodes_ > 0) {
      ++dropped_;  // the partial revolution before the first start flag, or a short one
    }
    std::fill(building_.ranges_m.begin(), building_.ranges_m.end(), std::numeric_limits<float>::infinity());
    building_.stamp = now;
    nodes_ = 0;
    started_ = true;
  }
  ++nodes_;
  const double r = node.distance_m();
  if (node.distance_q2 != 0 && node.quality != 0 && r >= config_.range_min_m && r <= config_.range_max_m) {
    float& bin = building_.ranges_m[bin_of(node.angle_deg())];
    bin = std::min(bin, static_cast<float>(r));
  }
  return completed;
}

}  // namespace tripodal::board::rplidar
