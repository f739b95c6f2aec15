#include "tripodal/board/protocol_profile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include "tripodal/board/frame.hpp"
#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal::board {
namespace detail {
extern const std::string_view kThesisProfileText;
extern const std::string_view kTripodalV1ProfileText;
}  // namespace detail

namespace {

constexpr std::array<std::uint8_t, 256> make_crc_table() noexcept {
  std::array<std::uint8_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned c = i;
    for (int bit = 0; bit < 8; ++bit) c = (c & 0x80U) != 0 ? ((c << 1) ^ 0x07U) & 0xFFU : (c << 1) & 0xFFU;
    table[i] = static_cast<std::uint8_t>(c);
  }
  return table;
}
constexpr std::array<std::uint8_t, 256> kCrcTable = make_crc_table();

constexpr std::array<Command, kCommandCount> kCommands{
    Command::sync,    Command::status,     Command::set_wheel_speeds, Command::read_encoders, Command::drive,
    Command::battery, Command::ultrasonic, Command::infrared,         Command::bump,          Command::liquid_level,
    Command::buttons, Command::atomizer,   Command::uv_lamp,          Command::voice,         Command::lcd_text};

std::size_t index_of(Command c) noexcept {
  return static_cast<std::size_t>(std::find(kCommands.begin(), kCommands.end(), c) - kCommands.begin());
}

constexpr std::array<ErrorCode, kErrorCodeCount> kErrorCodes{ErrorCode::checksum,        ErrorCode::not_synchronised,
                                                             ErrorCode::wrong_type,      ErrorCode::unknown_command,
                                                             ErrorCode::overflow,        ErrorCode::bad_payload};
constexpr std::array<std::string_view, kErrorCodeCount> kErrorKeys{"checksum",        "not_synchronised", "wrong_type",
                                                                   "unknown_command", "overflow",         "bad_payload"};

FieldSpec f(std::string name, FieldType type, std::string unit = {}, double scale = 1.0, std::string repeat = {},
            std::size_t max = 1) {
  FieldSpec s;
  s.name = std::move(name);
  s.type = type;
  s.unit = std::move(unit);
  s.scale = scale;
  s.repeat = std::move(repeat);
  s.max_count = max;
  return s;
}

std::vector<CommandSpec> make_builtins() {
  using T = FieldType;
  const std::vector<FieldSpec> speeds{f("left", T::i16, "m/s", 0.001), f("right", T::i16, "m/s", 0.001)};
  const std::vector<FieldSpec> encoders{f("left_pulses", T::i32, "pulses"), f("right_pulses", T::i32, "pulses"),
                                        f("left_speed", T::i16, "m/s", 0.001), f("right_speed", T::i16, "m/s", 0.001)};
  std::vector<FieldSpec> drive = encoders;
  drive.insert(drive.end(), {f("sensors", T::bitmap32), f("buttons", T::bitmap8), f("status", T::bitmap8)});
  std::vector<CommandSpec> b(kCommandCount);
  const auto set = [&](Command c, std::vector<FieldSpec> req, std::vector<FieldSpec> resp) {
    CommandSpec& s = b[index_of(c)];
    s.command = c;
    s.id = static_cast<std::uint8_t>(c);
    s.request = std::move(req);
    s.response = std::move(resp);
  };
  set(Command::sync, {}, {});
  set(Command::status, {},
      {f("flags", T::bitmap8), f("tick", T::u32, "s", 0.001), f("rx_frames", T::u16), f("rx_errors", T::u16)});
  set(Command::set_wheel_speeds, speeds, {});
  set(Command::read_encoders, {}, encoders);
  set(Command::drive, speeds, drive);
  set(Command::battery, {}, {f("percent", T::u8, "percent"), f("charging", T::u8), f("voltage", T::u16, "V", 0.001)});
  set(Command::ultrasonic, {}, {f("count", T::u8), f("range", T::u16, "m", 0.001, "count", kMaxUltrasonic)});
  set(Command::infrared, {},
      {f("cliff_count", T::u8), f("wall_count", T::u8), f("range", T::u16, "m", 0.001, "cliff_count+wall_count", 2 * kMaxInfrared)});
  set(Command::bump, {}, {f("sensors", T::bitmap32)});
  set(Command::liquid_level, {}, {f("level", T::u8, "percent"), f("empty", T::u8)});
  set(Command::buttons, {}, {f("held", T::bitmap8), f("pressed", T::bitmap8)});
  set(Command::atomizer, {f("atomizer", T::u8), f("fan", T::u8)}, {});
  set(Command::uv_lamp, {f("on", T::u8)}, {});
  set(Command::voice, {f("track", T::u8)}, {});
  set(Command::lcd_text, {f("line", T::u8), f("text", T::bytes, "", 1.0, "*", kMaxLcdText)}, {});
  return b;
}

