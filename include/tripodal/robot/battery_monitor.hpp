// BatteryMonitor: the sequencing-layer module that turns the battery resource (a BatteryReading:
// the simulator's, a control board's) into the facts the process nets' guards read — `charging`
// and `battery_percent` — so that a dock-and-charge net (configs/petri/PrDockCharge.xml) runs on
// any hardware that publishes a battery. Registered among the robot's built-in module types.
#pragma once

#include <optional>
#include <string>

#include "tripodal/processes/module.hpp"

namespace tripodal {

class BatteryMonitor final : public CModule {
 public:
  /// Type "BatteryMonitor": input `battery`; outputs the facts `charging` (boolean) and
  /// `battery_percent` (number, 0..100); parameter `battery` names the resource.
  static const ModuleManifest& static_manifest();

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  /// Sets the facts when they change (the supervisor keeps their latest values for processes that
  /// start later). Throws, which makes the module's fault, when the robot has no such resource.
  void on_update(ModuleContext& context) override;

 private:
  std::string resource_;
  std::optional<bool> charging_;
  std::optional<double> percent_;
};

}  // namespace tripodal
