// CHardware: the robot's hardware as its runtime owns it, below the reactive layer — the wheels the
// base controller drives (HardwareInterface), the command channels it exports for everything else
// it drives (joints, lamp, atomizer, voice, LCD; core/command_channel.hpp) and the sensors that
// publish into the reactive loop's resources. The robot profile's `hardware:` slot names its type: "sim" (the embedded simulator,
// sim/sim_hardware.hpp) or one an application registers (e.g. a serial control board).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "tripodal/controllers/controller.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/registry.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/resources/resource.hpp"

namespace tripodal {

/// What the robot gives a hardware type's factory.
struct HardwareConfig {
  std::string name = "hardware";
  std::string type;
  ParameterSet parameters;             ///< resolved against the type's manifest
  SourceLocation where;                ///< the profile's hardware entry
  const ControllerConfig* base = nullptr;  ///< the base controller's configuration (wheel geometry)
  std::filesystem::path profile_dir;       ///< relative file parameters are relative to it
};

/// A hardware whose link can fail on its own (a base behind DDS) also implements
/// ResourceFaultSource (resources/resource_faults.hpp): the robot reports its faults like a
/// resource's, as the module fault "<hardware name>.fault".
class CHardware {
 public:
  virtual ~CHardware() = default;
  CHardware(const CHardware&) = delete;
  CHardware& operator=(const CHardware&) = delete;

  [[nodiscard]] const ModuleManifest& manifest() const noexcept { return do_manifest(); }
  /// The wheels of the base controller. Called from the reactive loop's thread.
  [[nodiscard]] HardwareInterface& wheels() noexcept { return do_wheels(); }
  /// The command channels it exports: the behavior loop writes their fused values every cycle
  /// (its thread), the hardware applies them in its own cycle. Fixed after construction.
  [[nodiscard]] CommandChannels& command_channels() noexcept { return do_command_channels(); }
  /// Adds the sensors' resources to the reactive loop's table (once, at assembly).
  void add_resources(ResourceTable& table) { on_add_resources(table); }
  /// Simulated hardware moves with simulated time: the robot's simulation driver calls this before
  /// it runs the loops due at `now`. Real hardware moves by itself and ignores it.
  void advance_to(Time now) noexcept { on_advance_to(now); }
  /// Starts and stops the hardware's own I/O (a serial reader thread) on a real robot.
  void start() { on_start(); }
  void stop() noexcept { on_stop(); }

 protected:
  CHardware() = default;
  [[nodiscard]] virtual const ModuleManifest& do_manifest() const noexcept = 0;
  [[nodiscard]] virtual HardwareInterface& do_wheels() noexcept = 0;
  /// A hardware that embeds another (the simulated board) hands out the embedded one's channels.
  [[nodiscard]] virtual CommandChannels& do_command_channels() noexcept { return channels_; }
  /// Exports a channel (from the constructor); returns its index.
  std::size_t export_channel(ChannelSpec spec) { return channels_.add(std::move(spec)); }
  virtual void on_add_resources(ResourceTable& /*table*/) {}
  virtual void on_advance_to(Time /*now*/) noexcept {}
  virtual void on_start() {}
  virtual void on_stop() noexcept {}

 private:
  CommandChannels channels_;
};

/// A manifest for a hardware type: layer reactive, kind other (below the reactive layer's
/// resources and controllers), outputs the information its sensors give.
[[nodiscard]] ModuleManifest hardware_manifest(std::string name, std::string description, std::vector<std::string> outputs,
                                               std::vector<ParameterSpec> parameters);

/// Hardware types by name ("sim", an application's board), built from their configuration.
using HardwareRegistry = Registry<CHardware, const HardwareConfig&>;

}  // namespace tripodal