const std::vector<CommandSpec>& builtins() {
  static const std::vector<CommandSpec> b = make_builtins();
  return b;
}

std::string describe_field(const FieldSpec& s) {
  std::string out = fmt::format("{{name: {}, type: {}", s.name, to_string(s.type));
  if (!s.unit.empty()) out += fmt::format(", unit: {}", s.unit);
  if (s.scale != 1.0) out += fmt::format(", scale: {}", s.scale);
  if (!s.repeat.empty()) out += fmt::format(", repeat: {}, max: {}", s.repeat, s.max_count);
  return out + "}";
}

bool same_field(const FieldSpec& a, const FieldSpec& b) noexcept {
  return a.name == b.name && a.type == b.type && a.unit == b.unit && std::abs(a.scale - b.scale) <= 1e-12 * std::abs(b.scale) &&
         a.repeat == b.repeat && (a.repeat.empty() || a.max_count == b.max_count);
}

bool same_layout(const std::vector<FieldSpec>& a, const std::vector<FieldSpec>& b) noexcept {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!same_field(a[i], b[i])) return false;
  }
  return true;
}

constexpr std::array<std::string_view, 11> kFieldTypeNames{"u8",      "i8",       "u16",      "i16",     "u32",  "i32",
                                                           "f32",     "bitmap8",  "bitmap16", "bitmap32", "bytes"};

// --- the loader ---

class Loader {
 public:
  Loader(const std::string& file, Diagnostics& d) : r_(file, d) {}

  ProtocolProfile load(const YAML::Node& root) {
    ProtocolProfile p;
    p.source = r_.file();
    if (!r_.expect_map(root, "protocol profile")) return p;
    r_.expect_keys(root, {"name", "description", "frame", "sync_echo", "errors", "commands"}, "protocol profile");
    if (auto n = text(r_.require(root, "name", "protocol profile", "its name, e.g. thesis"), "name", true)) p.name = *n;
    if (root["description"]) {
      if (auto t = text(root["description"], "description")) p.description = *t;
    }
    frame(r_.require(root, "frame", "protocol profile", "the framing: flags, type, length_rule, checksum, ..."), p.frame);
    if (root["sync_echo"]) {
      if (auto b = r_.boolean(root["sync_echo"], "sync_echo")) p.sync_echo = *b;
    }
    errors(r_.require(root, "errors", "protocol profile", "resp and the six error codes"), p);
    commands(r_.require(root, "commands", "protocol profile", "the command table"), p);
    return p;
  }

 private:
  // The reader's typed reads, after a missing key (already reported by require): nothing.
  std::optional<std::string> text(const YAML::Node& n, std::string_view what, bool non_empty = false) {
    return n ? r_.text(n, what, non_empty) : std::nullopt;
  }
  std::optional<std::string> choice(const YAML::Node& n, std::string_view what, yaml::KeyList choices) {
    return n ? r_.choice(n, what, choices) : std::nullopt;
  }
  std::optional<std::int64_t> integer(const YAML::Node& n, std::string_view what, std::int64_t lo, std::int64_t hi) {
    return n ? r_.integer(n, what, lo, hi) : std::nullopt;
  }

  std::optional<std::uint8_t> byte(const YAML::Node& node, std::string_view what) {
    if (!node) return std::nullopt;
    const std::optional<std::string> t = text(node, what, true);
    if (!t) return std::nullopt;
    std::size_t used = 0;
    unsigned long v = 0;
    bool ok = true;
    try {
      v = std::stoul(*t, &used, 0);
    } catch (const std::exception&) {
      ok = false;
    }
    if (!ok || used != t->size() || v > 0xFF) {
      r_.error(node, fmt::format("{}: expected a byte (0 to 255, or 0x00 to 0xFF), got '{}'", what, *t));
      return std::nullopt;
    }
    return static_cast<std::uint8_t>(v);
  }

