#include "tripodal/robot/battery_monitor.hpp"

#include <cmath>
#include <stdexcept>

namespace tripodal {

const ModuleManifest& BatteryMonitor::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("BatteryMonitor", ModuleKind::other, Layer::sequencing)
          .description(
              "the battery's state as facts for the process nets: charging (on the dock's contacts) and "
              "battery_percent (state of charge, 0..100)")
          .input("battery")
          .outputs({"charging", "battery_percent"})
          .text("battery", "battery", "the battery resource to read")
          .build();
  return m;
}

void BatteryMonitor::on_configure(const ParameterSet& params) {
  resource_ = params.string("battery");
  charging_.reset();
  percent_.reset();
}

void BatteryMonitor::on_update(ModuleContext& context) {
  const auto* battery = context.resources != nullptr ? context.resources->find<BatteryReading>(resource_) : nullptr;
  if (battery == nullptr) throw std::runtime_error("no battery resource named '" + resource_ + "'");
  if (!battery->has_reading()) return;
  const BatteryReading& r = battery->latest();
  if (charging_ != r.charging) {
    charging_ = r.charging;
    context.set_fact("charging", Value{r.charging});
  }
  // Whole tenths of a percent, rounded down (95.0 means at least 95 %): a guard compares with
  // thresholds, and the nets need not hear of every change of the last digit.
  const double percent = std::floor(r.percentage * 1000.0 + 1e-9) / 10.0;
  if (percent_ != percent) {
    percent_ = percent;
    context.set_fact("battery_percent", Value{percent});
  }
}

}  // namespace tripodal
