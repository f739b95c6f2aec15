// The embedded simulator as a robot's hardware (type "sim" of the profile's hardware slot): its
// wheels are the simulated base, its sensors publish into the robot's resources, and it moves with
// the robot's simulated clock. It also tells the localizer the ground truth and the world's
// localization faults, and gives the world's map to a robot whose profile names none.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tripodal/core/snapshot.hpp"
#include "tripodal/hardware/buttons.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::sim {

/// The simulator as the localizer's ground truth and the maps module's map: what every hardware
/// on the simulator gives (types "sim" and the simulated "board", sim_board.hpp).
///
/// Threading: the hardware moves on the thread that advances it (the reactive loop's on the
/// wall-clock runtime) and publishes the true pose after each advance through a seqlock, so
/// true_pose() may be asked from any thread (the localizer's sequencing thread, a tool measuring
/// the run); the world's map, regions and fault windows never change.
class SimulatorSources : public navi::GroundTruthSource, public navi::MapSource {
 public:
  /// The true pose as of the last advance (any thread).
  [[nodiscard]] std::optional<Pose2D> true_pose(Time /*now*/) const override { return truth_.load(); }
  [[nodiscard]] bool localization_lost(Time now) const noexcept override { return world_sim().localization_lost(now); }
  [[nodiscard]] const navi::OccupancyGrid& world_map() const noexcept override { return world_sim().world().grid; }
  [[nodiscard]] const navi::RegionMap& world_regions() const noexcept override { return world_sim().world().regions; }
  /// The simulation itself, for what a run measures (true path, collisions, events).
  [[nodiscard]] const Simulator& simulation() const noexcept { return world_sim(); }

 protected:
  ~SimulatorSources() override = default;
  [[nodiscard]] virtual const Simulator& world_sim() const noexcept = 0;
  /// The hardware's thread, after each advance (and once at construction).
  void publish_truth() noexcept { truth_.store(world_sim().pose()); }

 private:
  SeqlockValue<Pose2D> truth_;
};

/// Not final: an application's hardware that adds devices to the simulated base derives from it
/// (constructed from its HardwareConfig, with the parameters of "sim" in its own manifest).
class SimHardware : public CHardware, public SimulatorSources, public ButtonPanel {
 public:
  /// Parameters of type "sim": world (a world file, relative to the profile) and seed (negative:
  /// the world's own).
  static const ModuleManifest& static_manifest();
  SimHardware(World world, const ControllerConfig& base, std::uint64_t seed);
  /// From the profile's hardware entry: the parameters world and seed; `world`, when given, is the
  /// world to run in if the parameter is left out. Throws ConfigError, located at the entry, when
  /// there is no base controller or no world.
  explicit SimHardware(const HardwareConfig& config, const std::shared_ptr<const World>& world = nullptr);

  [[nodiscard]] Simulator& simulator() noexcept { return sim_; }
  [[nodiscard]] const Simulator& simulator() const noexcept { return sim_; }
  [[nodiscard]] std::uint64_t seed() const noexcept { return seed_; }
  /// The world's LED buttons pressed since the last call (Simulator::take_button_presses).
  [[nodiscard]] std::vector<std::string> take_button_presses() override;

 protected:
  [[nodiscard]] const Simulator& world_sim() const noexcept override { return sim_; }
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  [[nodiscard]] HardwareInterface& do_wheels() noexcept override { return sim_; }
  void on_add_resources(ResourceTable& table) override;
  /// Applies the joints' command channels, steps the simulator, publishes the joints' states.
  void on_advance_to(Time now) noexcept override;

 private:
  SimHardware(World world, const HardwareConfig& config);
  void make_joints();
  std::uint64_t seed_;
  Simulator sim_;
  std::vector<std::unique_ptr<JointResource>> joints_;  // World robot.joints, same order
  std::vector<ChannelValue> joint_applied_;             // the joints' channels as last applied
};

/// The parameter "seed" of the simulated hardware types, and the seed it gives in world `w`
/// (negative: the world's own).
[[nodiscard]] ParameterSpec seed_parameter();
[[nodiscard]] std::uint64_t seed_of(const HardwareConfig& c, const World& w);

/// Registers the hardware type "sim". With `world`, every robot built from the registry runs in
/// that world (an application that loaded it, as `tripodal run --world` does) and the parameter
/// `world` may be left out; otherwise the parameter names the world file.
void register_sim_hardware(HardwareRegistry& registry, std::shared_ptr<const World> world = nullptr);

}  // namespace tripodal::sim
