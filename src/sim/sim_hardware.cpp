#include "tripodal/sim/sim_hardware.hpp"

#include <cmath>
#include <filesystem>
#include <utility>

namespace tripodal::sim {

const ModuleManifest& SimHardware::static_manifest() {
  static const ModuleManifest m = hardware_manifest(
      "sim", "the embedded 2D simulator: simulated base, laser, gyro, bumpers, cliff sensors and battery",
      {"laser_scan", "yaw_rate", "bumpers", "cliff", "battery", "ground_truth_pose"},
      {ParameterSpec{"world", ValueType::string, Value{std::string()}, "", "world file, relative to the robot profile", {}, {}},
       ParameterSpec{"seed", ValueType::number, Value{-1.0}, "",
                     "seed of every noise source; negative: the world's own seed", std::nullopt, std::nullopt}});
  return m;
}

SimHardware::SimHardware(World world, const ControllerConfig& base, std::uint64_t seed)
    : seed_(seed), sim_(std::move(world), base, seed) {}

void register_sim_hardware(HardwareRegistry& registry, std::shared_ptr<const World> world) {
  registry.add(SimHardware::static_manifest(), [world = std::move(world)](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
    if (c.base == nullptr) throw ConfigError(c.where, "hardware 'sim' needs the robot's base controller (its wheel geometry)");
    World w;
    const std::string& file = c.parameters.string("world");
    if (!file.empty()) {
      w = load_world(c.profile_dir / file);
    } else if (world) {
      w = *world;
    } else {
      throw ConfigError(c.where, "hardware 'sim' needs a world: parameters: {world: FILE} (a world file, docs/simulator.md)");
    }
    const double s = c.parameters.number("seed");
    const std::uint64_t seed = s < 0.0 ? w.seed : static_cast<std::uint64_t>(std::llround(s));
    return std::make_unique<SimHardware>(std::move(w), *c.base, seed);
  });
}

}  // namespace tripodal::sim
