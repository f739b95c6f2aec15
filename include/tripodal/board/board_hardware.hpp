// The disinfection robot's hardware as its robot profile names it: type "board", a differential
// base behind the control board's UART (seed 001). The wheels are the board's motors (speeds out
// in DRIVE, odometry from its encoders), its sensors are the robot's resources (battery,
// ultrasonic, cliff infrared, bumpers), and a missing, late or corrupt response makes the wheels
// refuse writes (the base controller reports a hardware fault) within two control periods. Its
// actuators are command channels (uv_lamp, atomizer, atomizer_fan, voice, lcd): each cycle the
// values the behavior loop fused become board commands where they changed.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "tripodal/board/board_link.hpp"
#include "tripodal/board/rplidar_a1.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/resources/resource.hpp"

namespace tripodal::board {

/// The link's state as the resource "board_link" publishes it each control period: a plain value,
/// so that the sequencing layer reads it through the robot's resource snapshot (Robot::start: the
/// reactive loop's thread runs the link, the sequencing thread must not read BoardLink itself).
struct BoardLinkReading {
  Time stamp{};
  bool synchronised = false;
  bool has_drive = false;
  std::uint8_t buttons = 0;       ///< held, from the latest DRIVE response
  std::uint8_t drive_status = 0;  ///< the latest DRIVE response's status flags (kStatusUvLamp, ...)
  Time drive_stamp{};             ///< when that response arrived
  bool has_battery = false;
  BatteryState battery{};
  bool has_tank = false;
  bool tank_empty = false;
  std::uint8_t tank_percent = 0;
  Time lost_at{};  ///< of the latest loss (stats.link_losses counts them)
  LinkStats stats{};
  std::uint64_t decoder_errors = 0;
  std::size_t pending_actuator_commands = 0;  ///< actuator commands not yet acknowledged
};

/// What holds the robot's BoardHardware: the hardware itself, or a hardware that embeds one (the
/// simulated board, embedded_board.hpp). The sequencing loop's BoardMonitor finds the link here.
class BoardHost {
 public:
  [[nodiscard]] virtual class BoardHardware& board() noexcept = 0;

 protected:
  ~BoardHost() = default;
};

struct BoardHardwareConfig {
  double wheel_radius_m = 0.09;
  double pulses_per_m = 5000.0;  ///< the board's encoder resolution (FirmwareConfig::pulses_per_m)
  LinkConfig link;
};

/// The liquid level module's reading (resource "tank"): what the LCD shows beside the battery.
struct TankReading {
  Time stamp{};
  double percent = 0.0;  ///< 0..100
  bool empty = false;
};
/// The manifest of the board's resource type "TankResource" (output information "tank").
[[nodiscard]] const ModuleManifest& tank_resource_manifest() noexcept;

class BoardHardware final : public CHardware, public HardwareInterface, public BoardHost {
 public:
  /// Parameters of type "board": port (the tty), baud, pulses_per_m, response_timeout_s, max_missed,
  /// and the RPLIDAR A1 beside the board: lidar_port (its tty; empty: none), lidar_timeout_s,
  /// lidar_beams.
  static const ModuleManifest& static_manifest();
  /// Talks over `stream` (not owned; `owned` may hold it).
  BoardHardware(ByteStream& stream, const BoardHardwareConfig& config, std::unique_ptr<ByteStream> owned = nullptr);
  ~BoardHardware() override;

  // HardwareInterface: wheels [left, right].
  [[nodiscard]] std::size_t wheel_count() const noexcept override { return 2; }
  /// Takes the speeds for the next DRIVE; false while the link is not synchronised.
  bool write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept override;
  /// From the latest DRIVE response; false before one or while the link is lost.
  bool read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept override;

  /// One link cycle (the "board_link" resource's poll calls it every control period): first the
  /// board commands of the command channels that changed since the last cycle.
  void cycle(Time now) noexcept;
  /// True once per link loss (the control loop's thread; BoardMonitor counts stats.link_losses).
  [[nodiscard]] bool take_link_lost() noexcept { return link_.take_link_lost(); }
  /// The link itself: for the thread that runs the control loop (or, between runs, the caller);
  /// another thread reads the resource "board_link" (BoardLinkReading) through a snapshot.
  [[nodiscard]] BoardLink& link() noexcept { return link_; }
  [[nodiscard]] BoardHardware& board() noexcept override { return *this; }
  /// Queues an actuator command (UV lamp, atomizer, voice, LCD): sent until acknowledged.
  bool command(Command cmd, std::span<const std::uint8_t> payload) noexcept { return link_.queue(cmd, payload); }
  /// The robot's laser, the resource "laser" (before add_resources; the hardware owns it).
  void attach_lidar(std::unique_ptr<RplidarA1> lidar) noexcept { lidar_ = std::move(lidar); }
  [[nodiscard]] RplidarA1* lidar() noexcept { return lidar_.get(); }

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  [[nodiscard]] HardwareInterface& do_wheels() noexcept override { return *this; }
  void on_add_resources(ResourceTable& table) override;

 private:
  class LinkResource;
  void publish(Time now) noexcept;
  void apply_channels() noexcept;

  std::unique_ptr<ByteStream> owned_;
  BoardHardwareConfig config_;
  BoardLink link_;
  WheelSpeeds speeds_{};
  std::unique_ptr<LinkResource> link_resource_;
  BatteryResource battery_{"battery"};
  TypedResource<TankReading> tank_{"tank", Duration{0}, tank_resource_manifest()};
  SonarResource ultrasonic_{"ultrasonic"};
  InfraredResource cliff_{"cliff"};
  BumperResource bumpers_{"bumpers"};
  std::unique_ptr<RplidarA1> lidar_;
  std::array<ChannelValue, 5> applied_{};  // the channels' values last sent, by channel index
  // The wheels' positions as last read, and what the encoder counts add to them since the latest
  // resynchronisation (read_wheel_states).
  std::array<double, 2> position_{};
  std::array<double, 2> offset_{};
  std::uint64_t resyncs_seen_ = 0;
  bool rebase_pending_ = false;
  bool positions_read_ = false;
};

/// The host side's configuration from a profile's hardware entry of type "board" (ConfigError
/// unless the base controller is differential).
[[nodiscard]] BoardHardwareConfig board_hardware_config(const HardwareConfig& c);

/// Registers the hardware type "board": opens `port` (a tty, e.g. /dev/ttyUSB0 or the
/// pseudo-terminal tripodal-board-sim prints) raw 8N1.
void register_board_hardware(HardwareRegistry& registry);

}  // namespace tripodal::board
