// A patrol robot's own hardware type (with its own command channel and resource), behavior, base controller and
// process type as a shared-library plugin (docs/plugins.md): its profile's `plugins:` names it, so `tripodal run` and
// custom_robot both find them.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "tripodal/controllers/differential_drive_controller.hpp"
#include "tripodal/robot/plugin_library.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;
namespace {
struct BeaconReading {  // what the beacon's driver reads: flashing and beeping?
  Time stamp{};
  bool on = false;
};

// The base as the simulator reads it: a differential base (the controller type "patrol_drive" is one).
ControllerConfig as_differential(ControllerConfig c) {
  c.type = "differential";
  apply_parameters(c);
  return c;
}

/// Hardware "sim_with_beacon": the simulator (parameters as "sim") and the warning beacon (LED + buzzer): a command
/// channel "beacon" of the application's own that a behavior switches, and the resource "beacon" saying whether it
/// sounds (while on and the base turns in place), which the hardware publishes like the simulator's sensors.
class BeaconBase final : public sim::SimHardware {
 public:
  static inline const ModuleManifest kManifest = [](ModuleManifest m) {
    m.name = "sim_with_beacon";
    m.outputs.push_back("beacon");
    m.command_channels.push_back(
        {.name = "beacon", .type = ChannelType::digital, .unit = "", .description = "the beacon sounds"});
    return m;
  }(sim::SimHardware::static_manifest());
  static const ModuleManifest& static_manifest() { return kManifest; }
  explicit BeaconBase(const HardwareConfig& c)
      : SimHardware(with_base(c, c.base ? as_differential(*c.base) : ControllerConfig{})) {
    export_channel(kManifest.command_channels.front());
  }

 private:
  static HardwareConfig with_base(HardwareConfig c, const ControllerConfig& base) {  // `base` lives for the constructor
    if (c.base != nullptr) c.base = &base;
    return c;
  }
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return kManifest; }
  void on_add_resources(ResourceTable& table) override {
    SimHardware::on_add_resources(table);
    table.add(beacon_);
  }
  void on_advance_to(Time now) noexcept override {
    SimHardware::on_advance_to(now);
    const Twist2D& v = simulator().velocity();
    beacon_.publish({now, command_channels().value(0).on() && std::abs(v.wz_rad_s) > 0.3 && std::abs(v.vx_m_s) < 0.05});
  }
  static inline const ModuleManifest kBeacon = ManifestBuilder("BeaconResource", ModuleKind::resource).output("beacon").build();
  TypedResource<BeaconReading> beacon_{"beacon", Duration{0}, kBeacon};  // (its manifest is kept by reference)
};

/// BhAnnounce: announces an arrival by turning in place until the beacon has sounded for beacon_s.
class BhAnnounce final : public CBehavior {
 public:
  static inline const ModuleManifest kManifest =
      [](ModuleManifest m) {
        m.writes.push_back({.name = "beacon", .type = ChannelType::digital, .description = "on while announcing"});
        return m;
      }(behavior_manifest("BhAnnounce", "turns in place, the beacon on, until it has sounded beacon_s", {"beacon"},
                          {parameter::number("yaw_rate_rad_s", 1.0, "rad/s", "turn rate", 0.5),
                           parameter::number("beacon_s", 3.0, "s", "beacon time")}));
  static const ModuleManifest& static_manifest() { return kManifest; }

 private:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return kManifest; }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override {
    yaw_rate_rad_s_ = params.number("yaw_rate_rad_s");
    left_s_ = params.number("beacon_s");
    if ((beacon_ = context.resources->first<BeaconReading>()) == nullptr) fail("no beacon resource");
  }
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override {
    if (beacon_->is_fresh(context.now) && beacon_->latest().on) left_s_ -= to_seconds(context.period);
    if (left_s_ <= 0.0) succeed();
    write_channel(0, ChannelValue::of(running()));
    return Twist2D{.wz_rad_s = running() ? yaw_rate_rad_s_ : 0.0};
  }
  const TypedResource<BeaconReading>* beacon_ = nullptr;
  double yaw_rate_rad_s_ = 0.0, left_s_ = 0.0;
};

/// Controller type "patrol_drive": the differential drive (same parameters), forward at most cruise_m_s among people.
class PatrolDrive final : public CController {
 public:
  static inline const ModuleManifest kManifest = [](ModuleManifest m) {
    m.name = "patrol_drive";
    m.parameters.push_back(parameter::number("cruise_m_s", 0.3, "m/s", "the highest forward speed", 0.0));
    return m;
  }(DifferentialDriveController::static_manifest());
  static const ModuleManifest& static_manifest() { return kManifest; }
  PatrolDrive(const ControllerConfig& c, HardwareInterface& wheels)
      : CController(c.period), drive_(as_differential(c), wheels), cruise_m_s_(c.parameters.number("cruise_m_s")) {}

 private:
  const ModuleManifest& do_manifest() const noexcept override { return kManifest; }
  BaseCapabilities do_capabilities() const noexcept override { return drive_.capabilities(); }
  std::span<const double> do_wheel_commands() const noexcept override { return drive_.wheel_commands(); }
  Duration command_timeout() const noexcept override { return drive_.config().cmd_timeout; }
  void on_reset_odometry() noexcept override { drive_.reset_odometry(odometry().pose); }
  ControlStatus on_update(Time now, Duration, const Twist2D& command, bool, Twist2D& limited,
                          OdometryReading& odom) noexcept override {
    drive_.set_command({std::clamp(command.vx_m_s, -cruise_m_s_, cruise_m_s_), command.vy_m_s, command.wz_rad_s}, now);
    const ControlStatus status = drive_.update(now);
    limited = drive_.limited_command();
    odom = drive_.odometry();
    return status;
  }
  DifferentialDriveController drive_;
  double cruise_m_s_;
};

/// Process type "announce": the profile counts an announcement in turns, the behavior in seconds.
class PrAnnounce final : public CProcess {
 public:
  static ModuleManifest static_manifest() { return ManifestBuilder("announce", ModuleKind::process, Layer::sequencing).build(); }
  using CProcess::CProcess;

 private:
  std::string on_bind(ParameterValues& values) const override {
    const double turns = std::get<double>(values.at("turns")), rate_rad_s = std::get<double>(values.at("yaw_rate_rad_s"));
    if (turns <= 0.0) return name() + ": turns must be positive, got " + std::to_string(turns);
    values["beacon_s"] = Value{turns * 2.0 * std::numbers::pi / rate_rad_s};
    return {};
  }
};
}  // namespace

TRIPODAL_REGISTER_PLUGINS(plugins) {
  plugins.hardware.add<BeaconBase>();
  plugins.controllers.add<PatrolDrive>();
  plugins.behaviors.add<BhAnnounce>();
  plugins.processes.add<PrAnnounce>();
}
