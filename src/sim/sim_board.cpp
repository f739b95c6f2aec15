#include "tripodal/sim/sim_board.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace tripodal::sim {

SimBoardPlant::SimBoardPlant(Simulator& sim, double wheel_radius_m, BoardSensorMounts mounts) noexcept
    : sim_(sim), wheel_radius_m_(wheel_radius_m), mounts_(mounts) {}

void SimBoardPlant::drive(Time now, double left_m_s, double right_m_s) noexcept {
  sim_.step_until(now);
  const std::array<double, 2> wheels{left_m_s / wheel_radius_m_, right_m_s / wheel_radius_m_};
  (void)sim_.write_wheel_velocities(wheels);
}

void SimBoardPlant::sense(Time /*now*/, board::PlantSensors& out) noexcept {
  const Pose2D& pose = sim_.pose();
  const double radius = sim_.world().robot.radius_m;
  const auto cast = [&](double mount_rad, double range_m) {
    const double heading = pose.theta_rad + mount_rad;
    const navi::Point2D from{pose.x_m + radius * std::cos(heading), pose.y_m + radius * std::sin(heading)};
    const double d = sim_.solid_map().cast(from, heading, range_m);
    return std::isfinite(d) && d <= range_m ? static_cast<float>(d) : std::numeric_limits<float>::infinity();
  };
  // The ultrasonic echo: the nearest solid thing in the cone (glass and low tables included: the
  // solid map holds them, the laser's does not), measured from the sensor on the rim.
  const int rays = std::max(1, mounts_.ultrasonic_rays);
  for (std::size_t i = 0; i < mounts_.ultrasonic_rad.size(); ++i) {
    float nearest = std::numeric_limits<float>::infinity();
    for (int k = 0; k < rays; ++k) {
      const double off = rays == 1 ? 0.0 : mounts_.ultrasonic_cone_rad * (static_cast<double>(k) / (rays - 1) - 0.5);
      const double mount = mounts_.ultrasonic_rad[i];
      const navi::Point2D from{pose.x_m + radius * std::cos(pose.theta_rad + mount),
                               pose.y_m + radius * std::sin(pose.theta_rad + mount)};
      const double d = sim_.solid_map().cast(from, pose.theta_rad + mount + off, mounts_.ultrasonic_range_m);
      if (std::isfinite(d) && d <= mounts_.ultrasonic_range_m) nearest = std::min(nearest, static_cast<float>(d));
    }
    out.ultrasonic_m[i] = nearest;
  }
  for (std::size_t i = 0; i < mounts_.wall_rad.size(); ++i) out.wall_m[i] = cast(mounts_.wall_rad[i], mounts_.wall_range_m);
  // Each cliff sensor looks down at its place on the chassis: the floor at floor_m, a drop
  // depth_m farther, no return beyond the sensor's range (and a stuck sensor as the fault says).
  for (std::size_t i = 0; i < out.cliff_floor_m.size(); ++i) {
    const double d = mounts_.floor_m + sim_.cliff_depth_m(i);
    out.cliff_floor_m[i] = d > mounts_.cliff_range_m ? std::numeric_limits<float>::infinity() : static_cast<float>(d);
  }
  out.bumps = static_cast<std::uint8_t>(sim_.bumpers().latest().pressed_mask & 0xFFU);
}

}  // namespace tripodal::sim