  void frame(const YAML::Node& n, FrameFormat& out) {
    if (!n || !r_.expect_map(n, "frame")) return;
    r_.expect_keys(n, {"flag_short", "flag_long", "type", "length_rule", "max_length", "max_short_length", "checksum", "checksum_enable"},
                   "frame");
    if (auto b = byte(r_.require(n, "flag_short", "frame", "0x10 in the thesis"), "frame.flag_short")) out.flag_short = *b;
    if (auto b = byte(r_.require(n, "flag_long", "frame", "0x50 in the thesis"), "frame.flag_long")) out.flag_long = *b;
    if (auto b = byte(r_.require(n, "type", "frame", "0xA8 in the thesis"), "frame.type")) out.type_byte = *b;
    if (auto c = choice(r_.require(n, "length_rule", "frame", "cmd_payload or type_cmd_payload"), "frame.length_rule",
                           {"cmd_payload", "type_cmd_payload"})) {
      out.length_rule = *c == "cmd_payload" ? LengthRule::cmd_payload : LengthRule::type_cmd_payload;
    }
    if (n["max_length"]) {
      if (auto v = integer(n["max_length"], "frame.max_length", 2, static_cast<std::int64_t>(kMaxLength))) out.max_length = static_cast<std::uint16_t>(*v);
    }
    if (n["max_short_length"]) {
      if (auto v = integer(n["max_short_length"], "frame.max_short_length", 1, 255)) out.max_short_length = static_cast<std::uint16_t>(*v);
    }
    if (auto c = choice(r_.require(n, "checksum", "frame", "crc8_smbus, sum8, xor8 or none"), "frame.checksum",
                           {"crc8_smbus", "sum8", "xor8", "none"})) {
      out.checksum = *c == "crc8_smbus" ? ChecksumKind::crc8_smbus
                     : *c == "sum8"     ? ChecksumKind::sum8
                     : *c == "xor8"     ? ChecksumKind::xor8
                                        : ChecksumKind::none;
    }
    if (n["checksum_enable"]) {
      if (auto c = choice(n["checksum_enable"], "frame.checksum_enable", {"always", "optional"})) out.checksum_optional = *c == "optional";
    }
    // Table 3-2: bit 6 LongFrame, bit 4 CheckSumEn, the low four bits zero.
    const std::uint8_t chk = out.checksum == ChecksumKind::none ? 0 : kFlagChecksumEn;
    const auto check_flag = [&](const char* key, std::uint8_t flag, bool long_frame) {
      const std::uint8_t expected = static_cast<std::uint8_t>((long_frame ? kFlagLongFrame : 0) | chk);
      if (n[key] && flag != expected) {
        r_.error(n[key], fmt::format("frame.{}: 0x{:02X} does not fit Table 3-2 with checksum {}; expected 0x{:02X} (LongFrame {}, "
                                     "CheckSumEn {}, low bits 0)",
                                     key, flag, to_string(out.checksum), expected, long_frame ? 1 : 0, chk != 0 ? 1 : 0));
      }
    };
    check_flag("flag_short", out.flag_short, false);
    check_flag("flag_long", out.flag_long, true);
    if (out.checksum == ChecksumKind::none && out.checksum_optional && n["checksum_enable"]) {
      r_.error(n["checksum_enable"], "frame.checksum_enable: optional needs a checksum; with checksum none no frame has one");
    }
    if (n["max_short_length"] && out.max_short_length > out.max_length) {
      r_.error(n["max_short_length"], fmt::format("frame.max_short_length: {} is above max_length {}", out.max_short_length, out.max_length));
    }
  }

