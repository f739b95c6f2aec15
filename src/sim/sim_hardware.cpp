#include "tripodal/sim/sim_hardware.hpp"

#include <cmath>
#include <filesystem>
#include <utility>

namespace tripodal::sim {

const ModuleManifest& SimHardware::static_manifest() {
  static const ModuleManifest m = hardware_manifest(
      "sim", "the embedded 2D simulator: simulated base, laser, gyro, bumpers, cliff sensors and battery",
      {"laser_scan", "yaw_rate", "bumpers", "cliff", "battery", "joint_state", "ground_truth_pose"},
      {ParameterSpec{"world", ValueType::string, Value{std::string()}, "", "world file, relative to the robot profile", {}, {}},
       seed_parameter()});
  return m;
}

ParameterSpec seed_parameter() {
  return ParameterSpec{"seed", ValueType::number, Value{-1.0}, "", "seed of every noise source; negative: the world's own seed",
                       std::nullopt, std::nullopt};
}

std::uint64_t seed_of(const HardwareConfig& c, const World& w) {
  const double s = c.parameters.number("seed");
  return s < 0.0 ? w.seed : static_cast<std::uint64_t>(std::llround(s));
}

namespace {

World world_of(const HardwareConfig& c, const std::shared_ptr<const World>& world) {
  if (c.base == nullptr) throw ConfigError(c.where, "hardware '" + c.type + "' needs the robot's base controller (its wheel geometry)");
  const std::string& file = c.parameters.string("world");
  if (!file.empty()) return load_world(c.profile_dir / file);
  if (world) return *world;
  throw ConfigError(c.where, "hardware '" + c.type + "' needs a world: parameters: {world: FILE} (a world file, docs/simulator.md)");
}

}  // namespace

SimHardware::SimHardware(World world, const ControllerConfig& base, std::uint64_t seed)
    : seed_(seed), sim_(std::move(world), base, seed) {
  make_joints();
}

SimHardware::SimHardware(const HardwareConfig& config, const std::shared_ptr<const World>& world)
    : SimHardware(world_of(config, world), config) {}

// world_of checked config.base; seed_ is initialised before sim_.
SimHardware::SimHardware(World world, const HardwareConfig& config)
    : seed_(seed_of(config, world)), sim_(std::move(world), *config.base, seed_) {
  make_joints();
}

void SimHardware::make_joints() {
  for (std::size_t i = 0; i < sim_.world().robot.joints.size(); ++i) {
    const JointConfig& j = sim_.world().robot.joints[i];
    joints_.push_back(std::make_unique<JointResource>(j.name, 3 * from_seconds(1.0 / j.rate_hz)));
    // Its position command: held where it was last sent (a servo stays), from where it starts.
    const ChannelValue start = ChannelValue::of(sim_.joints()[i].target_rad);
    export_channel(ChannelSpec{j.name, ChannelType::joint_position, start, true, Duration{0}, j.min_rad, j.max_rad, "rad",
                               "the position joint " + j.name + " goes to"});
    joint_applied_.push_back(start);
  }
  on_advance_to(sim_.now());  // a first state at the start
}

std::vector<std::string> SimHardware::take_button_presses() {
  return sim_.take_button_presses();
}

void SimHardware::on_add_resources(ResourceTable& table) {
  sim_.add_resources(table, false);
  for (auto& j : joints_) table.add(*j);
}

void SimHardware::on_advance_to(Time now) noexcept {
  // The joints' command channels (exported first, in joint order) as the behavior loop fused them.
  const CommandChannels& commands = command_channels();
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    if (commands.value(i) == joint_applied_[i]) continue;
    joint_applied_[i] = commands.value(i);
    sim_.command_joint(i, commands.value(i).number);
  }
  sim_.step_until(now);
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const JointConfig& c = sim_.world().robot.joints[i];
    const JointState& s = sim_.joints()[i];
    JointReading& r = joints_[i]->edit();
    r = {sim_.now(), s.position_rad, s.velocity_rad_s, s.target_rad, c.min_rad, c.max_rad};
    joints_[i]->commit();
  }
  publish_truth();
}

void register_sim_hardware(HardwareRegistry& registry, std::shared_ptr<const World> world) {
  registry.add(SimHardware::static_manifest(), [world = std::move(world)](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
    return std::make_unique<SimHardware>(c, world);
  });
}

}  // namespace tripodal::sim
