#include "tripodal/board/frame.hpp"

#include <catch2/catch.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "tripodal/board/commands.hpp"

using namespace tripodal::board;

namespace {

using Bytes = std::vector<std::uint8_t>;

struct Golden {
  const char* name;
  Bytes bytes;
};

// Every frame of docs/board-protocol.md, computed by hand from Tables 3-1 to 3-6 and the command
// table (CRC-8 by an independent bitwise implementation).
const std::vector<Golden>& golden() {
  static const std::vector<Golden> g = {
    {"SYNC request", {0x10, 0x02, 0xA8, 0x00, 0x01}},
    {"SYNC response (echo)", {0x10, 0x02, 0xA8, 0x00, 0x01}},
    {"STATUS request", {0x10, 0x02, 0xA8, 0x01, 0x06}},
    {"STATUS response: synchronised + UV lamp, tick 123456 ms, 1000 frames, 2 errors", {0x10, 0x0A, 0x01, 0x09, 0x40, 0xE2, 0x01, 0x00, 0xE8, 0x03, 0x02, 0x00, 0xBC}},
    {"SET_WHEEL_SPEEDS request: left 300 mm/s, right -300 mm/s", {0x10, 0x06, 0xA8, 0x10, 0x2C, 0x01, 0xD4, 0xFE, 0x06}},
    {"SET_WHEEL_SPEEDS response", {0x10, 0x01, 0x10, 0xC7}},
    {"READ_ENCODERS request", {0x10, 0x02, 0xA8, 0x11, 0x76}},
    {"READ_ENCODERS response: 100000 and -2 pulses, 250 and -250 mm/s", {0x10, 0x0D, 0x11, 0xA0, 0x86, 0x01, 0x00, 0xFE, 0xFF, 0xFF, 0xFF, 0xFA, 0x00, 0x06, 0xFF, 0x9B}},
    {"DRIVE request: left 200 mm/s, right 250 mm/s", {0x10, 0x06, 0xA8, 0x12, 0xC8, 0x00, 0xFA, 0x00, 0x19}},
    {"DRIVE response: 5000 / 5200 pulses, 198 / 251 mm/s, bump 1 + cliff 0, start held, synchronised", {0x10, 0x13, 0x12, 0x88, 0x13, 0x00, 0x00, 0x50, 0x14, 0x00, 0x00, 0xC6, 0x00, 0xFB, 0x00, 0x02, 0x01, 0x00, 0x00, 0x01, 0x01, 0x44}},
    {"BATTERY request", {0x10, 0x02, 0xA8, 0x20, 0xE1}},
    {"BATTERY response: 87 %, not charging, 15.800 V", {0x10, 0x05, 0x20, 0x57, 0x00, 0xB8, 0x3D, 0xF0}},
    {"ULTRASONIC request", {0x10, 0x02, 0xA8, 0x21, 0xE6}},
    {"ULTRASONIC response: 2 sensors, 1.200 m and no echo", {0x10, 0x06, 0x21, 0x02, 0xB0, 0x04, 0xFF, 0xFF, 0x3A}},
    {"INFRARED request", {0x10, 0x02, 0xA8, 0x22, 0xEF}},
    {"INFRARED response: 2 cliff (30, 31 mm), 2 wall (120 mm, no return)", {0x10, 0x0B, 0x22, 0x02, 0x02, 0x1E, 0x00, 0x1F, 0x00, 0x78, 0x00, 0xFF, 0xFF, 0xE6}},
    {"BUMP request", {0x10, 0x02, 0xA8, 0x23, 0xE8}},
    {"BUMP response: bump switch 1, cliff sensor 0", {0x10, 0x05, 0x23, 0x02, 0x01, 0x00, 0x00, 0xDB}},
    {"LIQUID_LEVEL request", {0x10, 0x02, 0xA8, 0x24, 0xFD}},
    {"LIQUID_LEVEL response: 64 %, not empty", {0x10, 0x03, 0x24, 0x40, 0x00, 0xBB}},
    {"BUTTONS request", {0x10, 0x02, 0xA8, 0x25, 0xFA}},
    {"BUTTONS response: emergency stop held, pressed since last read", {0x10, 0x03, 0x25, 0x02, 0x02, 0xAF}},
    {"ATOMIZER request: atomizer on, fan on", {0x10, 0x04, 0xA8, 0x30, 0x01, 0x01, 0xAD}},
    {"ATOMIZER response", {0x10, 0x01, 0x30, 0x27}},
    {"UV_LAMP request: on", {0x10, 0x03, 0xA8, 0x31, 0x01, 0xFA}},
    {"UV_LAMP response", {0x10, 0x01, 0x31, 0x20}},
    {"VOICE request: track 5", {0x10, 0x03, 0xA8, 0x32, 0x05, 0xD9}},
    {"VOICE response", {0x10, 0x01, 0x32, 0x29}},
    {"LCD_TEXT request: line 0, \"UV ON\"", {0x10, 0x08, 0xA8, 0x33, 0x00, 0x55, 0x56, 0x20, 0x4F, 0x4E, 0xA7}},
    {"LCD_TEXT response", {0x10, 0x01, 0x33, 0x2E}},
    {"error: checksum", {0x10, 0x03, 0xEE, 0x01, 0x00, 0xFF}},
    {"error: not synchronised (DRIVE before SYNC)", {0x10, 0x03, 0xEE, 0x02, 0x12, 0xBE}},
    {"error: wrong TYPE (0xA9, DRIVE)", {0x10, 0x03, 0xEE, 0x03, 0x12, 0xAB}},
    {"error: unknown command 0x7F", {0x10, 0x03, 0xEE, 0x04, 0x7F, 0xC4}},
    {"error: overflow (Length above 512)", {0x10, 0x03, 0xEE, 0x05, 0x00, 0xAB}},
    {"error: bad payload (SET_WHEEL_SPEEDS with 3 bytes)", {0x10, 0x03, 0xEE, 0x06, 0x10, 0xE4}},
  };
  return g;
}

const Bytes& golden(const std::string& name) {
  for (const Golden& g : golden()) {
    if (name == g.name) return g.bytes;
  }
  FAIL("no golden frame " << name);
  static const Bytes none;
  return none;
}

template <class T>
Bytes payload_of(const T& value) {
  std::array<std::uint8_t, 64> buf{};
  ByteWriter w(buf);
  pack(w, value);
  REQUIRE_FALSE(w.failed());
  return {w.written().begin(), w.written().end()};
}

Bytes request(Command cmd, const Bytes& payload = {}) {
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  const std::size_t n = encode_request(static_cast<std::uint8_t>(cmd), payload, out);
  REQUIRE(n > 0);
  return {out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n)};
}

