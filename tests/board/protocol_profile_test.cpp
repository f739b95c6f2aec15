// Protocol profiles (issue 35): the thesis's literal reading against frames written by hand from
// Tables 3-3 to 3-6, the other checksums, the profile loader's located errors, every command
// round-tripped with the firmware model, and a board of another dialect named as such.
#include "tripodal/board/protocol_profile.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <fstream>
#include <sstream>
#include <cstdint>
#include <string>
#include <vector>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/board_hardware.hpp"
#include "tripodal/board/board_link.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/serial_line.hpp"
#include "still_plant.hpp"

using namespace tripodal;
using namespace tripodal::board;
using tripodal::board::test::StillPlant;
using namespace std::chrono_literals;

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Golden {
  Command command;
  Bytes payload;
  Bytes frame;
};

// Thesis requests (Table 3-4, short: Flag 0x10, Length [7:0], TYPE 0xA8, CMD, payload, CHKSUM),
// Length = CMD + payload = 1 + payload bytes ("the sum of the length of the Payload field and
// one", 3.3.2). CHKSUM: CRC-8/SMBUS over Flag..payload, worked bit by bit (poly 0x07, init 0),
// not by the encoder. Ids and payloads: configs/board/thesis.yaml.
const std::vector<Golden>& thesis_requests() {
  static const std::vector<Golden> g = {
    // Length 1 + 0 = 1
    {Command::sync, {}, {0x10, 0x01, 0xA8, 0x00, 0xBC}},
    {Command::status, {}, {0x10, 0x01, 0xA8, 0x01, 0xBB}},
    // left 300 mm/s = 0x012C, right -300 = 0xFED4 (i16 LE, scale 0.001 m/s); Length 1 + 4 = 5
    {Command::set_wheel_speeds, {0x2C, 0x01, 0xD4, 0xFE}, {0x10, 0x05, 0xA8, 0x10, 0x2C, 0x01, 0xD4, 0xFE, 0x60}},
    {Command::read_encoders, {}, {0x10, 0x01, 0xA8, 0x11, 0xCB}},
    // left 200 = 0x00C8, right 250 = 0x00FA; Length 1 + 4 = 5
    {Command::drive, {0xC8, 0x00, 0xFA, 0x00}, {0x10, 0x05, 0xA8, 0x12, 0xC8, 0x00, 0xFA, 0x00, 0x7F}},
    {Command::battery, {}, {0x10, 0x01, 0xA8, 0x20, 0x5C}},
    {Command::ultrasonic, {}, {0x10, 0x01, 0xA8, 0x21, 0x5B}},
    {Command::infrared, {}, {0x10, 0x01, 0xA8, 0x22, 0x52}},
    {Command::bump, {}, {0x10, 0x01, 0xA8, 0x23, 0x55}},
    {Command::liquid_level, {}, {0x10, 0x01, 0xA8, 0x24, 0x40}},
    {Command::buttons, {}, {0x10, 0x01, 0xA8, 0x25, 0x47}},
    // atomizer on, fan on; Length 1 + 2 = 3
    {Command::atomizer, {0x01, 0x01}, {0x10, 0x03, 0xA8, 0x30, 0x01, 0x01, 0x84}},
    // Length 1 + 1 = 2
    {Command::uv_lamp, {0x01}, {0x10, 0x02, 0xA8, 0x31, 0x01, 0xEC}},
    {Command::voice, {0x05}, {0x10, 0x02, 0xA8, 0x32, 0x05, 0xCF}},
    // line 0, "UV ON" (55 56 20 4F 4E); Length 1 + 6 = 7
    {Command::lcd_text, {0x00, 0x55, 0x56, 0x20, 0x4F, 0x4E}, {0x10, 0x07, 0xA8, 0x33, 0x00, 0x55, 0x56, 0x20, 0x4F, 0x4E, 0x0E}},
  };
  return g;
}

