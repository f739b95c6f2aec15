// The command table of the control-board protocol (docs/board-protocol.md): the commands, the
// error codes and each command's payload as this host and the firmware model implement it, packed
// little-endian in integer SI-derived units (mm, mm/s, mV, encoder pulses). The bytes on the wire
// (CMD ids, error codes and Resp, layouts) are the protocol profile's (protocol_profile.hpp); the
// enum values below are the shipped profiles' ids. The board firmware (board_firmware.hpp) serves
// them; the host side (board_link.hpp) sends them. Packing writes into caller storage and never
// allocates.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace tripodal::board {

/// CMD of a request; a successful response carries the same byte as Resp.
enum class Command : std::uint8_t {
  sync = 0x00,              ///< echoed unchanged (the whole request frame); (re)synchronises the link
  status = 0x01,            ///< -> BoardStatus
  set_wheel_speeds = 0x10,  ///< WheelSpeeds -> (empty)
  read_encoders = 0x11,     ///< -> EncoderState
  drive = 0x12,             ///< WheelSpeeds -> DriveState: the control cycle's one exchange
  battery = 0x20,           ///< -> BatteryState
  ultrasonic = 0x21,        ///< -> u8 count, u16[count] mm
  infrared = 0x22,          ///< -> u8 cliff count, u8 wall count, u16[cliff + wall] mm
  bump = 0x23,              ///< -> u32 sensor bitmap (kBump*, kCliff*)
  liquid_level = 0x24,      ///< -> u8 percent, u8 empty
  buttons = 0x25,           ///< -> u8 held bitmap, u8 pressed since the last read (kButton*)
  atomizer = 0x30,          ///< u8 atomizer on, u8 fan on -> (empty)
  uv_lamp = 0x31,           ///< u8 on -> (empty)
  voice = 0x32,             ///< u8 WT2003S track index -> (empty)
  lcd_text = 0x33,          ///< u8 line, ASCII[0..32] -> (empty)
};
[[nodiscard]] std::string_view to_string(Command command) noexcept;
/// The Command of a CMD byte; nullopt for a byte not in the table.
[[nodiscard]] std::optional<Command> command_of(std::uint8_t cmd) noexcept;

/// Resp of an error response in the shipped profiles (ProtocolProfile::error_resp is the
/// dialect's); its payload is the error code, then the offending CMD (0 if unknown).
inline constexpr std::uint8_t kErrorResp = 0xEE;
enum class ErrorCode : std::uint8_t {
  checksum = 0x01,          ///< a frame whose CHKSUM did not match
  not_synchronised = 0x02,  ///< a command before SYNC (after power-on or a link loss)
  wrong_type = 0x03,        ///< TYPE other than 0xA8
  unknown_command = 0x04,   ///< CMD not in the table
  overflow = 0x05,          ///< Length above 512 (the receive buffer)
  bad_payload = 0x06,       ///< the payload's size does not fit the command
};
[[nodiscard]] std::string_view to_string(ErrorCode code) noexcept;

// The sensor bitmap (Figure 3-11: a 32-bit variable in segments, binary judgments only):
// bits 0-7 bump switches, bits 8-15 cliff judgments, bits 16-31 reserved.
inline constexpr std::uint32_t kBumpShift = 0;
inline constexpr std::uint32_t kCliffShift = 8;
inline constexpr std::uint32_t kSegmentMask = 0xFF;

// Button bits (the four push-buttons of the top panel).
inline constexpr std::uint8_t kButtonStart = 0x01;
inline constexpr std::uint8_t kButtonEmergencyStop = 0x02;
inline constexpr std::uint8_t kButtonPause = 0x04;
inline constexpr std::uint8_t kButtonHome = 0x08;

// Status flag bits.
inline constexpr std::uint8_t kStatusSynchronised = 0x01;
inline constexpr std::uint8_t kStatusLinkLost = 0x02;   ///< the watchdog stopped the motors (latched until SYNC)
inline constexpr std::uint8_t kStatusEmergencyStop = 0x04;
inline constexpr std::uint8_t kStatusUvLamp = 0x08;
inline constexpr std::uint8_t kStatusAtomizer = 0x10;

inline constexpr std::size_t kMaxUltrasonic = 8;
inline constexpr std::size_t kMaxInfrared = 8;
inline constexpr std::size_t kMaxLcdText = 32;
inline constexpr std::uint16_t kNoEcho = 0xFFFF;  ///< an ultrasonic or infrared range with no return

