// The RPLIDAR A1 driver: a laser resource of the reactive layer that owns the lidar's serial port
// (rplidar_protocol.hpp), switches its motor by DTR, checks the device (GET_INFO, GET_HEALTH),
// streams SCAN and publishes one LaserScan per revolution. Polled by the control loop each cycle
// like the board's link: nothing blocks (reads never wait), nothing allocates once scanning, and a
// lidar that stops (no start flag in `timeout`) becomes the resource's fault, never a hang.
// docs/lidar.md.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/board/rplidar_protocol.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/resources/resource_faults.hpp"

namespace tripodal::board {

/// The A1's motor enable. On the A1's USB adapter it is the DTR line: DTR asserted stops the
/// motor, released spins it (docs/lidar.md).
class MotorSwitch {
 public:
  virtual ~MotorSwitch() = default;
  /// False when the line cannot be switched (a pseudo-terminal has no modem lines).
  virtual bool set_motor(bool on) noexcept = 0;
};

struct RplidarConfig {
  rplidar::ScanAssemblerConfig scan;
  Duration timeout = std::chrono::seconds(1);                  ///< no start flag for this long: fault
  Duration response_timeout = std::chrono::milliseconds(500);  ///< for GET_INFO, GET_HEALTH, SCAN's descriptor
  Duration stop_settle = std::chrono::milliseconds(20);        ///< after STOP, bytes still in flight are dropped
  std::size_t max_garbage_bytes = 64;                          ///< bytes without a descriptor before the answer counts as garbage
};

/// What the driver counted (read on the loop's thread, or after it stopped).
struct RplidarStats {
  std::uint64_t scans = 0;           ///< revolutions published
  std::uint64_t nodes = 0;           ///< measurement nodes decoded
  std::uint64_t dropped = 0;         ///< revolutions not published (partial, too few nodes)
  std::uint64_t decoder_errors = 0;  ///< losses of sync in the node stream
  std::uint64_t skipped_bytes = 0;   ///< bytes dropped while out of sync
  std::uint64_t restarts = 0;        ///< SCAN sessions started again after a stall
  std::uint64_t faults = 0;          ///< faults raised (stalls, lost port, refused device)
};

/// The resource type "RplidarA1" (and the laser of hardware "board" when its `lidar_port` is set).
class RplidarA1 final : public LaserResource, public ResourceFaultSource {
 public:
  enum class State : std::uint8_t { starting, awaiting_info, awaiting_health, awaiting_scan, scanning, stalled, failed };

  /// Parameters: port, timeout_s, beams, range_min_m, range_max_m, rate_hz.
  static const ModuleManifest& static_manifest();

  /// Talks over `stream` (not owned unless `owned` holds it); switches the motor by `motor` (not
  /// owned; nullptr: by the SerialPort's DTR when `stream` is one, else not at all). Sends nothing
  /// until the first poll.
  RplidarA1(std::string name, ByteStream& stream, const RplidarConfig& config, MotorSwitch* motor = nullptr,
            std::unique_ptr<ByteStream> owned = nullptr);
  ~RplidarA1() override;

  /// Opens `port` (a tty: /dev/ttyUSB0, or the emulator's pseudo-terminal) at 115200 8N1 and
  /// waits (on `clock`, at most config.response_timeout per answer) until the lidar scans. Throws
  /// std::runtime_error naming the port and what failed: "does not exist", "is not a tty",
  /// "answered GET_INFO with ... (no RPLIDAR response descriptor)", "health status error ...".
  [[nodiscard]] static std::unique_ptr<RplidarA1> open(std::string name, const std::filesystem::path& port,
                                                       const RplidarConfig& config, const Clock& clock);

  /// Runs the protocol until scanning, failure or `deadline` (on `clock`); the state reached.
  State run_until_scanning(const Clock& clock, Time deadline) noexcept;

  [[nodiscard]] State state() const noexcept { return state_; }
  /// Why the state is failed or stalled (static text plus the detail of the first failure).
  [[nodiscard]] const std::string& last_error() const noexcept { return error_; }
  [[nodiscard]] const RplidarStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const rplidar::DeviceInfo& device_info() const noexcept { return info_; }
  [[nodiscard]] const rplidar::Health& health() const noexcept { return health_; }
  /// False once switching the motor failed (no modem lines): the motor then runs as it was.
  [[nodiscard]] bool motor_switchable() const noexcept { return motor_switchable_; }
  /// Stops scanning (STOP) and the motor; the next poll starts again.
  void shutdown() noexcept;

  [[nodiscard]] std::vector<std::string> take_faults() override;

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_poll(Time now) noexcept override;

 private:
  void step(Time now) noexcept;
  void send(rplidar::Command cmd) noexcept;
  void enter(State s, Time now) noexcept;
  enum class Fault : std::uint8_t { stalled, port_lost, no_answer, garbage, health_error };
  void fail(Fault fault, std::string_view detail, Time now) noexcept;
  void raise_fault(Fault fault) noexcept;
  // Looks for the descriptor `expected` in rx_; true when found (rx_ then starts past it).
  bool take_descriptor(const rplidar::Descriptor& expected, std::string_view request, Time now) noexcept;
  void read_available() noexcept;
  void consume(std::size_t n) noexcept;

  std::unique_ptr<ByteStream> owned_;
  ByteStream& stream_;
  RplidarConfig config_;
  MotorSwitch* motor_ = nullptr;
  std::unique_ptr<MotorSwitch> own_motor_;
  bool motor_switchable_ = true;
  State state_ = State::starting;
  Time entered_{};
  Time last_start_{};
  bool started_ = false;   // a first poll happened
  bool reported_ = false;  // the current failure's fault was raised (until the next scan)
  bool port_lost_ = false;
  bool rebase_ = false;           // opened on another clock than the loop's
  bool have_descriptor_ = false;  // the awaited answer's descriptor was read, its data not yet
  std::string garbage_head_;      // the first garbage bytes, in hex, for the error
  std::array<std::uint8_t, 512> rx_{};
  std::size_t rx_size_ = 0;
  std::size_t garbage_ = 0;
  rplidar::NodeDecoder decoder_;
  rplidar::ScanAssembler assembler_;
  rplidar::DeviceInfo info_;
  rplidar::Health health_;
  RplidarStats stats_;
  std::string error_;
  // Faults raised on the loop's thread, taken on the sequencing loop's: one pending count per kind,
  // so raising one neither locks nor allocates.
  std::array<std::atomic<std::uint32_t>, 5> pending_{};
};

[[nodiscard]] std::string_view to_string(RplidarA1::State s) noexcept;

/// The driver's configuration from the resolved parameters of static_manifest().
[[nodiscard]] RplidarConfig rplidar_config(const ParameterSet& p);

/// A profile's resource of type "RplidarA1": opened on its `port` (RplidarA1::open, the port's own
/// steady clock). Throws ConfigError at `where` with the open's reason.
[[nodiscard]] std::unique_ptr<RplidarA1> open_rplidar_resource(const std::string& name, const ParameterSet& p,
                                                               const SourceLocation& where);

/// Adds the resource type "RplidarA1" to a robot's resource registry (RobotPlugins::resources): the
/// lidar as a profile's `resources:` entry, beside any hardware. A template over the registry, as
/// dds::register_dds_modules, so that this area needs not link the robot's.
template <class ResourceRegistry>
void register_rplidar_resource(ResourceRegistry& resources) {
  resources.add(RplidarA1::static_manifest(), [](const auto& config) -> std::unique_ptr<CResource> {
    return open_rplidar_resource(config.name, config.parameters, config.where);
  });
}

}  // namespace tripodal::board
