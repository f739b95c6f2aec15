// Time conversions of the message types.
#include "tripodal/dds/messages.hpp"

#include <cmath>

namespace tripodal::dds {

msg::Time ros_time(double seconds) {
  // ROS 2 keeps nanosec in [0, 1e9), so a negative time has sec rounded down.
  const double whole = std::floor(seconds);
  auto nanos = static_cast<std::int64_t>(std::llround((seconds - whole) * 1e9));
  auto sec = static_cast<std::int64_t>(whole);
  if (nanos >= 1'000'000'000) {
    nanos -= 1'000'000'000;
    ++sec;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nanos)};
}

double ros_seconds(const msg::Time& t) { return static_cast<double>(t.sec) + static_cast<double>(t.nanosec) * 1e-9; }

msg::Time ros_time(Time t) {
  const std::int64_t ns = t.time_since_epoch().count();
  std::int64_t sec = ns / 1'000'000'000;
  std::int64_t nanos = ns % 1'000'000'000;
  if (nanos < 0) {  // ROS 2 keeps nanosec in [0, 1e9)
    nanos += 1'000'000'000;
    --sec;
  }
  return {static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nanos)};
}

Time tripodal_time(const msg::Time& t) {
  return Time{Duration{static_cast<std::int64_t>(t.sec) * 1'000'000'000 + static_cast<std::int64_t>(t.nanosec)}};
}

}  // namespace tripodal::dds
