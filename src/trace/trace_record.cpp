#include "tripodal/trace/trace_record.hpp"

namespace tripodal::trace {

std::string_view to_string(ChannelKind kind) noexcept {
  switch (kind) {
    case ChannelKind::kLaser: return "laser";
    case ChannelKind::kOdometry: return "odometry";
    case ChannelKind::kSonar: return "sonar";
    case ChannelKind::kInfrared: return "infrared";
    case ChannelKind::kBumper: return "bumper";
    case ChannelKind::kBattery: return "battery";
    case ChannelKind::kGyro: return "gyro";
    case ChannelKind::kCommand: return "command";
    case ChannelKind::kEvent: return "event";
  }
  return "unknown";
}

bool is_valid(ChannelKind kind) noexcept {
  const auto v = static_cast<std::uint8_t>(kind);
  return v >= static_cast<std::uint8_t>(ChannelKind::kLaser) && v <= static_cast<std::uint8_t>(ChannelKind::kEvent);
}

ChannelKind kind_of(const RecordData& data) noexcept {
  // The variant's alternatives are listed in ChannelKind order, starting at 1.
  return static_cast<ChannelKind>(data.index() + 1);
}

// std::visit throws only for a valueless variant, which a RecordData never is: its alternatives
// move without throwing.
// NOLINTNEXTLINE(bugprone-exception-escape)
Time stamp_of(const RecordData& data) noexcept {
  return std::visit([](const auto& r) { return r.stamp; }, data);
}

TraceFormatError::TraceFormatError(const std::string& file, std::uint64_t offset, const std::string& what)
    : std::runtime_error(file + ": byte " + std::to_string(offset) + ": " + what), offset_(offset) {}

}  // namespace tripodal::trace