  void errors(const YAML::Node& n, ProtocolProfile& p) {
    if (!n || !r_.expect_map(n, "errors")) return;
    r_.expect_keys(n, {"resp", "checksum", "not_synchronised", "wrong_type", "unknown_command", "overflow", "bad_payload"}, "errors");
    const YAML::Node resp = r_.require(n, "resp", "errors", "the Resp byte of an error response");
    if (auto b = byte(resp, "errors.resp")) {
      p.error_resp = *b;
      if (p.frame.length_rule == LengthRule::cmd_payload && *b == p.frame.type_byte) {
        r_.error(resp, fmt::format("errors.resp: 0x{:02X} is the TYPE byte, which marks a SYNC echo among responses under "
                                   "length_rule cmd_payload",
                                   *b));
      }
    }
    std::map<std::uint8_t, std::string> seen;
    for (std::size_t i = 0; i < kErrorCodeCount; ++i) {
      const std::string key(kErrorKeys[i]);
      const YAML::Node v = r_.require(n, key, "errors", "its code byte");
      if (!v) continue;
      if (auto b = byte(v, "errors." + key)) {
        p.set_code(kErrorCodes[i], *b);
        if (auto [it, fresh] = seen.emplace(*b, key); !fresh) {
          r_.error(v, fmt::format("errors.{}: code 0x{:02X} is already the code of {}", key, *b, it->second));
        }
      }
    }
  }

  std::vector<FieldSpec> layout(const YAML::Node& n, const std::string& what) {
    std::vector<FieldSpec> out;
    if (!n || !r_.expect_list(n, what)) return out;
    for (std::size_t i = 0; i < n.size(); ++i) {
      const YAML::Node e = n[i];
      const std::string fw = fmt::format("{} field {}", what, i + 1);
      if (!r_.expect_map(e, fw)) continue;
      r_.expect_keys(e, {"name", "type", "unit", "scale", "repeat", "max"}, fw);
      FieldSpec s;
      s.where = r_.at(e);
      if (auto t = text(r_.require(e, "name", fw, "the field's name"), fw + " name", true)) s.name = *t;
      const YAML::Node type = r_.require(e, "type", fw, "u8, i8, u16, i16, u32, i32, f32, bitmap8, bitmap16, bitmap32 or bytes");
      if (type) {
        if (auto t = choice(type, fw + " type", {"u8", "i8", "u16", "i16", "u32", "i32", "f32", "bitmap8", "bitmap16", "bitmap32", "bytes"})) {
          s.type = static_cast<FieldType>(std::find(kFieldTypeNames.begin(), kFieldTypeNames.end(), *t) - kFieldTypeNames.begin());
        }
      }
      if (e["unit"]) {
        if (auto t = text(e["unit"], fw + " unit")) s.unit = *t;
      }
      if (e["scale"]) {
        if (auto v = r_.positive(e["scale"], fw + " scale")) s.scale = *v;
      }
      if (e["repeat"]) {
        if (auto t = text(e["repeat"], fw + " repeat", true)) s.repeat = *t;
        if (auto v = integer(r_.require(e, "max", fw, "the most repetitions"), fw + " max", 1, 65535)) s.max_count = static_cast<std::size_t>(*v);
        // Each name of a count must be an earlier, fixed field.
        if (s.repeat != "*") {
          std::size_t start = 0;
          while (start <= s.repeat.size()) {
            const std::size_t plus = std::min(s.repeat.find('+', start), s.repeat.size());
            const std::string ref = s.repeat.substr(start, plus - start);
            const bool known = std::any_of(out.begin(), out.end(), [&](const FieldSpec& x) { return x.name == ref && x.repeat.empty(); });
            if (!known) r_.error(e["repeat"], fmt::format("{} repeat: '{}' is not an earlier field of this layout", fw, ref));
            start = plus + 1;
          }
        }
      } else if (e["max"]) {
        r_.error(e["max"], fw + " max: only a repeated field has a max (repeat: COUNT_FIELD)");
      }
      if (s.type == FieldType::bytes && s.repeat.empty()) s.repeat = "*";
      out.push_back(std::move(s));
    }
    return out;
  }

