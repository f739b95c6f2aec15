// The host side of the control-board link (the navigation board, the master of section 3.3.2):
// each control period it sends DRIVE with the wheel speeds (and at most one other request: a
// queued actuator command, or a sensor poll), matches the responses in order, and monitors the
// link: a missing, late or corrupt response marks the link lost within two control periods. No
// allocation and no waiting in a cycle; driven by the control loop's time.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/protocol_profile.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal::board {

struct LinkConfig {
  /// The dialect the board speaks (null: the thesis's, configs/board/thesis.yaml).
  std::shared_ptr<const ProtocolProfile> protocol;
  /// A response must be decoded within this of its request (the control period: the next cycle
  /// checks it).
  Duration response_timeout{std::chrono::milliseconds(10)};
  /// Consecutive missing, late or erroneous responses that make the link lost (1: the first).
  /// A stall of the host or the board misses every request in flight at once: misses less than
  /// response_timeout apart count once, so max_missed in a row means at least
  /// (max_missed - 1) x response_timeout without an answer after the first miss.
  std::uint32_t max_missed = 1;
  Duration battery_period{std::chrono::seconds(3)};
  Duration tank_period{std::chrono::seconds(1)};
  Duration ranges_period{std::chrono::milliseconds(100)};  ///< ultrasonic and infrared, alternately
  /// After the stream failed (the device went away): how often to open it again.
  Duration reopen_period{std::chrono::milliseconds(500)};
  /// How often the port's settings are read back and verified while all is well (another process
  /// may reconfigure the line under the host); they are also verified after every missed or
  /// erroneous response. A mismatch reopens the port (settings applied again) and resynchronises.
  Duration port_check_period{std::chrono::seconds(1)};
};

/// Link statistics, for the report and the tests.
struct LinkStats {
  std::uint64_t requests = 0;
  std::uint64_t responses = 0;
  std::uint64_t missed = 0;           ///< no response by the timeout (missing or late)
  std::uint64_t error_responses = 0;  ///< the board answered with an error code
  std::uint64_t retries = 0;          ///< actuator commands sent again
  std::uint64_t link_losses = 0;
  std::uint64_t resyncs = 0;
  std::uint64_t reopens = 0;          ///< the device opened again after a failure
  /// The device failed: a read failed, or its settings could not be read back (closed under the
  /// host, hung up, gone).
  std::uint64_t port_failures = 0;
  /// The port's settings read back differed from those it was opened with (`stty icanon echo`
  /// by another process): the port was reopened and configured again.
  std::uint64_t settings_changed = 0;
  std::uint64_t port_checks = 0;      ///< settings read back and verified while running
  /// The board answered "not synchronised" while the host held the link: its watchdog had stopped
  /// the motors (the board's own count is not on the wire; this is what the host learns of it).
  std::uint64_t watchdog_trips = 0;
  std::uint64_t bytes_sent = 0;      ///< written to the line by the host
  std::uint64_t bytes_received = 0;  ///< read from the line by the host
  /// Evidence that the board speaks another dialect: its frames failing our checksum but fitting
  /// another, or checksum errors it reports on requests framed right by our profile.
  std::uint64_t dialect_mismatches = 0;
  Duration max_round_trip{0};
  Duration last_round_trip{0};
  Duration total_round_trip{0};
};

/// An actuator command waiting for its acknowledgement (never dropped: sent again until acked).
struct ActuatorCommand {
  Command cmd = Command::uv_lamp;
  std::array<std::uint8_t, kMaxLcdText + 1> payload{};
  std::uint8_t size = 0;
};

class BoardLink {
 public:
  /// Builds its messages and takes the profile (the thesis's when none): may allocate, once.
  BoardLink(ByteStream& stream, const LinkConfig& config = {});

  /// One control cycle at `now`: takes the responses that arrived, times out the overdue ones,
  /// then sends SYNC (link not synchronised) or DRIVE with `speeds` and at most one other request.
  void cycle(Time now, WheelSpeeds speeds) noexcept;

  /// Queues an actuator command (UV lamp, atomizer, voice, LCD); false when the queue is full or
  /// the profile has no such command.
  bool queue(Command cmd, std::span<const std::uint8_t> payload) noexcept;