struct WheelSpeeds {
  std::int16_t left_mm_s = 0;
  std::int16_t right_mm_s = 0;
};
struct EncoderState {
  std::int32_t left_pulses = 0;   ///< accumulated, wraps at 2^31
  std::int32_t right_pulses = 0;
  std::int16_t left_mm_s = 0;     ///< measured over the last motor period
  std::int16_t right_mm_s = 0;
};
struct DriveState {
  EncoderState encoders;
  std::uint32_t sensors = 0;  ///< bitmap (kBumpShift, kCliffShift)
  std::uint8_t buttons = 0;   ///< held
  std::uint8_t status = 0;    ///< kStatus*
};
struct BatteryState {
  std::uint8_t percent = 0;   ///< 0..100, sampled every 3 s
  bool charging = false;
  std::uint16_t voltage_mv = 0;
};
struct BoardStatus {
  std::uint8_t flags = 0;         ///< kStatus*
  std::uint32_t tick_ms = 0;      ///< the board's 1 ms tick since power-on
  std::uint16_t rx_frames = 0;    ///< valid requests received (wraps)
  std::uint16_t rx_errors = 0;    ///< decoder errors (wraps)
};

/// Little-endian writer over caller storage; a write past the end sets failed() and writes nothing.
class ByteWriter {
 public:
  explicit ByteWriter(std::span<std::uint8_t> out) noexcept : out_(out) {}
  void u8(std::uint8_t v) noexcept;
  void u16(std::uint16_t v) noexcept;
  void u32(std::uint32_t v) noexcept;
  void i16(std::int16_t v) noexcept { u16(static_cast<std::uint16_t>(v)); }
  void i32(std::int32_t v) noexcept { u32(static_cast<std::uint32_t>(v)); }
  void bytes(std::span<const std::uint8_t> v) noexcept;
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] bool failed() const noexcept { return failed_; }
  [[nodiscard]] std::span<const std::uint8_t> written() const noexcept { return out_.first(size_); }

 private:
  bool room(std::size_t n) noexcept;
  std::span<std::uint8_t> out_;
  std::size_t size_ = 0;
  bool failed_ = false;
};

/// Little-endian reader; a read past the end sets failed() and yields 0.
class ByteReader {
 public:
  explicit ByteReader(std::span<const std::uint8_t> in) noexcept : in_(in) {}
  std::uint8_t u8() noexcept;
  std::uint16_t u16() noexcept;
  std::uint32_t u32() noexcept;
  std::int16_t i16() noexcept { return static_cast<std::int16_t>(u16()); }
  std::int32_t i32() noexcept { return static_cast<std::int32_t>(u32()); }
  [[nodiscard]] std::size_t remaining() const noexcept { return failed_ ? 0 : in_.size() - pos_; }
  [[nodiscard]] std::span<const std::uint8_t> rest() const noexcept { return in_.subspan(failed_ ? in_.size() : pos_); }
  [[nodiscard]] bool failed() const noexcept { return failed_; }
  /// All bytes read and none missing.
  [[nodiscard]] bool done() const noexcept { return !failed_ && pos_ == in_.size(); }

 private:
  bool has(std::size_t n) noexcept;
  std::span<const std::uint8_t> in_;
  std::size_t pos_ = 0;
  bool failed_ = false;
};

// Packing of each payload; unpack returns nullopt when the size is not exactly the payload's.
void pack(ByteWriter& w, const WheelSpeeds& v) noexcept;
void pack(ByteWriter& w, const EncoderState& v) noexcept;
void pack(ByteWriter& w, const DriveState& v) noexcept;
void pack(ByteWriter& w, const BatteryState& v) noexcept;
void pack(ByteWriter& w, const BoardStatus& v) noexcept;
[[nodiscard]] std::optional<WheelSpeeds> unpack_wheel_speeds(std::span<const std::uint8_t> p) noexcept;
[[nodiscard]] std::optional<EncoderState> unpack_encoders(std::span<const std::uint8_t> p) noexcept;
[[nodiscard]] std::optional<DriveState> unpack_drive(std::span<const std::uint8_t> p) noexcept;
[[nodiscard]] std::optional<BatteryState> unpack_battery(std::span<const std::uint8_t> p) noexcept;
[[nodiscard]] std::optional<BoardStatus> unpack_status(std::span<const std::uint8_t> p) noexcept;

/// A response body split into Resp and payload; error responses give their code and CMD.
struct Response {
  std::uint8_t resp = 0;
  std::span<const std::uint8_t> payload;
  [[nodiscard]] bool is_error() const noexcept { return resp == kErrorResp; }
  [[nodiscard]] std::optional<ErrorCode> error() const noexcept;
  [[nodiscard]] std::uint8_t error_cmd() const noexcept { return payload.size() >= 2 ? payload[1] : 0; }
};
/// A request body split into TYPE, CMD and payload.
struct Request {
  std::uint8_t type = 0;
  std::uint8_t cmd = 0;
  std::span<const std::uint8_t> payload;
};
/// Nullopt for an empty body.
[[nodiscard]] std::optional<Response> parse_response(std::span<const std::uint8_t> body) noexcept;
/// Nullopt for a body shorter than TYPE + CMD.
[[nodiscard]] std::optional<Request> parse_request(std::span<const std::uint8_t> body) noexcept;

}  // namespace tripodal::board