  void commands(const YAML::Node& n, ProtocolProfile& p) {
    if (!n || !r_.expect_list(n, "commands")) return;
    std::map<std::uint8_t, std::string> ids;
    std::set<std::string> names;
    for (std::size_t i = 0; i < n.size(); ++i) {
      const YAML::Node e = n[i];
      const std::string what = fmt::format("commands[{}]", i);
      if (!r_.expect_map(e, what)) continue;
      r_.expect_keys(e, {"name", "id", "request", "response"}, what);
      CommandSpec c;
      c.where = r_.at(e);
      const YAML::Node name = r_.require(e, "name", what, "SYNC, STATUS, DRIVE, ...");
      std::optional<std::string> nm;
      if (name) nm = text(name, what + " name", true);
      std::optional<Command> command;
      if (nm) {
        for (Command k : kCommands) {
          if (to_string(k) == *nm) command = k;
        }
        if (!command) {
          std::string list;
          for (Command k : kCommands) list += std::string(list.empty() ? "" : ", ") + std::string(to_string(k));
          r_.error(name, fmt::format("{}: unknown command '{}'; this host implements: {}", what, *nm, list));
        } else if (!names.insert(*nm).second) {
          r_.error(name, fmt::format("{}: command {} is already in the table", what, *nm));
        }
      }
      const YAML::Node id = r_.require(e, "id", what, "its CMD byte");
      std::optional<std::uint8_t> idv;
      if (id) idv = byte(id, what + " id");
      const std::string label = nm ? *nm : what;
      if (idv) {
        if (auto [it, fresh] = ids.emplace(*idv, label); !fresh) {
          r_.error(id, fmt::format("{}: duplicate id 0x{:02X}: already the id of {}", label, *idv, it->second));
        }
        if (*idv == p.error_resp) r_.error(id, fmt::format("{}: id 0x{:02X} is the error Resp (errors.resp)", label, *idv));
        if (p.frame.length_rule == LengthRule::cmd_payload && *idv == p.frame.type_byte) {
          r_.error(id, fmt::format("{}: id 0x{:02X} is the TYPE byte, which marks a SYNC echo among responses under length_rule "
                                   "cmd_payload",
                                   label, *idv));
        }
      }
      c.request = layout(r_.require(e, "request", label, "the request's payload fields ([] for none)"), label + " request");
      c.response = layout(r_.require(e, "response", label, "the response's payload fields ([] for none)"), label + " response");
      if (!command || !idv) continue;
      c.command = *command;
      c.id = *idv;
      check_size(c.request, e["request"] ? e["request"] : e, label + " request", 1 + (p.frame.length_rule == LengthRule::type_cmd_payload ? 1 : 0),
                 p.frame.max_length);
      check_size(c.response, e["response"] ? e["response"] : e, label + " response", 1, p.frame.max_length);
      check_builtin(c, e);  // may mark the layouts as transcoded
      p.commands.push_back(std::move(c));
    }
    for (Command required : {Command::sync, Command::drive}) {
      if (names.count(std::string(to_string(required))) == 0) {
        r_.error(n, fmt::format("commands: no {}; the host needs SYNC and DRIVE at least", to_string(required)));
      }
    }
  }

  void check_size(const std::vector<FieldSpec>& layout, const YAML::Node& at, const std::string& what, std::size_t counted_header,
                  std::size_t max_length) {
    const std::size_t bytes = max_payload_bytes(layout);
    if (bytes + counted_header > max_length) {
      r_.error(at, fmt::format("{}: payload up to {} bytes, Length up to {}: longer than the {}-byte buffer (frame.max_length)", what,
                               bytes, bytes + counted_header, max_length));
    }
  }

