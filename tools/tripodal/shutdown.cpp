#include "shutdown.hpp"

#include <algorithm>

#include "tripodal/hardware/hardware.hpp"
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

BaseStop stop_base(Robot& robot, const WheelCommands& commanded, Duration tick, Duration max_brake) {
  BaseStop out;
  CHardware* hw = robot.hardware();
  if (hw == nullptr) return out;
  const auto zero = [](double v) { return v == 0.0; };
  const auto at_zero = [&] {
    const std::vector<double> c = commanded();
    return std::all_of(c.begin(), c.end(), zero);
  };
  // The controller, with nothing left to drive it, brakes the base within its deceleration
  // limits (a wheel stopped at once could tip a tall robot or slip); the loop runs until the
  // base holds a zero command.
  for (Duration braked{0}; tick.count() > 0 && braked < max_brake; braked += tick) {
    if (commanded && at_zero()) break;
    robot.run_for(tick);
  }
  HardwareInterface& wheels = hw->wheels();
  const std::vector<double> zeros(wheels.wheel_count(), 0.0);
  const bool accepted = wheels.write_wheel_velocities(zeros);
  out.command_rad_s = commanded ? commanded() : zeros;
  out.at_rest = accepted && std::all_of(out.command_rad_s.begin(), out.command_rad_s.end(), zero);
  return out;
}

}  // namespace tripodal::app
