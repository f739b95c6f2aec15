// A test plugin as an application writes one: a behavior and a controller type, registered into
// the host's plugin set through TRIPODAL_REGISTER_PLUGINS.
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/differential_drive_controller.hpp"
#include "tripodal/robot/plugin_library.hpp"

namespace {

// Turns in place at yaw_rate_rad_s: enough to be created, configured and stepped by a host.
class BhPluginWave final : public tripodal::CBehavior {
 public:
  static const tripodal::ModuleManifest& static_manifest() {
    static const tripodal::ModuleManifest m =
        tripodal::behavior_manifest("BhPluginWave", "turns in place (a shared-library plugin's behavior)", {},
                                    {tripodal::parameter::number("yaw_rate_rad_s", 0.5, "rad/s", "turn rate", 0.0, 2.0)});
    return m;
  }

 private:
  [[nodiscard]] const tripodal::ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const tripodal::ParameterSet& params, const tripodal::BehaviorContext&) override {
    yaw_rate_rad_s_ = params.number("yaw_rate_rad_s");
  }
  std::optional<tripodal::Twist2D> on_step(const tripodal::BehaviorContext&) noexcept override {
    return tripodal::Twist2D{.wz_rad_s = yaw_rate_rad_s_};
  }
  double yaw_rate_rad_s_ = 0.0;
};

}  // namespace

TRIPODAL_REGISTER_PLUGINS(plugins) {
  plugins.behaviors.add<BhPluginWave>();
  // The built-in differential controller under another name: a controller type from a plugin.
  tripodal::ModuleManifest m = tripodal::DifferentialDriveController::static_manifest();
  m.name = "plugin_differential";
  plugins.controllers.add(std::move(m), [](const tripodal::ControllerConfig& c, tripodal::HardwareInterface& h) {
    tripodal::ControllerConfig differential = c;
    differential.type = "differential";
    return std::unique_ptr<tripodal::CController>(std::make_unique<tripodal::DifferentialDriveController>(differential, h));
  });
}