  // A layout may differ from the one the host implements in its fields' order, types, scales and
  // repetition limits (the payload is transcoded, transcode()), not in what the fields are: the
  // same names, the same units, integers for integers, bitmaps for bitmaps, bytes for bytes, the
  // same counts, and no more repetitions than the host's arrays hold.
  void check_builtin(CommandSpec& c, const YAML::Node& e) {
    const CommandSpec& b = builtin_command(c.command);
    const auto kind = [](FieldType t) {
      return t == FieldType::bytes ? 2 : (t == FieldType::bitmap8 || t == FieldType::bitmap16 || t == FieldType::bitmap32) ? 1 : 0;
    };
    const auto compare = [&](const std::vector<FieldSpec>& got, const std::vector<FieldSpec>& want, const char* which) {
      const std::string what = fmt::format("{} {}", to_string(c.command), which);
      const YAML::Node list = e[which] ? e[which] : e;
      bool same = got.size() == want.size();
      for (std::size_t i = 0; same && i < got.size(); ++i) same = same_field(got[i], want[i]);
      if (same) return true;
      bool ok = true;
      for (std::size_t i = 0; i < got.size(); ++i) {
        const FieldSpec& g = got[i];
        const auto w = std::find_if(want.begin(), want.end(), [&](const FieldSpec& x) { return x.name == g.name; });
        const YAML::Node at = list.IsSequence() && i < list.size() ? list[i] : list;
        if (w == want.end()) {
          std::string names;
          for (const FieldSpec& x : want) names += (names.empty() ? "" : ", ") + x.name;
          r_.error(at, fmt::format("{} field {} '{}': not a field of {} (this host and the firmware model know: {})", what, i + 1, g.name,
                                   what, names.empty() ? "none" : names));
          ok = false;
          continue;
        }
        std::string problem;
        if (kind(g.type) != kind(w->type)) {
          problem = fmt::format("type {} cannot carry {}", to_string(g.type), to_string(w->type));
        } else if (g.unit != w->unit) {
          problem = fmt::format("unit '{}', expected '{}'", g.unit, w->unit);
        } else if (g.repeat != w->repeat) {
          problem = fmt::format("repeat '{}', expected '{}'", g.repeat, w->repeat);
        } else if (!g.repeat.empty() && g.max_count > w->max_count) {
          problem = fmt::format("max {}, more than the {} this host holds", g.max_count, w->max_count);
        }
        if (!problem.empty()) {
          r_.error(at, fmt::format("{} field {} '{}': {} (this host and the firmware model implement {})", what, i + 1, g.name, problem,
                                   describe_field(*w)));
          ok = false;
        }
      }
      for (const FieldSpec& w : want) {
        if (std::none_of(got.begin(), got.end(), [&](const FieldSpec& x) { return x.name == w.name; })) {
          r_.error(list, fmt::format("{}: no field '{}' (this host and the firmware model implement {})", what, w.name, describe_field(w)));
          ok = false;
        }
      }
      return !ok;  // an error already reported; otherwise a layout to transcode
    };
    c.request_transcoded = !compare(c.request, b.request, "request") && !same_layout(c.request, b.request);
    c.response_transcoded = !compare(c.response, b.response, "response") && !same_layout(c.response, b.response);
  }

  yaml::Reader r_;
};

}  // namespace

std::string_view to_string(ChecksumKind kind) noexcept {
  switch (kind) {
    case ChecksumKind::crc8_smbus: return "CRC-8/SMBUS";
    case ChecksumKind::sum8: return "8-bit sum";
    case ChecksumKind::xor8: return "XOR";
    case ChecksumKind::none: return "none";
  }
  return "?";
}

std::uint8_t checksum(ChecksumKind kind, std::span<const std::uint8_t> bytes) noexcept {
  std::uint8_t c = 0;
  switch (kind) {
    case ChecksumKind::crc8_smbus:
      for (std::uint8_t b : bytes) c = kCrcTable[static_cast<std::uint8_t>(c ^ b)];
      break;
    case ChecksumKind::sum8:
      for (std::uint8_t b : bytes) c = static_cast<std::uint8_t>(c + b);
      break;
    case ChecksumKind::xor8:
      for (std::uint8_t b : bytes) c = static_cast<std::uint8_t>(c ^ b);
      break;
    case ChecksumKind::none: break;
  }
  return c;
}

std::string_view to_string(LengthRule rule) noexcept {
  return rule == LengthRule::cmd_payload ? "CMD + payload" : "TYPE + CMD + payload";
}

std::string_view to_string(FieldType type) noexcept { return kFieldTypeNames[static_cast<std::size_t>(type)]; }

std::size_t field_size(FieldType type) noexcept {
  switch (type) {
    case FieldType::u8: case FieldType::i8: case FieldType::bitmap8: case FieldType::bytes: return 1;
    case FieldType::u16: case FieldType::i16: case FieldType::bitmap16: return 2;
    case FieldType::u32: case FieldType::i32: case FieldType::f32: case FieldType::bitmap32: return 4;
  }
  return 1;
}

std::size_t max_payload_bytes(const std::vector<FieldSpec>& layout) noexcept {
  std::size_t n = 0;
  for (const FieldSpec& s : layout) n += field_size(s.type) * (s.repeat.empty() ? 1 : s.max_count);
  return n;
}

const CommandSpec& builtin_command(Command command) noexcept { return builtins()[index_of(command)]; }