namespace tripodal::sim {

SimBoardHardware::SimBoardHardware(World world, const ControllerConfig& base, std::uint64_t seed,
                                   const board::FirmwareConfig& firmware, const board::BoardHardwareConfig& host,
                                   board::BoardLine line, UvLamp lamp)
    : sim_(std::move(world), base, seed),
      plant_(sim_, base.differential.wheel_radius_m),
      board_(firmware, plant_, host, 115200, line),
      dose_(sim_.world().grid, lamp) {
  publish_truth();
}

// The lamp's state is the firmware's (what the board switched, whatever the host believes); the
// dose is counted per robot instant, at the pose reached, as the lamp moves a few millimetres
// between two instants.
void SimBoardHardware::on_advance_to(Time now) noexcept {
  const Time before = sim_.now();
  // The board's charger input is the dock's contacts (a powered dock's, World::docks): the
  // firmware then reports charging and its pack charges at the charger's current.
  board_.firmware().set_charging(sim_.charging());
  board_.advance_to(now);
  if (board_.firmware().uv_lamp()) dose_.expose({sim_.pose().x_m, sim_.pose().y_m}, sim_.now() - before);
  publish_truth();
}

// The real board's type, its parameters, plus what the simulated world adds (the laser, the gyro,
// the ground truth).
const ModuleManifest& SimBoardHardware::static_manifest() {
  static const ModuleManifest m = [] {
    const ModuleManifest& real = board::BoardHardware::static_manifest();
    std::vector<std::string> outputs = real.outputs;
    outputs.insert(outputs.end(), {"yaw_rate", "ground_truth_pose"});  // laser_scan: the world's laser stands in for the lidar
    std::vector<ParameterSpec> parameters = real.parameters;
    const UvLamp lamp;
    parameters.insert(
        parameters.end(),
        {seed_parameter(),
         ParameterSpec{"line",
                       ValueType::string,
                       Value{std::string("in_process")},
                       "",
                       "what carries the bytes: in_process (the simulated line) or pty (a kernel pseudo-terminal)",
                       {},
                       {}},
         ParameterSpec{"tank_l", ValueType::number, Value{board::FirmwareConfig{}.tank_initial_l}, "l",
                       "disinfectant in the tank at power-on", 0.0, board::FirmwareConfig{}.tank_l},
         ParameterSpec{"battery_initial", ValueType::number, Value{board::FirmwareConfig{}.battery_initial}, "",
                       "the pack's state of charge at power-on, 0..1 (a low start sends the robot to its dock)", 0.0, 1.0},
         ParameterSpec{"charger_current_a", ValueType::number, Value{board::FirmwareConfig{}.charger_current_a}, "A",
                       "what the dock's charger gives (5.2 A: 0.5 C of the 10.4 Ah pack, about 2 h from empty)", 0.0, 100.0},
         ParameterSpec{"uv_power_w", ValueType::number, Value{lamp.uvc_power_w}, "W", "the lamp's UVC output", 0.0, 1000.0, true},
         ParameterSpec{"uv_height_m", ValueType::number, Value{lamp.height_m}, "m", "the lamp above the floor", 0.0, 1.0, true},
         ParameterSpec{"uv_radius_m", ValueType::number, Value{lamp.radius_m}, "m", "the lit disc's radius on the floor", 0.0,
                       5.0, true}});
    ModuleManifest r = hardware_manifest("board",
                                         "the control board simulated in process in the embedded simulator's world, "
                                         "every exchange over the line byte for byte (docs/board-protocol.md)",
                                         std::move(outputs), std::move(parameters));
    r.command_channels = real.command_channels;  // the embedded host side's
    return r;
  }();
  return m;
}

void SimBoardHardware::on_add_resources(ResourceTable& table) {
  board_.host().add_resources(table);
  const SimRobotConfig& rc = sim_.world().robot;
  if (rc.laser.enabled) table.add(sim_.laser());
  if (rc.gyro.enabled) table.add(sim_.gyro());
}

void register_sim_board_hardware(HardwareRegistry& registry, const std::shared_ptr<const World>& world) {
  registry.add(SimBoardHardware::static_manifest(), [world](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
    const board::BoardHardwareConfig host = board::board_hardware_config(c);
    if (!world) throw ConfigError(c.where, "the simulated hardware 'board' needs a world (tripodal run --world FILE)");
    board::FirmwareConfig firmware;
    firmware.pulses_per_m = host.pulses_per_m;
    firmware.tank_initial_l = c.parameters.number("tank_l");
    firmware.battery_initial = c.parameters.number("battery_initial");
    firmware.charger_current_a = c.parameters.number("charger_current_a");
    // The board has as many cliff sensors as the world's robot (at most 8: the bitmap's segment).
    firmware.cliff_count = std::min(world->robot.cliff.positions.size(), std::size_t{8});
    const std::string& line = c.parameters.string("line");
    if (line != "in_process" && line != "pty") {
      throw ConfigError(c.where, "parameter 'line' is '" + line + "'; expected in_process or pty");
    }
    const UvLamp lamp{c.parameters.number("uv_power_w"), c.parameters.number("uv_height_m"), c.parameters.number("uv_radius_m")};
    return std::make_unique<SimBoardHardware>(*world, *c.base, seed_of(c, *world), firmware, host,
                                              line == "pty" ? board::BoardLine::pseudo_terminal : board::BoardLine::in_process,
                                              lamp);
  });
}

}  // namespace tripodal::sim