std::string read_file_text(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

Bytes concat_bytes(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::string thesis_text_with(const std::string& from, const std::string& to) {
  std::string text = read_file_text(TRIPODAL_SOURCE_DIR "/configs/board/thesis.yaml");
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  text.replace(at, from.size(), to);
  return text;
}

Bytes encode(const FrameFormat& f, Command c, std::uint8_t id, const Bytes& payload) {
  (void)c;
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  const std::size_t n = encode_request(id, payload, out, f);
  return Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
}

std::vector<Bytes> decode_all(FrameDecoder& d, const Bytes& in) {
  std::vector<Bytes> frames;
  d.feed(in, [&](const FrameView& f) { frames.emplace_back(f.bytes.begin(), f.bytes.end()); });
  return frames;
}

// Host (BoardLink) and board (BoardFirmware) on one simulated line, each with its own profile.
struct Pair {
  SimClock clock;
  SerialLine line{clock};
  StillPlant plant;
  BoardFirmware board;
  BoardLink link;
  static FirmwareConfig firmware(std::shared_ptr<const ProtocolProfile> p) {
    FirmwareConfig c;
    c.protocol = std::move(p);
    return c;
  }
  static LinkConfig host(std::shared_ptr<const ProtocolProfile> p) {
    LinkConfig c;
    c.protocol = std::move(p);
    return c;
  }
  Pair(std::shared_ptr<const ProtocolProfile> host_profile, std::shared_ptr<const ProtocolProfile> board_profile)
      : board(firmware(std::move(board_profile)), line.board(), plant), link(line.host(), host(std::move(host_profile))) {}
  void run_for(Duration d) {
    const Time end = clock.now() + d;
    while (clock.now() < end) {
      clock.advance(1ms);
      board.run_until(clock.now());
      if (to_ns(clock.now()) % 10'000'000 == 0) link.cycle(clock.now(), WheelSpeeds{200, 200});
    }
  }
};

std::shared_ptr<const ProtocolProfile> shared(ProtocolProfile p) { return std::make_shared<const ProtocolProfile>(std::move(p)); }

}  // namespace

TEST_CASE("the thesis profile reads section 3.3 literally and is the default", "[board][protocol]") {
  const ProtocolProfile& p = thesis_profile();
  CHECK(p.name == "thesis");
  CHECK(p.frame.length_rule == LengthRule::cmd_payload);
  CHECK(p.frame.flag_short == 0x10);
  CHECK(p.frame.flag_long == 0x50);
  CHECK(p.frame.type_byte == 0xA8);
  CHECK(p.frame.max_length == 512);
  CHECK(p.frame.checksum == ChecksumKind::crc8_smbus);
  CHECK_FALSE(p.frame.checksum_optional);
  CHECK(p.sync_echo);
  CHECK(p.commands.size() == kCommandCount);
  CHECK(p.summary() == "thesis (Length = CMD + payload, CRC-8/SMBUS)");
  // The built-in is the shipped file, byte for byte (compiled in).
  const ProtocolProfile file = load_protocol_profile(TRIPODAL_SOURCE_DIR "/configs/board/thesis.yaml");
  CHECK(file.frame.length_rule == p.frame.length_rule);
  CHECK(file.commands.size() == p.commands.size());
  const ProtocolProfile v1 = load_protocol_profile(TRIPODAL_SOURCE_DIR "/configs/board/tripodal-v1.yaml");
  CHECK(v1.name == "tripodal-v1");
  CHECK(v1.frame.length_rule == LengthRule::type_cmd_payload);
  CHECK(tripodal_v1_profile().frame.length_rule == LengthRule::type_cmd_payload);
  // Nothing named: the thesis's, for the host and for the firmware model.
  CHECK(resolve_protocol_profile("", {})->name == "thesis");
  StillPlant plant;
  SimClock clock;
  SerialLine line{clock};
  CHECK(BoardFirmware(FirmwareConfig{}, line.board(), plant).protocol().name == "thesis");
  CHECK(BoardLink(line.host()).protocol().name == "thesis");
  // The checksum's check value (CRC-8/SMBUS catalogue: 0xF4 over "123456789").
  const std::string check = "123456789";
  CHECK(checksum(ChecksumKind::crc8_smbus, std::span(reinterpret_cast<const std::uint8_t*>(check.data()), check.size())) == 0xF4);
}

TEST_CASE("golden frames of the thesis profile: requests count CMD + payload, written by hand", "[board][protocol][golden]") {
  const ProtocolProfile& p = thesis_profile();
  for (const Golden& g : thesis_requests()) {
    INFO(to_string(g.command));
    REQUIRE(p.id(g.command).has_value());
    CHECK(encode(p.frame, g.command, *p.id(g.command), g.payload) == g.frame);
    // The board's decoder reads TYPE outside Length, and finds each frame.
    FrameDecoder board(p.frame, FrameSide::requests);
    const auto frames = decode_all(board, g.frame);
    REQUIRE(frames.size() == 1);
    CHECK(board.frame().body.size() == 2 + g.payload.size());  // TYPE, CMD, payload
    CHECK(board.frame().body[0] == 0xA8);
    CHECK(board.stats().errors() == 0);
  }
  // All requests in one stream, split at every byte: still each one, no error.
  Bytes stream;
  for (const Golden& g : thesis_requests()) stream.insert(stream.end(), g.frame.begin(), g.frame.end());
  FrameDecoder split(p.frame, FrameSide::requests);
  std::size_t found = 0;
  for (std::uint8_t b : stream) found += split.feed(Bytes{b});
  CHECK(found == thesis_requests().size());
  CHECK(split.stats().errors() == 0);

  // A long request (Table 3-3: Flag 0x50, Len [7:0], LenH [15:8]) may carry a small Length:
  // SYNC, Len 0x01 LenH 0x00 (1 = CMD), CRC-8 over 50 01 00 A8 00 = 0x5C.
  FrameDecoder long_frame(p.frame, FrameSide::requests);
  REQUIRE(decode_all(long_frame, Bytes{0x50, 0x01, 0x00, 0xA8, 0x00, 0x5C}).size() == 1);
  CHECK(long_frame.frame().long_frame);
  CHECK(long_frame.frame().body.size() == 2);

  // Responses (Table 3-6): Length = Resp + payload, as in tripodal-v1.
  // DRIVE response: Resp 0x12, then 5000 and 5200 pulses (i32: 88 13 00 00, 50 14 00 00), 198 and
  // 251 mm/s (i16: C6 00, FB 00), bitmap 0x00000102 (bump 1, cliff 0), buttons 0x01, status 0x01;
  // Length = 1 + 18 = 0x13; the same bytes as tripodal-v1's (frame_test.cpp).
  const Bytes drive_response{0x10, 0x13, 0x12, 0x88, 0x13, 0x00, 0x00, 0x50, 0x14, 0x00, 0x00, 0xC6,
                             0x00, 0xFB, 0x00, 0x02, 0x01, 0x00, 0x00, 0x01, 0x01, 0x44};
  FrameDecoder host(p.frame, FrameSide::responses);
  REQUIRE(decode_all(host, drive_response).size() == 1);
  CHECK(host.frame().body.size() == 0x13);
  // Error response: Resp 0xEE, code 0x01 (checksum), CMD 0x00; Length 1 + 2 = 3; CHKSUM 0xFF.
  const Bytes checksum_error{0x10, 0x03, 0xEE, 0x01, 0x00, 0xFF};
  std::array<std::uint8_t, 16> out{};
  const std::array<std::uint8_t, 2> code{0x01, 0x00};
  const std::size_t n = encode_response(0xEE, code, out, p.frame);
  CHECK(Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n)) == checksum_error);

  // The SYNC echo (3.3.3: "the unchanged data packet back"): a response that keeps TYPE outside
  // Length; the host's decoder knows it by the TYPE byte after Length.
  FrameDecoder echo(p.frame, FrameSide::responses);
  const Bytes sync = thesis_requests()[0].frame;
  REQUIRE(decode_all(echo, concat_bytes(sync, checksum_error)).size() == 2);
  CHECK(echo.stats().errors() == 0);
}

