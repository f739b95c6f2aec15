// Private to the behaviors area: how a behavior tells a resource gone quiet for a moment from one
// gone for good (the "no odometry" / "no laser" failures of the built-in and gesture behaviors).
#pragma once

#include "tripodal/core/time.hpp"

namespace tripodal::detail {

/// Tracks how long a resource has been stale; true once that exceeds `timeout`.
inline bool stale_too_long(bool fresh, Time now, Duration timeout, bool& stale, Time& since) noexcept {
  if (fresh) {
    stale = false;
    return false;
  }
  if (!stale) {
    stale = true;
    since = now;
  }
  return now - since > timeout;
}

}  // namespace tripodal::detail
