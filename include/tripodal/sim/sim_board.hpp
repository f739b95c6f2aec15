// The simulated control board's world: the embedded simulator. The board firmware
// (board/board_firmware.hpp) drives the simulated differential base at the speeds its motors reach
// and reads its ultrasonic, infrared and bump sensors from the simulator's world, so the board and
// the 2D simulator share one world and one clock. Used in process (tests, `tripodal run --board`)
// and by tripodal-board-sim behind a pseudo-terminal.
#pragma once

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/sim/simulator.hpp"

namespace tripodal::sim {

/// Where the board's range sensors sit on the round base (body frame, from the rim).
struct BoardSensorMounts {
  std::array<double, 3> ultrasonic_rad{-0.5236, 0.0, 0.5236};  ///< front, +-30 deg (section 2.4.2)
  double ultrasonic_range_m = 4.5;                             ///< US-100
  std::array<double, 2> wall_rad{1.5708, -1.5708};             ///< left, right
  double wall_range_m = 0.15;                                  ///< GP2Y0A51SK0F: 2-15 cm
  double floor_m = 0.02;                                       ///< what a cliff sensor sees over floor
};

class SimBoardPlant final : public board::BoardPlant {
 public:
  /// `sim` must have a differential base (wheels [left, right]) of this wheel radius; not owned.
  SimBoardPlant(Simulator& sim, double wheel_radius_m, BoardSensorMounts mounts = {}) noexcept;

  /// Advances the simulator to `now` at the previous wheel speeds, then sets the new ones.
  void drive(Time now, double left_m_s, double right_m_s) noexcept override;
  void sense(Time now, board::PlantSensors& out) noexcept override;

 private:
  Simulator& sim_;
  double wheel_radius_m_;
  BoardSensorMounts mounts_;
};

}  // namespace tripodal::sim
