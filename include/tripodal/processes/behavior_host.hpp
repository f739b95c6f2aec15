// The behaviors as the process supervisor sees them: activate with parameters, deactivate, and
// read their status. The reactive layer implements it over its CBehavior instances (which the
// control loop steps); tests implement it with test doubles. Keeping the supervisor on this narrow
// seam lets it run, and be tested, without a control loop.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal {

/// A behavior's status as of its last period.
struct BehaviorReport {
  BehaviorStatus state = BehaviorStatus::idle;
  std::string reason;             ///< why it failed
  std::optional<Time> last_step;  ///< when the control loop last stepped it; nullopt: not tracked
};

class BehaviorHost {
 public:
  virtual ~BehaviorHost() = default;
  BehaviorHost() = default;
  BehaviorHost(const BehaviorHost&) = delete;
  BehaviorHost& operator=(const BehaviorHost&) = delete;

  /// True when the robot has a behavior of this name.
  [[nodiscard]] virtual bool has(std::string_view behavior) const = 0;
  /// Starts the behavior with `params` at `now`; it reports running from then on. May throw: the
  /// supervisor turns that into the behavior's failure.
  virtual void activate(std::string_view behavior, const ParameterValues& params, Time now) = 0;
  /// Stops it; it produces no command afterwards. May throw (the supervisor logs and goes on).
  virtual void deactivate(std::string_view behavior, Time now) = 0;
  /// Its current status. May throw: the supervisor treats that as a failure.
  [[nodiscard]] virtual BehaviorReport report(std::string_view behavior) const = 0;
};

}  // namespace tripodal