  [[nodiscard]] bool synchronised() const noexcept { return synchronised_; }
  /// Lost since the last check: true once per loss (the event to post).
  [[nodiscard]] bool take_link_lost() noexcept;
  [[nodiscard]] Time link_lost_at() const noexcept { return lost_at_; }
  /// When SYNC was last answered with the link not synchronised (stats().resyncs counts them).
  [[nodiscard]] Time synchronised_at() const noexcept { return synced_at_; }
  /// The latest DRIVE response and when it was received; sensors polled less often.
  [[nodiscard]] const DriveState& drive() const noexcept { return drive_; }
  [[nodiscard]] Time drive_stamp() const noexcept { return drive_stamp_; }
  [[nodiscard]] bool has_drive() const noexcept { return has_drive_; }
  [[nodiscard]] const BatteryState& battery() const noexcept { return battery_; }
  [[nodiscard]] bool has_battery() const noexcept { return has_battery_; }
  [[nodiscard]] std::uint8_t tank_percent() const noexcept { return tank_percent_; }
  [[nodiscard]] bool tank_empty() const noexcept { return tank_empty_; }
  /// Whether the liquid level module has answered yet (before that the tank reads 0 %).
  [[nodiscard]] bool has_tank() const noexcept { return has_tank_; }
  [[nodiscard]] std::span<const std::uint16_t> ultrasonic_mm() const noexcept { return {ultrasonic_.data(), ultrasonic_count_}; }
  [[nodiscard]] std::span<const std::uint16_t> infrared_mm() const noexcept { return {infrared_.data(), infrared_count_}; }
  [[nodiscard]] std::size_t cliff_count() const noexcept { return cliff_count_; }
  [[nodiscard]] std::size_t pending_actuator_commands() const noexcept { return queue_size_; }
  [[nodiscard]] const LinkStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const DecoderStats& decoder_stats() const noexcept { return decoder_.stats(); }
  /// The board seems to speak another dialect than the profile: what does not match, e.g.
  /// "protocol profile thesis expects CRC-8/SMBUS, the board's frames fit an 8-bit sum". Empty
  /// while nothing says so (two pieces of evidence are needed: one could be line noise).
  [[nodiscard]] std::string_view dialect_mismatch() const noexcept { return dialect_mismatch_; }
  [[nodiscard]] const ProtocolProfile& protocol() const noexcept { return profile_; }
  /// What the latest port check found wrong ("icanon on, expected off"); empty if none yet.
  [[nodiscard]] std::string_view last_port_fault() const noexcept { return last_port_fault_; }

 private:
  struct Outstanding {
    Command cmd = Command::sync;
    Time sent{};
    bool actuator = false;  // the queue's front: popped when acknowledged
  };
  void receive(Time now) noexcept;
  void on_frame(const FrameView& frame, Time now) noexcept;
  void miss(Time now, bool rescan = true) noexcept;
  void lose(Time now) noexcept;
  void fail_stream(Time now) noexcept;
  void check_port(Time now) noexcept;
  bool send(Command cmd, std::span<const std::uint8_t> payload, Time now, bool actuator) noexcept;
  void check_dialect() noexcept;

  ByteStream& stream_;
  LinkConfig config_;
  std::shared_ptr<const ProtocolProfile> protocol_;
  const ProtocolProfile& profile_;
  FrameDecoder decoder_;
  // The messages a mismatch may give, built once (no allocation in a cycle): one per checksum
  // the board's frames may fit, then the Length rule, then "it refuses our checksums".
  std::array<std::string, kChecksumKindCount + 2> mismatch_text_;
  std::string_view dialect_mismatch_;
  std::uint32_t refused_checksums_ = 0;  // consecutive checksum errors reported by the board
  std::array<std::uint8_t, 256> rx_{};
  std::array<std::uint8_t, kMaxFrameBytes> tx_{};
  std::array<std::uint8_t, kMaxLength> transcoded_{};  // a response's payload in the host's layout
  std::array<std::uint8_t, 16> sync_frame_{};
  std::size_t sync_size_ = 0;
  std::array<Outstanding, 4> outstanding_{};
  std::size_t outstanding_size_ = 0;
  std::array<ActuatorCommand, 8> queue_{};
  std::size_t queue_head_ = 0;
  std::size_t queue_size_ = 0;
  std::uint32_t consecutive_missed_ = 0;
  Time last_counted_miss_{};  // of consecutive_missed_'s latest increment
  bool synchronised_ = false;
  bool lost_pending_ = false;
  bool stream_failed_ = false;  // read or write failed: reopen every reopen_period
  Time next_reopen_{};
  Time next_port_check_{};
  bool check_port_now_ = false;  // a response was missed: verify the port before going on
  std::string_view last_port_fault_;
  Time lost_at_{};
  Time synced_at_{};
  Time next_battery_{}, next_tank_{}, next_ranges_{};
  bool ranges_toggle_ = false;
  DriveState drive_{};
  Time drive_stamp_{};
  bool has_drive_ = false;
  BatteryState battery_{};
  bool has_battery_ = false;
  std::uint8_t tank_percent_ = 0;
  bool tank_empty_ = false;
  bool has_tank_ = false;
  std::array<std::uint16_t, kMaxUltrasonic> ultrasonic_{};
  std::size_t ultrasonic_count_ = 0;
  std::array<std::uint16_t, 2 * kMaxInfrared> infrared_{};
  std::size_t infrared_count_ = 0;
  std::size_t cliff_count_ = 0;
  LinkStats stats_;
};

}  // namespace tripodal::board
