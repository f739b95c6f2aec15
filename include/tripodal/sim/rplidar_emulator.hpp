// An RPLIDAR A1 emulated on a byte stream (a pseudo-terminal in tripodal-board-sim --lidar, or a
// test's): it answers GET_INFO, GET_HEALTH, STOP, RESET and SCAN byte for byte as the A1's
// protocol describes (board/rplidar_protocol.hpp) and streams SCAN's 5-byte nodes at the A1's
// sample rate, one revolution at its rotation rate, each range cast by the simulator's ray caster
// (SimLidarScene) in the world the simulated board also moves in. Its motor follows the DTR line
// the host switches (set_motor; a pseudo-terminal carries no modem lines, docs/lidar.md).
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "tripodal/board/rplidar_protocol.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/sim/simulator.hpp"

namespace tripodal::sim {

/// What the emulated lidar sees: the range (m) along `bearing_rad` (counter-clockwise from the
/// scanner's front, in its frame) at time `t`; +infinity for no return.
class LidarScene {
 public:
  virtual ~LidarScene() = default;
  [[nodiscard]] virtual double range_m(double bearing_rad, Time t) const noexcept = 0;
};

/// The simulator's world through its ray caster, from the world's laser mount on the robot's
/// current pose (the simulator as the board's plant last stepped it).
class SimLidarScene final : public LidarScene {
 public:
  /// `sim` is not owned and must outlive the scene.
  explicit SimLidarScene(const Simulator& sim) noexcept : sim_(sim) {}
  [[nodiscard]] double range_m(double bearing_rad, Time t) const noexcept override;

 private:
  const Simulator& sim_;
};

struct RplidarEmulatorConfig {
  double rate_hz = 5.5;            ///< revolutions per second (the A1's typical)
  double sample_rate_hz = 2000.0;  ///< measurements per second in SCAN (the A1's standard mode)
  double range_min_m = 0.15;
  double range_max_m = 12.0;
  std::uint8_t quality = 47;                            ///< the quality of a return (0..63)
  Duration spin_up = std::chrono::milliseconds(0);      ///< from motor on to the first node
  Duration reset_time = std::chrono::milliseconds(5);   ///< from RESET to its start-up banner
  board::rplidar::DeviceInfo info{0x18, 29, 1, 7, {}};  ///< model A1M8, firmware 1.29, hardware 7
  board::rplidar::Health health{};                      ///< good
};

struct RplidarEmulatorCounters {
  std::uint64_t requests = 0;      ///< well-formed requests taken
  std::uint64_t bad_requests = 0;  ///< bytes that began no request, or a payload's checksum wrong
  std::uint64_t nodes = 0;         ///< measurement nodes sent
  std::uint64_t revolutions = 0;   ///< start flags sent
  std::uint64_t bytes_lost = 0;    ///< bytes the stream would not take (no reader)
};

class RplidarEmulator {
 public:
  /// Serves on `line` (not owned), its first moment `start`; the motor is on (DTR released).
  RplidarEmulator(board::ByteStream& line, const LidarScene& scene, const RplidarEmulatorConfig& config, Time start) noexcept;

  /// Takes the requests that arrived and sends what is due by `now`: answers, and the nodes of
  /// the samples measured in (previous run, now]. Call at 1 kHz or so (a node is 0.5 ms).
  void run_until(Time now) noexcept;
  /// The DTR line as the host drives it: on spins the motor, off stops it (nodes stop with it).
  void set_motor(bool on, Time now) noexcept;
  [[nodiscard]] bool motor_on() const noexcept { return motor_on_; }
  [[nodiscard]] bool scanning() const noexcept { return scanning_; }
  /// Sends `bytes` as they are, now (tests: garbage on the line mid-stream).
  void inject(std::span<const std::uint8_t> bytes) noexcept;
  /// The health GET_HEALTH answers from now on (tests: a protection stop).
  void set_health(const board::rplidar::Health& health) noexcept { config_.health = health; }
  [[nodiscard]] const RplidarEmulatorCounters& counters() const noexcept { return counters_; }
  /// The A1's angle (degrees clockwise, q6) of sample `k` of a scan session.
  [[nodiscard]] std::uint64_t angle_q6_total(std::uint64_t k) const noexcept;

 private:
  void take_requests(Time now) noexcept;
  void handle(std::uint8_t cmd, Time now) noexcept;
  void send(std::span<const std::uint8_t> bytes) noexcept;
  void send_nodes(Time now) noexcept;

  board::ByteStream& line_;
  const LidarScene& scene_;
  RplidarEmulatorConfig config_;
  RplidarEmulatorCounters counters_;
  bool motor_on_ = true;
  Time motor_since_{};
  bool scanning_ = false;
  Time base_time_{};  // when sample base_sample_ is measured (samples follow at sample_rate_hz)
  std::uint64_t base_sample_ = 0;
  std::uint64_t sample_ = 0;      // next sample of the session
  std::uint64_t revolution_ = 0;  // of the last sample sent
  Time reset_banner_at_ = Time::max();
  // A request being received: A5, CMD, then SIZE, payload and checksum for CMD >= 0x80.
  std::array<std::uint8_t, 260> request_{};
  std::size_t request_size_ = 0;
};

}  // namespace tripodal::sim
