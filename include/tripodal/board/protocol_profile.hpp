// A control board's protocol dialect as data (docs/board-protocol.md, "Protocol profiles"): the
// command table (ids, payload layouts), the Length rule, the checksum and the CheckSumEn handling,
// the error codes, the SYNC echo, the Flags and the buffer size, read once from a YAML profile.
// The framing (frame.hpp) takes its FrameFormat; the host link and the firmware model take the
// whole profile. The default, configs/board/thesis.yaml, reads seed 001 section 3.3 literally
// (built in: its text is compiled into the library); configs/board/tripodal-v1.yaml is the
// dialect this project spoke before profiles existed.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/board/commands.hpp"
#include "tripodal/core/diagnostic.hpp"

namespace tripodal::board {

/// What CHKSUM is computed with, over every byte of the frame before it.
enum class ChecksumKind : std::uint8_t {
  crc8_smbus,  ///< CRC-8, polynomial 0x07, init 0, no reflection, no final XOR (check 0xF4)
  sum8,        ///< the bytes' sum modulo 256
  xor8,        ///< the bytes' XOR
  none,        ///< no CHKSUM byte (the Flags' CheckSumEn bit clear)
};
inline constexpr std::size_t kChecksumKindCount = 4;
/// "CRC-8/SMBUS", "8-bit sum", "XOR", "none".
[[nodiscard]] std::string_view to_string(ChecksumKind kind) noexcept;
/// The checksum of `bytes` (0 for none).
[[nodiscard]] std::uint8_t checksum(ChecksumKind kind, std::span<const std::uint8_t> bytes) noexcept;

/// What a request's Length counts (a response's is always Resp + payload).
enum class LengthRule : std::uint8_t {
  cmd_payload,       ///< CMD + payload: the thesis ("the sum of the length of the Payload field and one")
  type_cmd_payload,  ///< TYPE + CMD + payload: tripodal-v1
};
/// "CMD + payload", "TYPE + CMD + payload".
[[nodiscard]] std::string_view to_string(LengthRule rule) noexcept;

/// What the framing needs of a profile: small, copied into every decoder, no allocation.
struct FrameFormat {
  std::uint8_t flag_short = 0x10;  ///< Table 3-2: CheckSumEn
  std::uint8_t flag_long = 0x50;   ///< Table 3-2: LongFrame | CheckSumEn
  std::uint8_t type_byte = 0xA8;   ///< Tables 3-3, 3-4
  LengthRule length_rule = LengthRule::cmd_payload;
  ChecksumKind checksum = ChecksumKind::crc8_smbus;
  /// Also accept frames whose Flag has CheckSumEn clear (0x00, 0x40), which carry no CHKSUM
  /// (Table 3-2 read as a per-frame choice); frames sent always set it.
  bool checksum_optional = false;
  std::uint16_t max_length = 512;      ///< the 512-byte buffers (Table 3-7, section 3.3.3)
  std::uint16_t max_short_length = 255;  ///< one Length byte; longer frames are long frames
};
/// The dialect of tripodal before profiles (Length counts TYPE): what frame.hpp's functions
/// without a format use, so their golden frames stay byte for byte.
inline constexpr FrameFormat kTripodalV1Format{0x10, 0x50, 0xA8, LengthRule::type_cmd_payload, ChecksumKind::crc8_smbus,
                                               false, 512, 255};

/// A payload field's wire type.
enum class FieldType : std::uint8_t { u8, i8, u16, i16, u32, i32, f32, bitmap8, bitmap16, bitmap32, bytes };
[[nodiscard]] std::string_view to_string(FieldType type) noexcept;
[[nodiscard]] std::size_t field_size(FieldType type) noexcept;  ///< bytes (1 for bytes: per element)

/// One field of a payload layout, little-endian. A value on the wire is the physical value
/// divided by `scale`, in `unit` (a range of 1.2 m with scale 0.001 is 1200).
struct FieldSpec {
  std::string name;
  FieldType type = FieldType::u8;
  std::string unit;      ///< SI (m, m/s, V, percent, pulses, ...); empty for a count or a code
  double scale = 1.0;    ///< physical value per wire unit
  /// Repeated: names of earlier fields whose sum is the count ("count"; "cliff_count+wall_count"),
  /// or "*" for as many as the payload holds (bytes); empty: exactly once.
  std::string repeat;
  std::size_t max_count = 1;  ///< most repetitions (the 512-byte buffer bounds the sum)
  SourceLocation where;
};

/// One command: its id and its layouts (a response to SYNC is the request echoed).
struct CommandSpec {
  Command command = Command::sync;
  std::uint8_t id = 0;
  std::vector<FieldSpec> request;
  std::vector<FieldSpec> response;
  /// The layout differs from the host's (order, types, scales): payloads are transcoded.
  bool request_transcoded = false;
  bool response_transcoded = false;
  SourceLocation where;
};
/// The most bytes a layout takes.
[[nodiscard]] std::size_t max_payload_bytes(const std::vector<FieldSpec>& layout) noexcept;
/// Rewrites a payload laid out as `from` into the layout `to` (the same fields by name, in any
/// order, type and scale): each value read as physical (wire x scale), written rounded and
/// saturated in the other's type and scale; a value at its unsigned type's largest (0xFFFF: no
/// echo) stays the largest. Returns the bytes written, or -1 when `in` does not fit `from` or
/// `out` is too small. No allocation.
[[nodiscard]] std::ptrdiff_t transcode(const std::vector<FieldSpec>& from, const std::vector<FieldSpec>& to,
                                       std::span<const std::uint8_t> in, std::span<std::uint8_t> out) noexcept;
/// The layouts this host and the firmware model implement for `command` (what a profile's are
/// transcoded to and from: the same fields, units and counts; order, types and scales may differ).
[[nodiscard]] const CommandSpec& builtin_command(Command command) noexcept;
/// Every command of the table, in the order of the Command enum.
[[nodiscard]] std::span<const Command> all_commands() noexcept;
inline constexpr std::size_t kCommandCount = 15;
inline constexpr std::size_t kErrorCodeCount = 6;

class ProtocolProfile {
 public:
  std::string name;         ///< "thesis", "tripodal-v1"
  std::string description;
  std::string source;       ///< the file it came from ("built-in thesis.yaml" for the embedded one)
  FrameFormat frame;
  /// A SYNC request is answered with the request frame itself, unchanged (section 3.3.3).
  bool sync_echo = true;
  std::uint8_t error_resp = 0xEE;
  std::vector<CommandSpec> commands;

