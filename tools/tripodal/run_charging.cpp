#include "run_charging.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "tripodal/core/clock.hpp"
#include "tripodal/planner/recovery.hpp"

namespace tripodal::app {

namespace {

constexpr std::string_view kDockCharge = "PrDockCharge";
constexpr double kFullPercent = 95.0;  // PrDockCharge.xml's full_percent

bool inserts_dock_charge(const RobotProfile& profile) {
  if (profile.recovery.empty()) return false;
  const RecoveryPolicy policy = RecoveryPolicy::load(profile.recovery);
  return std::any_of(policy.rules().begin(), policy.rules().end(), [](const RecoveryRule& r) {
    return r.then == RecoveryAction::retry &&
           std::any_of(r.insert.begin(), r.insert.end(), [](const ProcessStep& s) { return s.process == kDockCharge; });
  });
}

}  // namespace

std::optional<ChargingStops> plan_charging_stops(const RobotProfile& profile, const sim::World& world,
                                                 const board::FirmwareConfig& pack, double need_ah, double available_ah,
                                                 double low_percent) {
  const auto dock = std::find_if(world.docks.begin(), world.docks.end(), [](const sim::Dock& d) { return d.powered; });
  const bool runs_it = std::any_of(profile.processes.begin(), profile.processes.end(),
                                   [](const ProcessEntry& p) { return p.name == kDockCharge; });
  if (dock == world.docks.end() || !runs_it || !inserts_dock_charge(profile)) return std::nullopt;
  const double per_charge_ah = std::max(0.0, kFullPercent - low_percent) / 100.0 * pack.battery_capacity_ah;
  const double net_charge_a = pack.charger_current_a - pack.idle_current_a;
  if (per_charge_ah <= 0.0 || net_charge_a <= 0.0) return std::nullopt;
  ChargingStops s;
  s.dock = dock->name;
  s.stops = static_cast<int>(std::ceil(std::max(0.0, need_ah - available_ah) / per_charge_ah));
  s.charge_s = s.stops * per_charge_ah / net_charge_a * 3600.0;
  return s;
}

std::string charging_summary(const TaskReport& report) {
  int charges = 0;
  double on_dock_s = 0.0;
  for (const ProcessRecord& p : report.processes) {
    if (p.step.process != kDockCharge || !p.success || !p.finished) continue;
    ++charges;
    on_dock_s += to_seconds(*p.finished - p.started);
  }
  if (charges == 0) return {};
  return fmt::format(
      "charged {} time{} at the dock (PrDockCharge), {:.0f} s from leaving the task to charged, resumed where it "
      "stopped",
      charges, charges == 1 ? "" : "s", on_dock_s);
}

}  // namespace tripodal::app