namespace {

struct Parsed {
  static constexpr std::size_t kMaxFields = 16;
  static constexpr std::size_t kMaxValues = 96;
  std::array<std::size_t, kMaxFields> first{};
  std::array<std::size_t, kMaxFields> count{};
  std::array<double, kMaxValues> value{};    // physical (wire * scale)
  std::array<bool, kMaxValues> saturated{};  // the wire value was its type's largest (a "no echo")
};

std::uint64_t read_le(const std::uint8_t* p, std::size_t n) noexcept {
  std::uint64_t v = 0;
  for (std::size_t i = n; i-- > 0;) v = (v << 8) | p[i];
  return v;
}

bool is_signed(FieldType t) noexcept { return t == FieldType::i8 || t == FieldType::i16 || t == FieldType::i32; }

std::size_t count_of(const std::vector<FieldSpec>& layout, const Parsed& parsed, const FieldSpec& f, std::size_t remaining) noexcept {
  if (f.repeat.empty()) return 1;
  if (f.repeat == "*") return remaining / field_size(f.type);
  std::size_t total = 0;
  std::size_t start = 0;
  while (start <= f.repeat.size()) {
    const std::size_t plus = std::min(f.repeat.find('+', start), f.repeat.size());
    const std::string_view ref = std::string_view(f.repeat).substr(start, plus - start);
    for (std::size_t i = 0; i < layout.size() && i < Parsed::kMaxFields; ++i) {
      if (layout[i].name == ref && parsed.count[i] == 1) total += static_cast<std::size_t>(std::llround(parsed.value[parsed.first[i]]));
    }
    start = plus + 1;
  }
  return total;
}

}  // namespace

std::ptrdiff_t transcode(const std::vector<FieldSpec>& from, const std::vector<FieldSpec>& to, std::span<const std::uint8_t> in,
                         std::span<std::uint8_t> out) noexcept {
  if (from.size() > Parsed::kMaxFields || to.size() > Parsed::kMaxFields) return -1;
  Parsed parsed;
  std::size_t pos = 0;
  std::size_t next = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const FieldSpec& f = from[i];
    const std::size_t size = field_size(f.type);
    const std::size_t n = count_of(from, parsed, f, in.size() - pos);
    if ((!f.repeat.empty() && n > f.max_count) || n * size > in.size() - pos || next + n > Parsed::kMaxValues) return -1;
    parsed.first[i] = next;
    parsed.count[i] = n;
    for (std::size_t k = 0; k < n; ++k, pos += size) {
      const std::uint64_t raw = read_le(in.data() + pos, size);
      double v = 0.0;
      if (f.type == FieldType::f32) {
        float x = 0.0F;
        const auto bits = static_cast<std::uint32_t>(raw);
        std::memcpy(&x, &bits, sizeof x);
        v = static_cast<double>(x);
      } else if (is_signed(f.type)) {
        const unsigned shift = static_cast<unsigned>(64 - 8 * size);
        v = static_cast<double>(static_cast<std::int64_t>(raw << shift) >> shift);
      } else {
        v = static_cast<double>(raw);
        parsed.saturated[next] = f.type != FieldType::bytes && raw == (std::uint64_t{1} << (8 * size)) - 1 && size > 1;
      }
      parsed.value[next++] = v * f.scale;
    }
  }
  if (pos != in.size()) return -1;
  std::size_t written = 0;
  for (const FieldSpec& t : to) {
    std::size_t src = Parsed::kMaxFields;
    for (std::size_t i = 0; i < from.size(); ++i) {
      if (from[i].name == t.name) src = i;
    }
    if (src == Parsed::kMaxFields) return -1;
    const std::size_t size = field_size(t.type);
    if (parsed.count[src] * size > out.size() - written) return -1;
    for (std::size_t k = 0; k < parsed.count[src]; ++k, written += size) {
      const std::size_t at = parsed.first[src] + k;
      std::uint64_t raw = 0;
      if (t.type == FieldType::f32) {
        const auto x = static_cast<float>(parsed.value[at] / t.scale);
        std::uint32_t bits = 0;
        std::memcpy(&bits, &x, sizeof bits);
        raw = bits;
      } else {
        const double bits = 8.0 * static_cast<double>(size);
        const double hi = is_signed(t.type) ? std::exp2(bits - 1) - 1 : std::exp2(bits) - 1;
        const double lo = is_signed(t.type) ? -std::exp2(bits - 1) : 0.0;
        // Rounded and saturated; a saturated value (no echo) stays saturated whatever the width.
        const double v = parsed.saturated[at] ? hi : std::clamp(std::round(parsed.value[at] / t.scale), lo, hi);
        raw = static_cast<std::uint64_t>(static_cast<std::int64_t>(v));
      }
      for (std::size_t b = 0; b < size; ++b) out[written + b] = static_cast<std::uint8_t>((raw >> (8 * b)) & 0xFFU);
    }
  }
  return static_cast<std::ptrdiff_t>(written);
}
std::span<const Command> all_commands() noexcept { return kCommands; }

