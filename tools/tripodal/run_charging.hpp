// Self-charging in `tripodal run`: whether a task that needs more charge than the pack holds can
// stop at a dock to charge (the profile's dock-and-charge process and recovery rules, a dock in
// the world), how many stops that takes, and what the charges of a finished task were. Used by
// run_task.cpp's up-front check of a dose-planned disinfection and its report.
#pragma once

#include <optional>
#include <string>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/planner/planner.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::app {

/// The charging stops a task needing `need_ah` makes with `available_ah` above the low mark.
struct ChargingStops {
  int stops = 0;
  double charge_s = 0.0;  ///< the time on the dock, all stops together (constant-current charger)
  std::string dock;       ///< the world's dock (its name)
};

/// The robot charges on the way when its profile runs PrDockCharge as a process, its recovery
/// rules insert it on a fault, and the world has a powered dock; nullopt otherwise. Each stop
/// charges from `low_percent` to PrDockCharge's full mark (95 %).
[[nodiscard]] std::optional<ChargingStops> plan_charging_stops(const RobotProfile& profile, const sim::World& world,
                                                               const board::FirmwareConfig& pack, double need_ah,
                                                               double available_ah, double low_percent);

/// The charges of a task as its report lists them: "charged 2 times at the dock, 11800 s on the
/// dock" (PrDockCharge's runs and the time from each start to its end); empty when none.
[[nodiscard]] std::string charging_summary(const TaskReport& report);

}  // namespace tripodal::app
