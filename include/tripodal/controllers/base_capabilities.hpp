// What a base can do, as its controller reports it to the reactive layer's behaviors. It lives
// with the controllers (they produce it) so that controllers need not include the behaviors area.
#pragma once

#include <limits>

namespace tripodal {

/// Per-axis velocity limits of the base in the body frame (all >= 0). A base that cannot move
/// sideways (differential drive) has max_vy_m_s == 0: behaviors read this to steer by heading, so
/// the same behavior code drives holonomic and differential bases.
struct BaseCapabilities {
  double max_vx_m_s = std::numeric_limits<double>::infinity();
  double max_vy_m_s = std::numeric_limits<double>::infinity();
  double max_wz_rad_s = std::numeric_limits<double>::infinity();
  [[nodiscard]] bool holonomic() const noexcept { return max_vy_m_s > 0.0; }
};

}  // namespace tripodal