TEST_CASE("golden frames of the other checksums: 8-bit sum, XOR, none", "[board][protocol][golden]") {
  SECTION("8-bit sum") {
    const ProtocolProfile p = parse_protocol_profile(thesis_text_with("checksum: crc8_smbus", "checksum: sum8"), "sum8.yaml");
    // DRIVE, left 200 right 250: 10+05+A8+12+C8+00+FA+00 = 16+5+168+18+200+0+250+0 = 657 = 0x291 -> 0x91
    CHECK(encode(p.frame, Command::drive, 0x12, {0xC8, 0x00, 0xFA, 0x00}) == Bytes{0x10, 0x05, 0xA8, 0x12, 0xC8, 0x00, 0xFA, 0x00, 0x91});
    // SYNC: 10+01+A8+00 = 16+1+168 = 185 = 0xB9
    CHECK(encode(p.frame, Command::sync, 0x00, {}) == Bytes{0x10, 0x01, 0xA8, 0x00, 0xB9});
  }
  SECTION("XOR") {
    const ProtocolProfile p = parse_protocol_profile(thesis_text_with("checksum: crc8_smbus", "checksum: xor8"), "xor8.yaml");
    // 10^05 = 15, ^A8 = BD, ^12 = AF, ^C8 = 67, ^00 = 67, ^FA = 9D, ^00 = 9D
    CHECK(encode(p.frame, Command::drive, 0x12, {0xC8, 0x00, 0xFA, 0x00}) == Bytes{0x10, 0x05, 0xA8, 0x12, 0xC8, 0x00, 0xFA, 0x00, 0x9D});
  }
  SECTION("none: CheckSumEn clear (Table 3-2), no CHKSUM byte") {
    std::string text = thesis_text_with("checksum: crc8_smbus", "checksum: none");
    text.replace(text.find("flag_short: 0x10"), 16, "flag_short: 0x00");
    text.replace(text.find("flag_long: 0x50"), 15, "flag_long: 0x40");
    const ProtocolProfile p = parse_protocol_profile(text, "none.yaml");
    const Bytes drive{0x00, 0x05, 0xA8, 0x12, 0xC8, 0x00, 0xFA, 0x00};
    CHECK(encode(p.frame, Command::drive, 0x12, {0xC8, 0x00, 0xFA, 0x00}) == drive);
    FrameDecoder d(p.frame, FrameSide::requests);
    CHECK(decode_all(d, drive).size() == 1);
  }
  SECTION("CheckSumEn optional: a frame without CHKSUM is taken too") {
    const ProtocolProfile p =
        parse_protocol_profile(thesis_text_with("checksum_enable: always", "checksum_enable: optional"), "optional.yaml");
    FrameDecoder d(p.frame, FrameSide::requests);
    // Flag 0x00 (CheckSumEn clear): no CHKSUM; then the CRC golden SYNC with it.
    const auto frames = decode_all(d, Bytes{0x00, 0x01, 0xA8, 0x00, 0x10, 0x01, 0xA8, 0x00, 0xBC});
    CHECK(frames.size() == 2);
    CHECK(d.stats().errors() == 0);
  }
}

