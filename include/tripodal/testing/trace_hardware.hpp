// TraceHardware: a recorded trace as a robot's hardware (type "trace" of the profile's hardware
// slot), for testing a whole robot open loop: its sensor channels publish into the robot's
// resources as the robot's clock passes their stamps, its wheels follow their commands exactly and
// move nothing, and a channel of recorded poses may stand in for the localizer's ground truth.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/sim/world.hpp"
#include "tripodal/trace/rosbag.hpp"
#include "tripodal/trace/trace_replay.hpp"
#include "tripodal/trace/trace_resources.hpp"

namespace tripodal::testing {

struct TraceHardwareOptions {
  std::filesystem::path trace;  ///< a trace, or a rosbag2 bag (converted with the default topic mapping)
  /// An odometry channel of map_from_base poses (the recorded robot's true or corrected pose) the
  /// localizer reads as ground truth; empty: none (a robot with a GroundTruthLocalizer then stays lost).
  std::string localization_channel;
  /// Channels not replayed because the robot computes them itself: by default the controller's
  /// odometry, which integrates the commanded wheels here.
  std::vector<std::string> skip{"odometry"};
  Duration resource_max_age{0};  ///< of every replayed resource; 0: a reading never goes stale
  /// The world whose map the robot's GridMaps takes when its profile names no map file.
  std::shared_ptr<const sim::World> world;
};

class TraceHardware final : public CHardware, public navi::GroundTruthSource, public navi::MapSource {
 public:
  /// Opens the trace (a first pass reads its channels). Throws trace::TraceIoError or
  /// trace::TraceFormatError (with the byte offset), std::invalid_argument for a localization
  /// channel the trace lacks.
  TraceHardware(TraceHardwareOptions options, const ControllerConfig& base, ModuleManifest manifest);

  [[nodiscard]] Time start_time() const noexcept { return summary_.first; }
  [[nodiscard]] Time end_time() const noexcept { return summary_.last; }
  [[nodiscard]] const trace::TraceSummary& summary() const noexcept { return summary_; }
  /// The recorded pose of the localization channel at or before `t` (nullopt: none yet).
  [[nodiscard]] std::optional<Pose2D> recorded_pose(Time t) const;
  /// Empty, or why the replay stopped early ("FILE: at byte N: ..."): the trace turned out corrupt.
  [[nodiscard]] const std::string& error() const noexcept { return error_; }
  [[nodiscard]] const IdealWheelHardware& ideal_wheels() const noexcept { return wheels_; }

  [[nodiscard]] std::optional<Pose2D> true_pose(Time now) const override { return recorded_pose(now); }
  [[nodiscard]] const navi::OccupancyGrid& world_map() const noexcept override;
  [[nodiscard]] const navi::RegionMap& world_regions() const noexcept override;

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return manifest_; }
  [[nodiscard]] HardwareInterface& do_wheels() noexcept override { return wheels_; }
  void on_add_resources(ResourceTable& table) override;
  void on_advance_to(Time now) noexcept override;

 private:
  TraceHardwareOptions options_;
  ModuleManifest manifest_;
  trace::TraceSource source_;  // the trace file (a bag converted): before summary_, which reads it
  trace::TraceSummary summary_;
  trace::TraceResources resources_;
  std::unique_ptr<trace::TraceReplay> replay_;
  const OdometryResource* localization_ = nullptr;
  IdealWheelHardware wheels_;
  navi::OccupancyGrid empty_map_;
  navi::RegionMap empty_regions_;
  std::string error_;
};

/// The manifest of type "trace": the outputs of the hardware the trace was recorded on (the trace
/// stands in for it), parameters trace, localization, world and max_age_s.
[[nodiscard]] ModuleManifest trace_hardware_manifest(std::vector<std::string> outputs);

/// Registers the hardware type "trace" providing `outputs` (default: the simulator's). Its
/// parameters: trace (file, relative to the profile), localization (channel), world (a world file
/// for the map, relative to the profile; or `world` given here), max_age_s.
void register_trace_hardware(HardwareRegistry& registry, std::vector<std::string> outputs = {},
                             const std::shared_ptr<const sim::World>& world = nullptr);

}  // namespace tripodal::testing