  /// Builds the look-up tables; called by the loader once the fields are set.
  void index();
  [[nodiscard]] std::optional<std::uint8_t> id(Command command) const noexcept;
  [[nodiscard]] bool has(Command command) const noexcept { return id(command).has_value(); }
  /// The command of a CMD (or Resp) byte; nullopt for one not in this profile's table.
  [[nodiscard]] std::optional<Command> command_of(std::uint8_t id) const noexcept;
  [[nodiscard]] std::uint8_t code(ErrorCode code) const noexcept;
  [[nodiscard]] std::optional<ErrorCode> error_of(std::uint8_t code) const noexcept;
  void set_code(ErrorCode code, std::uint8_t value) noexcept;
  /// The command's spec in this profile; nullptr when it has none.
  [[nodiscard]] const CommandSpec* spec(Command command) const noexcept;
  /// "thesis (Length = CMD + payload, CRC-8/SMBUS)".
  [[nodiscard]] std::string summary() const;

 private:
  std::array<std::uint16_t, kCommandCount> id_of_{};  // 0x100: absent
  std::array<std::uint8_t, 256> command_at_{};         // index into all_commands() + 1; 0: none
  std::array<std::uint8_t, kErrorCodeCount> codes_{0x01, 0x02, 0x03, 0x04, 0x05, 0x06};
};

/// Reads a profile from YAML text: every problem of the file (unknown keys or field types,
/// duplicate ids, a payload longer than the buffer, a layout that differs from what the host
/// implements) is collected and thrown as one ConfigError, each at FILE:LINE:COL.
[[nodiscard]] ProtocolProfile parse_protocol_profile(std::string_view text, const std::string& file);
/// Reads the file (ConfigError as above, or "cannot read the file").
[[nodiscard]] ProtocolProfile load_protocol_profile(const std::filesystem::path& file);
/// The shipped profiles, parsed once from the text of configs/board/*.yaml compiled in.
[[nodiscard]] const ProtocolProfile& thesis_profile();
[[nodiscard]] const ProtocolProfile& tripodal_v1_profile();
/// The profile a robot names: "thesis" and "tripodal-v1" are the built-in ones; anything else a
/// file (relative to `base_dir`). Empty: the thesis.
[[nodiscard]] std::shared_ptr<const ProtocolProfile> resolve_protocol_profile(const std::string& name_or_path,
                                                                             const std::filesystem::path& base_dir);

}  // namespace tripodal::board