void ProtocolProfile::index() {
  id_of_.fill(0x100);
  command_at_.fill(0);
  for (const CommandSpec& c : commands) {
    const std::size_t i = index_of(c.command);
    id_of_[i] = c.id;
    command_at_[c.id] = static_cast<std::uint8_t>(i + 1);
  }
}

std::optional<std::uint8_t> ProtocolProfile::id(Command command) const noexcept {
  const std::uint16_t v = id_of_[index_of(command)];
  return v > 0xFF ? std::nullopt : std::optional<std::uint8_t>(static_cast<std::uint8_t>(v));
}

std::optional<Command> ProtocolProfile::command_of(std::uint8_t id) const noexcept {
  const std::uint8_t i = command_at_[id];
  return i == 0 ? std::nullopt : std::optional<Command>(kCommands[i - 1U]);
}

std::uint8_t ProtocolProfile::code(ErrorCode code) const noexcept {
  return codes_[static_cast<std::size_t>(std::find(kErrorCodes.begin(), kErrorCodes.end(), code) - kErrorCodes.begin())];
}

std::optional<ErrorCode> ProtocolProfile::error_of(std::uint8_t code) const noexcept {
  for (std::size_t i = 0; i < kErrorCodeCount; ++i) {
    if (codes_[i] == code) return kErrorCodes[i];
  }
  return std::nullopt;
}

void ProtocolProfile::set_code(ErrorCode code, std::uint8_t value) noexcept {
  codes_[static_cast<std::size_t>(std::find(kErrorCodes.begin(), kErrorCodes.end(), code) - kErrorCodes.begin())] = value;
}

const CommandSpec* ProtocolProfile::spec(Command command) const noexcept {
  for (const CommandSpec& c : commands) {
    if (c.command == command) return &c;
  }
  return nullptr;
}

std::string ProtocolProfile::summary() const {
  return fmt::format("{} (Length = {}, {})", name, to_string(frame.length_rule), to_string(frame.checksum));
}

ProtocolProfile parse_protocol_profile(std::string_view text, const std::string& file) {
  Diagnostics d;
  const YAML::Node root = yaml::parse(text, file);
  ProtocolProfile p = yaml::guarded(file, [&] { return Loader(file, d).load(root); });
  if (d.has_errors()) throw ConfigError(std::move(d));
  p.index();
  return p;
}

ProtocolProfile load_protocol_profile(const std::filesystem::path& file) {
  return parse_protocol_profile(yaml::read_file(file), file.string());
}

const ProtocolProfile& thesis_profile() {
  static const ProtocolProfile p = parse_protocol_profile(detail::kThesisProfileText, "built-in configs/board/thesis.yaml");
  return p;
}

const ProtocolProfile& tripodal_v1_profile() {
  static const ProtocolProfile p = parse_protocol_profile(detail::kTripodalV1ProfileText, "built-in configs/board/tripodal-v1.yaml");
  return p;
}

std::shared_ptr<const ProtocolProfile> resolve_protocol_profile(const std::string& name_or_path,
                                                                const std::filesystem::path& base_dir) {
  // The built-in ones are static: share them without a copy.
  if (name_or_path.empty() || name_or_path == "thesis") return std::shared_ptr<const ProtocolProfile>(&thesis_profile(), [](const ProtocolProfile*) {});
  if (name_or_path == "tripodal-v1") return std::shared_ptr<const ProtocolProfile>(&tripodal_v1_profile(), [](const ProtocolProfile*) {});
  std::filesystem::path file(name_or_path);
  if (file.is_relative()) file = base_dir / file;
  return std::make_shared<const ProtocolProfile>(load_protocol_profile(file));
}

}  // namespace tripodal::board