TEST_CASE("every command round-trips with the firmware model in the thesis profile", "[board][protocol]") {
  const auto thesis = resolve_protocol_profile("thesis", {});
  SimClock clock;
  SerialLine line{clock};
  StillPlant plant;
  FirmwareConfig config;
  config.link_timeout = 1h;
  BoardFirmware board(config, line.board(), plant);
  FrameDecoder host(thesis->frame, FrameSide::responses);
  const auto exchange = [&](const Bytes& frame) {
    REQUIRE(line.host().write(frame));
    for (int i = 0; i < 20; ++i) {
      clock.advance(1ms);
      board.run_until(clock.now());
      std::array<std::uint8_t, 600> buf{};
      const auto n = line.host().read(buf, clock.now());
      const auto r = host.decode(std::span<const std::uint8_t>(buf.data(), static_cast<std::size_t>(n)));
      if (r.frame) return Bytes(host.frame().bytes.begin(), host.frame().bytes.end());
    }
    FAIL("no response");
    return Bytes{};
  };
  for (const Golden& g : thesis_requests()) {
    INFO(to_string(g.command));
    const Bytes response = exchange(g.frame);
    if (g.command == Command::sync) {
      CHECK(response == g.frame);  // echoed unchanged
      continue;
    }
    const std::optional<Response> r = parse_response(host.frame().body);
    REQUIRE(r);
    CHECK(r->resp == *thesis->id(g.command));
    CHECK(r->payload.size() <= max_payload_bytes(thesis->spec(g.command)->response));
    // Length = Resp + payload.
    CHECK(response[1] == 1 + r->payload.size());
  }
  CHECK(board.counters().error_responses == 0);
  CHECK(board.decoder_stats().errors() == 0);
  CHECK(board.uv_lamp());
  CHECK(board.last_voice_track() == 5);
  CHECK(board.lcd_line(0) == "UV ON");

  // And the host link drives, polls and commands through it with no error.
  Pair pair(thesis, thesis);
  pair.run_for(1s);
  const std::array<std::uint8_t, 1> on{1};
  CHECK(pair.link.queue(Command::uv_lamp, on));
  pair.run_for(4s);
  CHECK(pair.link.synchronised());
  CHECK(pair.link.stats().error_responses == 0);
  CHECK(pair.link.stats().missed == 0);
  CHECK(pair.link.has_battery());
  CHECK(pair.link.ultrasonic_mm().size() == 3);
  CHECK(pair.board.uv_lamp());
  CHECK(pair.board.wheel_speed_m_s(0) == Approx(0.2).margin(0.01));
  CHECK(pair.link.dialect_mismatch().empty());
}

