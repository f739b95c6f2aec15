#include "tripodal/board/commands.hpp"

#include <cstring>

namespace tripodal::board {

std::string_view to_string(Command command) noexcept {
  switch (command) {
    case Command::sync: return "SYNC";
    case Command::status: return "STATUS";
    case Command::set_wheel_speeds: return "SET_WHEEL_SPEEDS";
    case Command::read_encoders: return "READ_ENCODERS";
    case Command::drive: return "DRIVE";
    case Command::battery: return "BATTERY";
    case Command::ultrasonic: return "ULTRASONIC";
    case Command::infrared: return "INFRARED";
    case Command::bump: return "BUMP";
    case Command::liquid_level: return "LIQUID_LEVEL";
    case Command::buttons: return "BUTTONS";
    case Command::atomizer: return "ATOMIZER";
    case Command::uv_lamp: return "UV_LAMP";
    case Command::voice: return "VOICE";
    case Command::lcd_text: return "LCD_TEXT";
  }
  return "?";
}

std::optional<Command> command_of(std::uint8_t cmd) noexcept {
  switch (cmd) {
    case 0x00: case 0x01: case 0x10: case 0x11: case 0x12: case 0x20: case 0x21: case 0x22:
    case 0x23: case 0x24: case 0x25: case 0x30: case 0x31: case 0x32: case 0x33:
      return static_cast<Command>(cmd);
    default: return std::nullopt;
  }
}

std::string_view to_string(ErrorCode code) noexcept {
  switch (code) {
    case ErrorCode::checksum: return "checksum";
    case ErrorCode::not_synchronised: return "not synchronised";
    case ErrorCode::wrong_type: return "wrong TYPE";
    case ErrorCode::unknown_command: return "unknown command";
    case ErrorCode::overflow: return "overflow";
    case ErrorCode::bad_payload: return "bad payload";
  }
  return "?";
}

bool ByteWriter::room(std::size_t n) noexcept {
  if (failed_ || out_.size() - size_ < n) {
    failed_ = true;
    return false;
  }
  return true;
}
void ByteWriter::u8(std::uint8_t v) noexcept {
  if (room(1)) out_[size_++] = v;
}
void ByteWriter::u16(std::uint16_t v) noexcept {
  if (!room(2)) return;
  out_[size_++] = static_cast<std::uint8_t>(v & 0xFFU);
  out_[size_++] = static_cast<std::uint8_t>(v >> 8);
}
void ByteWriter::u32(std::uint32_t v) noexcept {
  if (!room(4)) return;
  for (int i = 0; i < 4; ++i) out_[size_++] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFFU);
}
void ByteWriter::bytes(std::span<const std::uint8_t> v) noexcept {
  if (!room(v.size()) || v.empty()) return;
  std::memcpy(out_.data() + size_, v.data(), v.size());
  size_ += v.size();
}

bool ByteReader::has(std::size_t n) noexcept {
  if (failed_ || in_.size() - pos_ < n) {
    failed_ = true;
    return false;
  }
  return true;
}
std::uint8_t ByteReader::u8() noexcept { return has(1) ? in_[pos_++] : 0; }
std::uint16_t ByteReader::u16() noexcept {
  if (!has(2)) return 0;
  const auto v = static_cast<std::uint16_t>(in_[pos_] | (in_[pos_ + 1] << 8));
  pos_ += 2;
  return v;
}
std::uint32_t ByteReader::u32() noexcept {
  if (!has(4)) return 0;
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | in_[pos_ + static_cast<std::size_t>(i)];
  pos_ += 4;
  return v;
}

void pack(ByteWriter& w, const WheelSpeeds& v) noexcept {
  w.i16(v.left_mm_s);
  w.i16(v.right_mm_s);
}
void pack(ByteWriter& w, const EncoderState& v) noexcept {
  w.i32(v.left_pulses);
  w.i32(v.right_pulses);
  w.i16(v.left_mm_s);
  w.i16(v.right_mm_s);
}
void pack(ByteWriter& w, const DriveState& v) noexcept {
  pack(w, v.encoders);
  w.u32(v.sensors);
  w.u8(v.buttons);
  w.u8(v.status);
}
void pack(ByteWriter& w, const BatteryState& v) noexcept {
  w.u8(v.percent);
  w.u8(v.charging ? 1 : 0);
  w.u16(v.voltage_mv);
}
void pack(ByteWriter& w, const BoardStatus& v) noexcept {
  w.u8(v.flags);
  w.u32(v.tick_ms);
  w.u16(v.rx_frames);
  w.u16(v.rx_errors);
}

namespace {
template <class T>
std::optional<T> finish(const ByteReader& r, const T& v) noexcept {
  return r.done() ? std::optional<T>(v) : std::nullopt;
}
EncoderState read_encoders(ByteReader& r) noexcept {
  EncoderState v;
  v.left_pulses = r.i32();
  v.right_pulses = r.i32();
  v.left_mm_s = r.i16();
  v.right_mm_s = r.i16();
  return v;
}
}  // namespace

std::optional<WheelSpeeds> unpack_wheel_speeds(std::span<const std::uint8_t> p) noexcept {
  ByteReader r(p);
  WheelSpeeds v;
  v.left_mm_s = r.i16();
  v.right_mm_s = r.i16();
  return finish(r, v);
}
std::optional<EncoderState> unpack_encoders(std::span<const std::uint8_t> p) noexcept {
  ByteReader r(p);
  const EncoderState v = read_encoders(r);
  return finish(r, v);
}
std::optional<DriveState> unpack_drive(std::span<const std::uint8_t> p) noexcept {
  ByteReader r(p);
  DriveState v;
  v.encoders = read_encoders(r);
  v.sensors = r.u32();
  v.buttons = r.u8();
  v.status = r.u8();
  return finish(r, v);
}
std::optional<BatteryState> unpack_battery(std::span<const std::uint8_t> p) noexcept {
  ByteReader r(p);
  BatteryState v;
  v.percent = r.u8();
  v.charging = r.u8() != 0;
  v.voltage_mv = r.u16();
  return finish(r, v);
}
std::optional<BoardStatus> unpack_status(std::span<const std::uint8_t> p) noexcept {
  ByteReader r(p);
  BoardStatus v;
  v.flags = r.u8();
  v.tick_ms = r.u32();
  v.rx_frames = r.u16();
  v.rx_errors = r.u16();
  return finish(r, v);
}

std::optional<ErrorCode> Response::error() const noexcept {
  if (!is_error() || payload.empty()) return std::nullopt;
  const std::uint8_t c = payload[0];
  if (c < 0x01 || c > 0x06) return std::nullopt;
  return static_cast<ErrorCode>(c);
}

std::optional<Response> parse_response(std::span<const std::uint8_t> body) noexcept {
  if (body.empty()) return std::nullopt;
  return Response{body[0], body.subspan(1)};
}

std::optional<Request> parse_request(std::span<const std::uint8_t> body) noexcept {
  if (body.size() < 2) return std::nullopt;
  return Request{body[0], body[1], body.subspan(2)};
}

}  // namespace tripodal::board
