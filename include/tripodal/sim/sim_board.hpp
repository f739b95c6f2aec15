// The simulated control board's world: the embedded simulator. The board firmware
// (board/board_firmware.hpp) drives the simulated differential base at the speeds its motors reach
// and reads its ultrasonic, infrared and bump sensors from the simulator's world, so the board and
// the 2D simulator share one world and one clock. Used in process (tests, `tripodal run --board`)
// and by tripodal-board-sim behind a pseudo-terminal.
#pragma once

#include <cstdint>
#include <memory>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/embedded_board.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/uv_dose.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::sim {

/// Where the board's range sensors sit on the round base (body frame, from the rim). The cliff
/// sensors sit where the world's robot.cliff.positions say, looking down from floor_m.
struct BoardSensorMounts {
  std::array<double, 3> ultrasonic_rad{-0.5236, 0.0, 0.5236};  ///< front, +-30 deg (section 2.4.2)
  double ultrasonic_range_m = 4.5;                             ///< US-100
  /// The US-100's beam: the echo comes from the nearest solid thing within this full cone angle
  /// (about 15 degrees), traced with ultrasonic_rays rays across it.
  double ultrasonic_cone_rad = 0.26;
  int ultrasonic_rays = 7;
  std::array<double, 2> wall_rad{1.5708, -1.5708};             ///< left, right
  double wall_range_m = 0.15;                                  ///< GP2Y0A51SK0F: 2-15 cm
  double floor_m = 0.02;                                       ///< what a cliff sensor sees over floor
  double cliff_range_m = 0.15;                                 ///< GP2Y0A51SK0F: farther floor (a drop) is no return
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

/// A simulated robot of hardware type "board": the embedded simulator's world moved by the
/// simulated board's firmware, the robot's wheels and sensors behind the board's host side, every
/// exchange crossing the in-process line byte for byte (board/embedded_board.hpp). Like "sim", it
/// gives the localizer the ground truth and the maps module the world's map; the world's laser and
/// gyro (when the world's robot has them) publish as they do on "sim", the rest comes from the board.
/// The UV lamp's dose on the floor is the simulation's ground truth (uv_dose.hpp), accumulated
/// while the firmware has the lamp on.
class SimBoardHardware final : public CHardware, public board::BoardHost, public SimulatorSources {
 public:
  /// The real board's parameters plus the simulation's: line ("in_process" or "pty"), tank_l,
  /// uv_power_w, uv_height_m, uv_radius_m.
  static const ModuleManifest& static_manifest();
  SimBoardHardware(World world, const ControllerConfig& base, std::uint64_t seed, const board::FirmwareConfig& firmware,
                   const board::BoardHardwareConfig& host, board::BoardLine line = board::BoardLine::in_process,
                   UvLamp lamp = {});

  [[nodiscard]] board::BoardHardware& board() noexcept override { return board_.host(); }
  [[nodiscard]] board::EmbeddedBoard& embedded() noexcept { return board_; }
  [[nodiscard]] Simulator& simulator() noexcept { return sim_; }
  [[nodiscard]] const UvDoseMap& uv_dose() const noexcept { return dose_; }

 protected:
  [[nodiscard]] const Simulator& world_sim() const noexcept override { return sim_; }
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  [[nodiscard]] HardwareInterface& do_wheels() noexcept override { return board_.host().wheels(); }
  [[nodiscard]] CommandChannels& do_command_channels() noexcept override { return board_.host().command_channels(); }
  void on_add_resources(ResourceTable& table) override;
  void on_advance_to(Time now) noexcept override;

 private:
  Simulator sim_;
  SimBoardPlant plant_;
  board::EmbeddedBoard board_;
  UvDoseMap dose_;
};

/// Registers the hardware type "board" as the simulated board in `world` (what `tripodal run`
/// registers): the parameters of the real type (board/board_hardware.hpp) except `port` and
/// `baud`, which the in-process line ignores (115200).
void register_sim_board_hardware(HardwareRegistry& registry, const std::shared_ptr<const World>& world);

}  // namespace tripodal::sim