Bytes response(std::uint8_t resp, const Bytes& payload = {}) {
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  const std::size_t n = encode_response(resp, payload, out);
  REQUIRE(n > 0);
  return {out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n)};
}
Bytes response(Command cmd, const Bytes& payload = {}) { return response(static_cast<std::uint8_t>(cmd), payload); }
Bytes error(ErrorCode code, std::uint8_t cmd) { return response(kErrorResp, {static_cast<std::uint8_t>(code), cmd}); }

Bytes concat(std::initializer_list<Bytes> parts) {
  Bytes all;
  for (const Bytes& p : parts) all.insert(all.end(), p.begin(), p.end());
  return all;
}

// Decodes everything; returns the frames' bytes.
std::vector<Bytes> decode_all(FrameDecoder& d, const Bytes& stream) {
  std::vector<Bytes> frames;
  d.feed(stream, [&](const FrameView& f) { frames.emplace_back(f.bytes.begin(), f.bytes.end()); });
  return frames;
}

}  // namespace

TEST_CASE("the checksum is CRC-8/SMBUS", "[board][frame]") {
  const std::string check = "123456789";
  const auto* p = reinterpret_cast<const std::uint8_t*>(check.data());
  CHECK(crc8(std::span<const std::uint8_t>(p, check.size())) == 0xF4);
  CHECK(crc8({}) == 0x00);
  // Chained: the CRC of a prefix continues over the rest.
  CHECK(crc8(std::span<const std::uint8_t>(p + 4, 5), crc8(std::span<const std::uint8_t>(p, 4))) == 0xF4);
  // One flipped bit anywhere in a frame changes it.
  Bytes f = golden("DRIVE request: left 200 mm/s, right 250 mm/s");
  const std::uint8_t good = crc8(std::span<const std::uint8_t>(f).first(f.size() - 1));
  for (std::size_t i = 0; i + 1 < f.size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      f[i] ^= static_cast<std::uint8_t>(1U << bit);
      CHECK(crc8(std::span<const std::uint8_t>(f).first(f.size() - 1)) != good);
      f[i] ^= static_cast<std::uint8_t>(1U << bit);
    }
  }
}