namespace {
// A board whose layouts are not the host's: DRIVE's speeds swapped and in i32 of 0.1 mm/s, the
// battery's voltage in u8 of 0.1 V, the ultrasonic ranges in u8 of 1 cm.
std::string other_layouts() {
  std::string text = thesis_text_with("    id: 0x12\n    request:\n      - {name: left, type: i16, unit: m/s, scale: 0.001}\n"
                                      "      - {name: right, type: i16, unit: m/s, scale: 0.001}\n",
                                      "    id: 0x12\n    request:\n      - {name: right, type: i32, unit: m/s, scale: 0.0001}\n"
                                      "      - {name: left, type: i32, unit: m/s, scale: 0.0001}\n");
  text.replace(text.find("{name: voltage, type: u16, unit: V, scale: 0.001}"), 49, "{name: voltage, type: u8, unit: V, scale: 0.1}");
  text.replace(text.find("{name: range, type: u16, unit: m, scale: 0.001, repeat: count, max: 8}"), 70,
               "{name: range, type: u8, unit: m, scale: 0.01, repeat: count, max: 8}");
  return text;
}
}  // namespace

TEST_CASE("a board whose layouts differ in order, type and scale: payloads transcoded both ways", "[board][protocol][golden]") {
  const auto other = shared(parse_protocol_profile(other_layouts(), "other.yaml"));
  REQUIRE(other->spec(Command::drive)->request_transcoded);
  CHECK_FALSE(other->spec(Command::drive)->response_transcoded);
  CHECK(other->spec(Command::battery)->response_transcoded);
  // DRIVE left 200 mm/s, right 250 mm/s (the host's C8 00 FA 00): right first, 0.25 m/s / 0.0001
  // = 2500 = 0x000009C4, then left 2000 = 0x000007D0; Length 1 + 8 = 9; CRC-8 0x7C.
  std::array<std::uint8_t, 16> staged{};
  const Bytes host_payload{0xC8, 0x00, 0xFA, 0x00};
  const std::ptrdiff_t n = transcode(builtin_command(Command::drive).request, other->spec(Command::drive)->request, host_payload, staged);
  REQUIRE(n == 8);
  const Bytes wire(staged.begin(), staged.begin() + n);
  CHECK(encode(other->frame, Command::drive, 0x12, wire) == Bytes{0x10, 0x09, 0xA8, 0x12, 0xC4, 0x09, 0x00, 0x00, 0xD0, 0x07, 0x00, 0x00, 0x7C});
  // BATTERY 87 %, not charging, 15.800 V: voltage 158 (0x9E) of 0.1 V; Length 1 + 3 = 4; CRC 0x3E.
  const Bytes battery{0x57, 0x00, 0xB8, 0x3D};
  const std::ptrdiff_t m = transcode(builtin_command(Command::battery).response, other->spec(Command::battery)->response, battery, staged);
  REQUIRE(m == 3);
  std::array<std::uint8_t, 16> out{};
  const std::size_t k = encode_response(0x20, std::span<const std::uint8_t>(staged.data(), 3), out, other->frame);
  CHECK(Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(k)) == Bytes{0x10, 0x04, 0x20, 0x57, 0x00, 0x9E, 0x3E});
  // No echo (FFFF) stays no echo (FF) in a narrower type; a payload that does not fit is refused.
  const Bytes ranges{0x02, 0xB0, 0x04, 0xFF, 0xFF};
  REQUIRE(transcode(builtin_command(Command::ultrasonic).response, other->spec(Command::ultrasonic)->response, ranges, staged) == 3);
  CHECK(Bytes(staged.begin(), staged.begin() + 3) == Bytes{0x02, 0x78, 0xFF});  // 1.200 m = 120 cm
  CHECK(transcode(builtin_command(Command::ultrasonic).response, other->spec(Command::ultrasonic)->response, Bytes{0x02, 0xB0}, staged) == -1);

  // Host and board both in it: driving, polling and the sensors as in the host's own layout.
  Pair pair(other, other);
  pair.run_for(3s);
  CHECK(pair.link.synchronised());
  CHECK(pair.link.stats().error_responses == 0);
  CHECK(pair.board.required_m_s(0) == Approx(0.2));
  CHECK(pair.board.required_m_s(1) == Approx(0.2));
  CHECK(pair.link.drive().encoders.left_mm_s == Approx(200).margin(10));
  REQUIRE(pair.link.has_battery());
  CHECK(pair.link.battery().voltage_mv == 16800);
  REQUIRE(pair.link.ultrasonic_mm().size() == 3);
  CHECK(pair.link.ultrasonic_mm()[2] == 1200);
  // A host in the thesis's own layouts against this board: DRIVE refused (8 bytes expected).
  Pair mixed(resolve_protocol_profile("thesis", {}), other);
  mixed.run_for(1s);
  CHECK(mixed.link.stats().error_responses > 0);
}

