#include "tripodal/sim/sim_board.hpp"

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
  for (std::size_t i = 0; i < mounts_.ultrasonic_rad.size(); ++i) out.ultrasonic_m[i] = cast(mounts_.ultrasonic_rad[i], mounts_.ultrasonic_range_m);
  for (std::size_t i = 0; i < mounts_.wall_rad.size(); ++i) out.wall_m[i] = cast(mounts_.wall_rad[i], mounts_.wall_range_m);
  const auto& cliff = sim_.cliff().latest().cliff;
  for (std::size_t i = 0; i < out.cliff_floor_m.size(); ++i) {
    const bool drop = i < cliff.size() && cliff[i] != 0;
    out.cliff_floor_m[i] = drop ? std::numeric_limits<float>::infinity() : static_cast<float>(mounts_.floor_m);
  }
  out.bumps = static_cast<std::uint8_t>(sim_.bumpers().latest().pressed_mask & 0xFFU);
}

}  // namespace tripodal::sim