TEST_CASE("golden frames: every command and error as the tables give it", "[board][frame]") {
  CHECK(request(Command::sync) == golden("SYNC request"));
  CHECK(request(Command::status) == golden("STATUS request"));
  CHECK(response(Command::status, payload_of(BoardStatus{kStatusSynchronised | kStatusUvLamp, 123456, 1000, 2})) ==
        golden("STATUS response: synchronised + UV lamp, tick 123456 ms, 1000 frames, 2 errors"));
  CHECK(request(Command::set_wheel_speeds, payload_of(WheelSpeeds{300, -300})) ==
        golden("SET_WHEEL_SPEEDS request: left 300 mm/s, right -300 mm/s"));
  CHECK(response(Command::set_wheel_speeds) == golden("SET_WHEEL_SPEEDS response"));
  CHECK(request(Command::read_encoders) == golden("READ_ENCODERS request"));
  CHECK(response(Command::read_encoders, payload_of(EncoderState{100000, -2, 250, -250})) ==
        golden("READ_ENCODERS response: 100000 and -2 pulses, 250 and -250 mm/s"));
  CHECK(request(Command::drive, payload_of(WheelSpeeds{200, 250})) == golden("DRIVE request: left 200 mm/s, right 250 mm/s"));
  const DriveState drive{{5000, 5200, 198, 251}, (1U << (kBumpShift + 1)) | (1U << kCliffShift), kButtonStart, kStatusSynchronised};
  CHECK(response(Command::drive, payload_of(drive)) ==
        golden("DRIVE response: 5000 / 5200 pulses, 198 / 251 mm/s, bump 1 + cliff 0, start held, synchronised"));
  CHECK(request(Command::battery) == golden("BATTERY request"));
  CHECK(response(Command::battery, payload_of(BatteryState{87, false, 15800})) == golden("BATTERY response: 87 %, not charging, 15.800 V"));
  CHECK(request(Command::ultrasonic) == golden("ULTRASONIC request"));
  CHECK(response(Command::ultrasonic, {2, 0xB0, 0x04, 0xFF, 0xFF}) == golden("ULTRASONIC response: 2 sensors, 1.200 m and no echo"));
  CHECK(request(Command::infrared) == golden("INFRARED request"));
  CHECK(response(Command::infrared, {2, 2, 30, 0, 31, 0, 120, 0, 0xFF, 0xFF}) ==
        golden("INFRARED response: 2 cliff (30, 31 mm), 2 wall (120 mm, no return)"));
  CHECK(request(Command::bump) == golden("BUMP request"));
  CHECK(response(Command::bump, {0x02, 0x01, 0x00, 0x00}) == golden("BUMP response: bump switch 1, cliff sensor 0"));
  CHECK(request(Command::liquid_level) == golden("LIQUID_LEVEL request"));
  CHECK(response(Command::liquid_level, {64, 0}) == golden("LIQUID_LEVEL response: 64 %, not empty"));
  CHECK(request(Command::buttons) == golden("BUTTONS request"));
  CHECK(response(Command::buttons, {kButtonEmergencyStop, kButtonEmergencyStop}) ==
        golden("BUTTONS response: emergency stop held, pressed since last read"));
  CHECK(request(Command::atomizer, {1, 1}) == golden("ATOMIZER request: atomizer on, fan on"));
  CHECK(response(Command::atomizer) == golden("ATOMIZER response"));
  CHECK(request(Command::uv_lamp, {1}) == golden("UV_LAMP request: on"));
  CHECK(response(Command::uv_lamp) == golden("UV_LAMP response"));
  CHECK(request(Command::voice, {5}) == golden("VOICE request: track 5"));
  CHECK(response(Command::voice) == golden("VOICE response"));
  CHECK(request(Command::lcd_text, {0, 'U', 'V', ' ', 'O', 'N'}) == golden("LCD_TEXT request: line 0, \"UV ON\""));
  CHECK(response(Command::lcd_text) == golden("LCD_TEXT response"));
  CHECK(error(ErrorCode::checksum, 0) == golden("error: checksum"));
  CHECK(error(ErrorCode::not_synchronised, 0x12) == golden("error: not synchronised (DRIVE before SYNC)"));
  CHECK(error(ErrorCode::wrong_type, 0x12) == golden("error: wrong TYPE (0xA9, DRIVE)"));
  CHECK(error(ErrorCode::unknown_command, 0x7F) == golden("error: unknown command 0x7F"));
  CHECK(error(ErrorCode::overflow, 0) == golden("error: overflow (Length above 512)"));
  CHECK(error(ErrorCode::bad_payload, 0x10) == golden("error: bad payload (SET_WHEEL_SPEEDS with 3 bytes)"));

  // Each golden frame decodes to itself, and its body parses as its kind says.
  for (const Golden& g : golden()) {
    INFO(g.name);
    FrameDecoder d;
    const auto frames = decode_all(d, g.bytes);
    REQUIRE(frames.size() == 1);
    CHECK(frames[0] == g.bytes);
    CHECK(d.stats().errors() == 0);
  }
}