TEST_CASE("a profile without the SYNC echo: the board answers SYNC with its Resp", "[board][protocol]") {
  const auto no_echo = shared(parse_protocol_profile(thesis_text_with("sync_echo: true", "sync_echo: false"), "no_echo.yaml"));
  Pair pair(no_echo, no_echo);
  pair.run_for(1s);
  CHECK(pair.link.synchronised());
  CHECK(pair.link.stats().resyncs == 1);
  CHECK(pair.link.stats().error_responses == 0);
  CHECK(pair.board.counters().resyncs == 1);
}

TEST_CASE("a profile's errors are located and all reported", "[board][protocol][config]") {
  SECTION("duplicate ids") {
    const std::string text = thesis_text_with("    id: 0x01\n", "    id: 0x12\n");  // STATUS takes DRIVE's id
    REQUIRE_THROWS_WITH(parse_protocol_profile(text, "dup.yaml"),
                        Catch::Matches("(.|\\n)*dup\\.yaml:\\d+:\\d+: error: DRIVE: duplicate id 0x12: already the id of STATUS(.|\\n)*"));
  }
  SECTION("a payload longer than the 512-byte buffer") {
    const std::string text = thesis_text_with("{name: text, type: bytes, repeat: \"*\", max: 32}",
                                              "{name: text, type: bytes, repeat: \"*\", max: 600}");
    REQUIRE_THROWS_WITH(parse_protocol_profile(text, "long.yaml"),
                        Catch::Contains("LCD_TEXT request: payload up to 601 bytes, Length up to 602: longer than the 512-byte "
                                        "buffer (frame.max_length)"));
  }
  SECTION("an unknown field type, with its line and column") {
    const std::string text = thesis_text_with("{name: on, type: u8}", "{name: on, type: u12}");
    try {
      (void)parse_protocol_profile(text, "type.yaml");
      FAIL("no error");
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      CHECK_THAT(what, Catch::Contains("UV_LAMP request field 1 type: expected one of u8, i8, u16, i16, u32, i32, f32, bitmap8, "
                                       "bitmap16, bitmap32, bytes; got 'u12'"));
      // Line of the field in the file: count it.
      const std::size_t line = static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(text.find("u12")), '\n')) + 1;
      CHECK_THAT(what, Catch::Contains("type.yaml:" + std::to_string(line) + ":"));
    }
  }
  SECTION("several errors at once, and a layout this host does not implement") {
    std::string text = thesis_text_with("    id: 0x01\n", "    id: 0xEE\n");  // the error Resp
    text.replace(text.find("length_rule: cmd_payload"), 24, "length_rule: sideways");
    text.replace(text.find("{name: track, type: u8}"), 23, "{name: track, type: u8, unit: m}");
    try {
      (void)parse_protocol_profile(text, "many.yaml");
      FAIL("no error");
    } catch (const ConfigError& e) {
      CHECK(e.diagnostics().error_count() == 3);
      const std::string what = e.what();
      CHECK_THAT(what, Catch::Contains("frame.length_rule: expected one of cmd_payload, type_cmd_payload; got 'sideways'"));
      CHECK_THAT(what, Catch::Contains("STATUS: id 0xEE is the error Resp (errors.resp)"));
      CHECK_THAT(what, Catch::Contains("VOICE request field 1 'track': unit 'm', expected '' (this host and the firmware model "
                                       "implement {name: track, type: u8})"));
    }
  }
  SECTION("an error Resp equal to TYPE, which would read as a SYNC echo") {
    const std::string text = thesis_text_with("  resp: 0xEE", "  resp: 0xA8");
    REQUIRE_THROWS_WITH(parse_protocol_profile(text, "resp.yaml"), Catch::Contains("errors.resp: 0xA8 is the TYPE byte"));
  }
  SECTION("a field the host does not know, and one it misses") {
    const std::string text = thesis_text_with("{name: on, type: u8}", "{name: lamp, type: u8}");
    try {
      (void)parse_protocol_profile(text, "field.yaml");
      FAIL("no error");
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      CHECK_THAT(what, Catch::Contains("UV_LAMP request field 1 'lamp': not a field of UV_LAMP request (this host and the firmware "
                                       "model know: on)"));
      CHECK_THAT(what, Catch::Contains("UV_LAMP request: no field 'on'"));
    }
  }
  SECTION("a Flag that does not fit Table 3-2") {
    const std::string text = thesis_text_with("flag_long: 0x50", "flag_long: 0x51");
    REQUIRE_THROWS_WITH(parse_protocol_profile(text, "flag.yaml"),
                        Catch::Contains("frame.flag_long: 0x51 does not fit Table 3-2 with checksum CRC-8/SMBUS; expected 0x50"));
  }
  SECTION("a missing key is located, not a YAML exception (found by fuzzing)") {
    const std::string text = thesis_text_with("  resp: 0xEE\n", "");
    try {
      (void)parse_protocol_profile(text, "missing.yaml");
      FAIL("no error");
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      CHECK_THAT(what, Catch::Contains("errors: missing 'resp'"));
      CHECK_THAT(what, Catch::Matches("(.|\\n)*missing\\.yaml:\\d+:\\d+: error: errors: missing 'resp'(.|\\n)*"));
      CHECK_THAT(what, !Catch::Contains("invalid node"));
    }
  }
  SECTION("a missing file") {
    REQUIRE_THROWS_WITH(load_protocol_profile("/nonexistent/board.yaml"), Catch::Contains("/nonexistent/board.yaml"));
  }
}

