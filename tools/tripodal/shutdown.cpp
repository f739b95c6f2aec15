#include "shutdown.hpp"

#include <algorithm>
#include <span>

#include "tripodal/controllers/controller.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/reactive/control_loop.hpp"
#include "tripodal/robot/robot.hpp"

namespace tripodal::app {

std::string stop_reason(int sig) {
  switch (sig) {
    case 0: return {};
    case SIGINT: return "interrupted by SIGINT";
    case SIGTERM: return "interrupted by SIGTERM";
#ifdef SIGHUP
    case SIGHUP: return "interrupted by SIGHUP";
#endif
    default: return "interrupted by signal " + std::to_string(sig);
  }
}

namespace {

bool all_zero(std::span<const double> v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return x == 0.0; });
}

}  // namespace

bool brake_through_controller(CController& controller, const Clock& clock, Duration max_brake,
                              const std::function<void(Time)>& each_period) {
  const Duration period = controller.nominal_period();
  const Time until = clock.now() + max_brake;
  for (;;) {
    const Time now = clock.now();
    if (each_period) each_period(now);
    controller.set_command(Twist2D{}, now);
    (void)controller.update(now);
    if (all_zero(controller.wheel_commands())) return true;
    if (now >= until) return false;
    clock.sleep_until(now + period);
  }
}

BaseStop stop_base(Robot& robot, const Clock& clock, const WheelCommands& commanded, Duration tick, Duration max_brake) {
  BaseStop out;
  CHardware* hw = robot.hardware();
  CController* controller = robot.behavior_loop().controller();
  if (hw == nullptr) return out;
  if (controller == nullptr) {  // nothing drives the wheels
    if (commanded) out.command_rad_s = commanded();
    out.at_rest = all_zero(out.command_rad_s);
    return out;
  }
  if (tick.count() > 0) {
    // The controller, with nothing left to drive it, brakes the base within its deceleration
    // limits (a wheel stopped at once could tip a tall robot or slip); the loop runs until the
    // base holds a zero command.
    for (Duration braked{0}; braked < max_brake; braked += tick) {
      if (commanded && all_zero(commanded())) break;
      robot.run_for(tick);
    }
  } else {
    (void)brake_through_controller(*controller, clock, max_brake, [hw](Time now) { hw->advance_to(now); });
  }
  const std::span<const double> written = controller->wheel_commands();
  out.command_rad_s = commanded ? commanded() : std::vector<double>(written.begin(), written.end());
  out.at_rest = all_zero(written) && all_zero(out.command_rad_s);
  return out;
}

}  // namespace tripodal::app
