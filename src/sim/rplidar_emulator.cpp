#include "tripodal/sim/rplidar_emulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string_view>

namespace tripodal::sim {

namespace rp = board::rplidar;

namespace {
constexpr std::uint64_t kTurnQ6 = std::uint64_t{360} * 64;
// What the A1 prints after RESET before it takes requests (the host's decoder must skip it).
constexpr std::string_view kBanner = "RPLIDAR A1 (tripodal emulator)\r\nFirmware 1.29, hardware 7\r\n";
}  // namespace

double SimLidarScene::range_m(double bearing_rad, Time /*t*/) const noexcept {
  const LaserConfig& laser = sim_.world().robot.laser;
  const Pose2D map_from_laser = compose(sim_.pose(), laser.mount);
  return sim_.solid_map().cast(navi::Point2D{map_from_laser.x_m, map_from_laser.y_m}, map_from_laser.theta_rad + bearing_rad,
                               laser.range_max_m);
}

RplidarEmulator::RplidarEmulator(board::ByteStream& line, const LidarScene& scene, const RplidarEmulatorConfig& config,
                                 Time start) noexcept
    : line_(line), scene_(scene), config_(config), motor_since_(start) {}

void RplidarEmulator::set_motor(bool on, Time now) noexcept {
  if (on == motor_on_) return;
  motor_on_ = on;
  motor_since_ = now;
  if (on && scanning_) {
    base_time_ = now + config_.spin_up;
    base_sample_ = sample_;
  }
}

void RplidarEmulator::send(std::span<const std::uint8_t> bytes) noexcept {
  if (!line_.write(bytes)) counters_.bytes_lost += bytes.size();
}

void RplidarEmulator::inject(std::span<const std::uint8_t> bytes) noexcept {
  send(bytes);
}

std::uint64_t RplidarEmulator::angle_q6_total(std::uint64_t k) const noexcept {
  return static_cast<std::uint64_t>(
      std::llround(static_cast<double>(k) * static_cast<double>(kTurnQ6) * config_.rate_hz / config_.sample_rate_hz));
}

void RplidarEmulator::run_until(Time now) noexcept {
  take_requests(now);
  if (now >= reset_banner_at_) {
    reset_banner_at_ = Time::max();
    send(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(kBanner.data()), kBanner.size()));
  }
  if (scanning_ && motor_on_) send_nodes(now);
}

void RplidarEmulator::take_requests(Time now) noexcept {
  std::array<std::uint8_t, 64> in{};
  while (true) {
    const std::ptrdiff_t n = line_.read(in, Time{});
    if (n <= 0) return;
    for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
      const std::uint8_t b = in[i];
      if (request_size_ == 0 && b != rp::kRequestSync) {
        ++counters_.bad_requests;
        continue;
      }
      request_[request_size_++] = b;
      if (request_size_ < 2) continue;
      const std::uint8_t cmd = request_[1];
      if ((cmd & 0x80U) == 0) {
        request_size_ = 0;
        handle(cmd, now);
        continue;
      }
      if (request_size_ < 3) continue;
      const std::size_t total = 4 + request_[2];
      if (request_size_ < total) continue;
      std::uint8_t x = 0;
      for (std::size_t j = 0; j + 1 < total; ++j) x = static_cast<std::uint8_t>(x ^ request_[j]);
      request_size_ = 0;
      if (x != request_[total - 1]) {
        ++counters_.bad_requests;
        continue;
      }
      handle(cmd, now);  // the A1's payload commands (express scan, motor PWM of the A2) are not emulated
    }
  }
}

void RplidarEmulator::handle(std::uint8_t cmd, Time now) noexcept {
  ++counters_.requests;
  scanning_ = false;  // any request ends a SCAN session
  std::array<std::uint8_t, rp::kDescriptorBytes + rp::kInfoBytes> out{};
  const auto descriptor = std::span<std::uint8_t, rp::kDescriptorBytes>(out.data(), rp::kDescriptorBytes);
  switch (static_cast<rp::Command>(cmd)) {
    case rp::Command::stop:
      break;
    case rp::Command::reset:
      reset_banner_at_ = now + config_.reset_time;
      break;
    case rp::Command::get_info:
      rp::encode_descriptor(rp::kInfoDescriptor, descriptor);
      rp::encode_info(config_.info, std::span<std::uint8_t, rp::kInfoBytes>(out.data() + rp::kDescriptorBytes, rp::kInfoBytes));
      send(std::span<const std::uint8_t>(out.data(), rp::kDescriptorBytes + rp::kInfoBytes));
      break;
    case rp::Command::get_health:
      rp::encode_descriptor(rp::kHealthDescriptor, descriptor);
      rp::encode_health(config_.health,
                        std::span<std::uint8_t, rp::kHealthBytes>(out.data() + rp::kDescriptorBytes, rp::kHealthBytes));
      send(std::span<const std::uint8_t>(out.data(), rp::kDescriptorBytes + rp::kHealthBytes));
      break;
    case rp::Command::scan:
      // In its protection stop the A1 ignores SCAN.
      if (config_.health.status == static_cast<std::uint8_t>(rp::HealthStatus::error)) break;
      rp::encode_descriptor(rp::kScanDescriptor, descriptor);
      send(std::span<const std::uint8_t>(out.data(), rp::kDescriptorBytes));
      scanning_ = true;
      sample_ = 0;
      base_sample_ = 0;
      // Nodes flow once the motor turns steadily.
      base_time_ = std::max(now, motor_since_ + config_.spin_up);
      break;
    default:
      break;
  }
}

void RplidarEmulator::send_nodes(Time now) noexcept {
  std::array<std::uint8_t, 64 * rp::kNodeBytes> out{};
  std::size_t size = 0;
  while (true) {
    const Time at = base_time_ + from_seconds(static_cast<double>(sample_ - base_sample_) / config_.sample_rate_hz);
    if (at > now) break;
    const std::uint64_t q6_total = angle_q6_total(sample_);
    const std::uint64_t revolution = q6_total / kTurnQ6;
    rp::Node node;
    node.start = sample_ == 0 || revolution != revolution_;
    revolution_ = revolution;
    node.angle_q6 = static_cast<std::uint16_t>(q6_total % kTurnQ6);
    // The A1 turns clockwise; the scene's bearings are counter-clockwise.
    const double r = scene_.range_m(-node.angle_deg() * std::numbers::pi / 180.0, at);
    if (std::isfinite(r) && r >= config_.range_min_m && r <= config_.range_max_m) {
      node.distance_q2 = static_cast<std::uint16_t>(std::min<long long>(std::llround(r * 4000.0), 65535));
      node.quality = config_.quality;
    }
    rp::encode_node(node, std::span<std::uint8_t, rp::kNodeBytes>(out.data() + size, rp::kNodeBytes));
    size += rp::kNodeBytes;
    ++sample_;
    ++counters_.nodes;
    if (node.start) ++counters_.revolutions;
    if (size == out.size()) {
      send(std::span<const std::uint8_t>(out.data(), size));
      size = 0;
    }
  }
  if (size > 0) send(std::span<const std::uint8_t>(out.data(), size));
}

}  // namespace tripodal::sim