TEST_CASE("a board of another dialect is named: the checksum it fits, or the Length rule", "[board][protocol][dialect]") {
  const auto thesis = resolve_protocol_profile("thesis", {});
  SECTION("the board sums where the profile expects CRC-8") {
    const auto sum8 = shared(parse_protocol_profile(thesis_text_with("checksum: crc8_smbus", "checksum: sum8"), "sum8.yaml"));
    Pair pair(thesis, sum8);
    pair.run_for(1s);
    CHECK_FALSE(pair.link.synchronised());
    CHECK(pair.link.dialect_mismatch() == "protocol profile thesis expects CRC-8/SMBUS, the board's frames fit an 8-bit sum");
    CHECK(pair.link.stats().dialect_mismatches == 1);
    CHECK(pair.link.decoder_stats().fits[static_cast<std::size_t>(ChecksumKind::sum8)] >= 2);
  }
  SECTION("the board counts TYPE in Length (tripodal-v1) where the profile does not") {
    Pair pair(thesis, resolve_protocol_profile("tripodal-v1", {}));
    pair.run_for(1s);
    CHECK_FALSE(pair.link.synchronised());
    CHECK(pair.link.dialect_mismatch() ==
          "the board refuses the checksum of requests framed by protocol profile thesis (Length = CMD + payload), while its own "
          "frames pass CRC-8/SMBUS: it reads Length as TYPE + CMD + payload, or computes another checksum");
  }
  SECTION("the same dialect: nothing to say, even on a noisy line") {
    Pair pair(thesis, thesis);
    pair.line.set_noise(LineNoise{0.002, 0.0, 0.0, 7});
    pair.run_for(5s);
    CHECK(pair.link.stats().responses > 300);
    CHECK(pair.link.dialect_mismatch().empty());
  }
  SECTION("the decoder's description names the checksum a failed frame fits") {
    const auto sum8 = parse_protocol_profile(thesis_text_with("checksum: crc8_smbus", "checksum: sum8"), "sum8.yaml");
    // The 8-bit-sum SYNC (CHKSUM 0xB9, see above) read by a CRC-8 board.
    FrameDecoder d(thesis->frame, FrameSide::requests);
    CHECK(decode_all(d, Bytes{0x10, 0x01, 0xA8, 0x00, 0xB9}).empty());
    CHECK(describe(d.last_error()) ==
          "stream offset 0: checksum mismatch: frame of Length 1 carries CHKSUM 0xb9, expected 0xbc (CRC-8/SMBUS); the frame fits "
          "an 8-bit sum");
    (void)sum8;
    // tripodal-v1's SYNC (Length 2 counts TYPE) read by a thesis board: it fits the other rule.
    FrameDecoder t(thesis->frame, FrameSide::requests);
    CHECK(decode_all(t, Bytes{0x10, 0x02, 0xA8, 0x00, 0x01, 0x10}).empty());
    CHECK(t.last_error().fits_other_length_rule);
    CHECK(t.stats().fits_other_length_rule == 1);
  }
}

