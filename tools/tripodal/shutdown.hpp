// How a `tripodal run` ends when it is told to (SIGINT, SIGTERM): the reason the report names and
// the base brought to rest before the devices close. Internal to the tool (tools/tripodal),
// shared by the task runs (run_task.cpp) and the guide's visits (visit.cpp).
#pragma once

#include <csignal>
#include <functional>
#include <string>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal {
class CController;
class Robot;
}  // namespace tripodal

namespace tripodal::app {

/// "interrupted by SIGTERM" for a signal number (SIGINT, SIGTERM, SIGHUP by name; another
/// "interrupted by signal N"); "" for 0, a run that was not interrupted.
[[nodiscard]] std::string stop_reason(int sig);

/// The signal that stopped the run, or 0: the value the tool's handler stored in `stop`.
[[nodiscard]] inline int stop_signal(const volatile std::sig_atomic_t* stop) noexcept { return stop != nullptr ? *stop : 0; }

struct BaseStop {
  std::vector<double> command_rad_s;  ///< the wheel velocities the base is commanded last
  bool at_rest = false;                ///< every one of them is zero (and the write was accepted)
};

/// What the base is commanded now, wheel by wheel (rad/s), as the base itself holds it: the
/// simulator's wheel commands, or the control board firmware's required speeds. Empty function:
/// the base is in another process and cannot be read back.
using WheelCommands = std::function<std::vector<double>()>;

/// Brakes the base through its controller on the calling thread, once the robot's threads have
/// stopped: every controller period of `clock`, `each_period(now)` (the hardware's own cycle:
/// a simulator's physics, the board's link), then the controller commanded zero and updated —
/// its limits, its kinematics, the hardware's wheels: the path every behavior-loop cycle takes —
/// until the wheel velocities it writes are all zero or `max_brake` has passed. Returns whether
/// they are all zero.
bool brake_through_controller(CController& controller, const Clock& clock, Duration max_brake,
                              const std::function<void(Time)>& each_period = {});

/// Brings the base to rest once the run's work is cancelled, through the base's controller (the
/// one path the wheels are driven by): runs the robot on (at most `max_brake`, simulated) while its
/// controller brakes through the base's limits, until `commanded` reads all zero; with `tick` 0
/// (the robot's threads stopped) brakes on this thread on `clock` (brake_through_controller). The
/// result is what `commanded` reads last (without it, the controller's last wheel commands); at
/// rest when those and the controller's are all zero.
BaseStop stop_base(Robot& robot, const Clock& clock, const WheelCommands& commanded, Duration tick,
                   Duration max_brake = std::chrono::seconds(3));

}  // namespace tripodal::app
