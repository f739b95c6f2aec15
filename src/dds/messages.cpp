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

}  // namespace tripodal::dds