TEST_CASE("a robot names its board's protocol profile, and errors say where", "[board][protocol][config]") {
  HardwareRegistry registry("hardware type");
  register_board_hardware(registry);
  HardwareConfig c;
  c.type = "board";
  c.where = SourceLocation{SourceFile(std::string_view("robot.yaml")), 12, 3};
  ControllerConfig base;
  base.type = "differential";
  base.differential = {0.42, 0.09};
  c.base = &base;
  c.profile_dir = TRIPODAL_SOURCE_DIR "/configs/robots";
  c.parameters = ParameterSet::resolve(registry.manifest("board"), {}, c.where);
  CHECK(board_hardware_config(c).link.protocol->name == "thesis");
  c.parameters = ParameterSet::resolve(registry.manifest("board"), {{"protocol", Value{std::string("tripodal-v1")}}}, c.where);
  CHECK(board_hardware_config(c).link.protocol->frame.length_rule == LengthRule::type_cmd_payload);
  c.parameters = ParameterSet::resolve(registry.manifest("board"), {{"protocol", Value{std::string("../board/tripodal-v1.yaml")}}}, c.where);
  CHECK(board_hardware_config(c).link.protocol->name == "tripodal-v1");
  c.parameters = ParameterSet::resolve(registry.manifest("board"), {{"protocol", Value{std::string("../board/nope.yaml")}}}, c.where);
  REQUIRE_THROWS_WITH(board_hardware_config(c), Catch::Contains("nope.yaml") && Catch::Contains("robot.yaml:12:3: note: protocol profile "
                                                                                                "'../board/nope.yaml' named by hardware 'board' here"));
}