TEST_CASE("a body above 255 bytes goes in a long frame with a little-endian length", "[board][frame]") {
  Bytes payload(298);
  for (std::size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<std::uint8_t>(i);
  const Bytes f = request(Command::sync, payload);
  REQUIRE(f.size() == 304);
  CHECK(f[0] == 0x50);
  CHECK(f[1] == 0x2C);
  CHECK(f[2] == 0x01);
  CHECK(f[3] == 0xA8);
  CHECK(f[4] == 0x00);
  CHECK(f.back() == 0x05);
  FrameDecoder d;
  const auto frames = decode_all(d, f);
  REQUIRE(frames.size() == 1);
  CHECK(d.frame().long_frame);
  CHECK(d.frame().body.size() == 300);
  // A long frame with a short body is valid too.
  Bytes small = {0x50, 0x02, 0x00, 0xA8, 0x00};
  small.push_back(crc8(small));
  FrameDecoder d2;
  CHECK(decode_all(d2, small).size() == 1);
}

TEST_CASE("the encoder refuses what no frame can carry", "[board][frame]") {
  std::array<std::uint8_t, kMaxFrameBytes + 8> out{};
  CHECK(encode_frame({}, out) == 0);
  const Bytes body(kMaxLength + 1, 0x55);
  CHECK(encode_frame(body, out) == 0);
  const Bytes max(kMaxLength, 0x55);
  CHECK(encode_frame(max, out) == kMaxLength + 4);  // Flag, Len, LenH, body, CHKSUM
  std::array<std::uint8_t, 4> tiny{};
  CHECK(encode_request(0x01, {}, tiny) == 0);  // needs 5 bytes
  CHECK(tiny == std::array<std::uint8_t, 4>{});
}

TEST_CASE("the decoder finds frames split across any reads", "[board][frame]") {
  Bytes stream;
  for (const Golden& g : golden()) stream.insert(stream.end(), g.bytes.begin(), g.bytes.end());
  for (std::size_t chunk : {std::size_t{1}, std::size_t{2}, std::size_t{3}, std::size_t{7}, std::size_t{64}, stream.size()}) {
    INFO("chunk " << chunk);
    FrameDecoder d;
    std::vector<Bytes> frames;
    for (std::size_t i = 0; i < stream.size(); i += chunk) {
      const Bytes part(stream.begin() + static_cast<std::ptrdiff_t>(i),
                       stream.begin() + static_cast<std::ptrdiff_t>(std::min(stream.size(), i + chunk)));
      for (const Bytes& f : decode_all(d, part)) frames.push_back(f);
    }
    REQUIRE(frames.size() == golden().size());
    for (std::size_t i = 0; i < frames.size(); ++i) CHECK(frames[i] == golden()[i].bytes);
    CHECK(d.stats().errors() == 0);
    CHECK(d.stats().bytes == stream.size());
    CHECK_FALSE(d.partial());
  }
}

TEST_CASE("malformed frames: each counted, located and described", "[board][frame]") {
  const Bytes sync = golden("SYNC request");
  const Bytes status = golden("STATUS request");

  SECTION("garbage between frames") {
    FrameDecoder d;
    const auto frames = decode_all(d, concat({sync, {0x00, 0xFF, 0x42}, status}));
    REQUIRE(frames.size() == 2);
    CHECK(frames[1] == status);
    CHECK(d.stats().garbage_runs == 1);
    CHECK(d.stats().garbage_bytes == 3);
    CHECK(d.last_error().kind == DecodeErrorKind::garbage);
    CHECK(describe(d.last_error()) == "stream offset 5: garbage: 3 byte(s) skipped; expected a Flag 0x10 or 0x50");
  }
  SECTION("a wrong checksum") {
    Bytes bad = sync;
    bad.back() = 0x02;
    FrameDecoder d;
    const auto frames = decode_all(d, concat({bad, status}));
    REQUIRE(frames.size() == 1);
    CHECK(frames[0] == status);
    CHECK(d.stats().checksum == 1);
    CHECK(describe(d.last_error()).find("stream offset 0: checksum mismatch: frame of Length 2 carries CHKSUM 0x02, expected 0x01") == 0);
  }
  SECTION("a length above 512") {
    FrameDecoder d;
    // 0x0201 = 513
    const auto frames = decode_all(d, concat({{0x50, 0x01, 0x02, 0xA8, 0x00}, status}));
    REQUIRE(frames.size() == 1);
    CHECK(frames[0] == status);
    CHECK(d.stats().oversize == 1);
    // The 4 bytes after the refused Flag are its remains: skipped, not a second error.
    CHECK(d.last_error().kind == DecodeErrorKind::oversize);
    CHECK(d.stats().garbage_bytes == 4);
    CHECK(d.stats().errors() == 1);
    FrameDecoder d2;
    (void)decode_all(d2, {0x50, 0xFF, 0xFF});
    CHECK(d2.stats().oversize == 1);
    CHECK(describe(d2.last_error()) == "stream offset 0: oversize frame: Length 65535; expected at most 512");
  }
  SECTION("a zero length") {
    FrameDecoder d;
    const auto frames = decode_all(d, concat({{0x10, 0x00}, status}));
    REQUIRE(frames.size() == 1);
    CHECK(d.stats().empty == 1);
    FrameDecoder d2;
    (void)decode_all(d2, {0x10, 0x00});
    CHECK(describe(d2.last_error()) == "stream offset 0: empty frame: Length 0; expected at least 1 (the CMD or Resp byte)");
  }
  SECTION("a truncated frame followed by a good one: found by re-scanning") {
    const Bytes drive = golden("DRIVE request: left 200 mm/s, right 250 mm/s");
    const Bytes truncated(drive.begin(), drive.begin() + 5);
    FrameDecoder d;
    const auto frames = decode_all(d, concat({truncated, status, sync}));
    // The truncated DRIVE swallows STATUS's bytes, fails its CHKSUM, and the scan resumes inside it.
    REQUIRE(frames.size() == 2);
    CHECK(frames[0] == status);
    CHECK(frames[1] == sync);
    CHECK(d.stats().checksum == 1);
  }
  SECTION("a truncated frame the line gave up on") {
    const Bytes drive = golden("DRIVE request: left 200 mm/s, right 250 mm/s");
    FrameDecoder d;
    CHECK(decode_all(d, Bytes(drive.begin(), drive.begin() + 5)).empty());
    CHECK(d.partial());
    const auto r = d.abandon_partial();
    CHECK_FALSE(r.frame);
    CHECK_FALSE(d.partial());
    CHECK(d.stats().truncated == 1);
    CHECK(d.stats().garbage_bytes == 4);  // "06 A8 12 C8", re-scanned after the Flag
    CHECK(d.stats().errors() == 1);
    CHECK(decode_all(d, status).size() == 1);
    // Length 16 (itself a Flag byte): the message of the truncated candidate.
    FrameDecoder d2;
    CHECK(decode_all(d2, Bytes{0x10, 0x10}).empty());
    (void)d2.abandon_partial();
    CHECK(describe(d2.last_error()) == "stream offset 0: truncated frame: Length 16 but the frame's bytes stopped coming");
    CHECK(d2.partial());  // the second 0x10 may begin a frame
  }
  SECTION("a false Flag claiming a long frame: the frames after it are recovered") {
    // 0x50 0xFF 0x01: a long frame of Length 511 that never was; the real frames follow.
    Bytes stream = {0x50, 0xFF, 0x01};
    for (int i = 0; i < 40; ++i) stream.insert(stream.end(), status.begin(), status.end());
    FrameDecoder d;
    // Not enough bytes yet to refuse the candidate: on a deadline its owner abandons it.
    CHECK(decode_all(d, stream).empty());
    std::size_t frames = 0;
    auto r = d.abandon_partial();
    while (r.frame) {
      ++frames;
      r = d.decode({});
    }
    CHECK(frames == 40);
    // With more bytes the candidate fails its checksum by itself and the scan resumes inside it.
    FrameDecoder d2;
    for (int i = 0; i < 200; ++i) stream.insert(stream.end(), status.begin(), status.end());
    CHECK(decode_all(d2, stream).size() == 240);
    CHECK(d2.stats().checksum == 1);
  }
}

TEST_CASE("line noise: dropped, duplicated and flipped bytes never yield a wrong frame", "[board][frame]") {
  // Seeded, engine output only (distributions differ between standard libraries).
  std::mt19937_64 rng(17);
  std::vector<Bytes> sent;
  Bytes line;
  for (int i = 0; i < 2000; ++i) {
    const auto left = static_cast<std::int16_t>(rng() % 1000);
    const auto right = static_cast<std::int16_t>(rng() % 1000);
    sent.push_back(request(Command::drive, payload_of(WheelSpeeds{left, right})));
    for (std::uint8_t b : sent.back()) {
      const auto dice = rng() % 1000;
      if (dice < 2) continue;  // dropped (0.2 %)
      if (dice < 4) {          // duplicated (0.2 %)
        line.push_back(b);
      } else if (dice < 6) {   // one bit flipped (0.2 %)
        b ^= static_cast<std::uint8_t>(1U << (rng() % 8));
      }
      line.push_back(b);
    }
  }
  FrameDecoder d;
  const auto got = decode_all(d, line);
  std::size_t matched = 0;
  std::size_t next = 0;
  for (const Bytes& f : got) {
    // Every delivered frame is one that was sent, in order.
    while (next < sent.size() && sent[next] != f) ++next;
    REQUIRE(next < sent.size());
    ++matched;
    ++next;
  }
  CHECK(matched == got.size());
  CHECK(got.size() > 1850);  // ~5 % of 9-byte frames meet an error at 0.6 % per byte
  CHECK(got.size() < 1950);
  CHECK(d.stats().errors() > 0);
  CHECK(d.stats().checksum > 0);
}

TEST_CASE("payloads pack and unpack exactly", "[board][commands]") {
  const DriveState drive{{-7, 123456789, -32768, 32767}, 0x0000FF01, kButtonEmergencyStop, kStatusLinkLost};
  const Bytes p = payload_of(drive);
  CHECK(p.size() == 18);
  const auto back = unpack_drive(p);
  REQUIRE(back);
  CHECK(back->encoders.left_pulses == -7);
  CHECK(back->encoders.right_pulses == 123456789);
  CHECK(back->encoders.left_mm_s == -32768);
  CHECK(back->encoders.right_mm_s == 32767);
  CHECK(back->sensors == 0x0000FF01);
  CHECK(back->buttons == kButtonEmergencyStop);
  CHECK(back->status == kStatusLinkLost);
  CHECK_FALSE(unpack_drive(Bytes(p.begin(), p.end() - 1)));
  Bytes longer = p;
  longer.push_back(0);
  CHECK_FALSE(unpack_drive(longer));
  CHECK_FALSE(unpack_wheel_speeds(Bytes{1, 2, 3}));
  const auto battery = unpack_battery(payload_of(BatteryState{55, true, 14000}));
  REQUIRE(battery);
  CHECK(battery->percent == 55);
  CHECK(battery->charging);
  CHECK(battery->voltage_mv == 14000);
  const auto status = unpack_status(payload_of(BoardStatus{0x05, 42, 7, 3}));
  REQUIRE(status);
  CHECK(status->tick_ms == 42);
  CHECK(status->rx_errors == 3);
}

TEST_CASE("requests and responses split into their fields", "[board][commands]") {
  const Bytes body = {0xA8, 0x12, 0xC8, 0x00, 0xFA, 0x00};
  const auto req = parse_request(body);
  REQUIRE(req);
  CHECK(req->type == kRequestType);
  CHECK(req->cmd == 0x12);
  CHECK(req->payload.size() == 4);
  CHECK_FALSE(parse_request(Bytes{0xA8}));
  const Bytes err = {kErrorResp, 0x04, 0x7F};
  const auto resp = parse_response(err);
  REQUIRE(resp);
  CHECK(resp->is_error());
  CHECK(resp->error() == ErrorCode::unknown_command);
  CHECK(resp->error_cmd() == 0x7F);
  CHECK(to_string(*resp->error()) == "unknown command");
  CHECK_FALSE(parse_response({}));
  CHECK(command_of(0x12) == Command::drive);
  CHECK_FALSE(command_of(0x7F));
  CHECK(to_string(Command::lcd_text) == "LCD_TEXT");
}
