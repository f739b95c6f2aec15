#include "tripodal/board/board_firmware.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "tripodal/board/serial_line.hpp"

using namespace tripodal;
using namespace tripodal::board;
using namespace std::chrono_literals;

namespace {

using Bytes = std::vector<std::uint8_t>;

// A plant that integrates the wheel travel and reports fixed sensor values.
struct StubPlant final : BoardPlant {
  double left_m = 0.0, right_m = 0.0;
  Time last{};
  PlantSensors view{};
  void drive(Time now, double l, double r) noexcept override {
    const double dt = to_seconds(now - last);
    last = now;
    left_m += l * dt;
    right_m += r * dt;
  }
  void sense(Time, PlantSensors& out) noexcept override { out = view; }
};

// The host's side in a test: sends a request, runs the board, returns the response frame.
struct Bench {
  SimClock clock;
  SerialLine line{clock};
  StubPlant plant;
  FirmwareConfig config;
  std::unique_ptr<BoardFirmware> board;
  FrameDecoder decoder;

  // A long link timeout: these tests talk to the board only now and then (the watchdog's own test
  // sets it short).
  static FirmwareConfig patient() {
    FirmwareConfig c;
    c.link_timeout = 1h;
    return c;
  }
  // The frames below are tripodal-v1's (docs/board-protocol.md's golden table before profiles):
  // the board speaks that dialect here; the thesis's is tested in protocol_profile_test.cpp.
  explicit Bench(FirmwareConfig c = patient()) : config(c) {
    if (!config.protocol) config.protocol = resolve_protocol_profile("tripodal-v1", {});
    board = std::make_unique<BoardFirmware>(config, line.board(), plant);
  }

  void run_for(Duration d) {
    clock.advance(d);
    board->run_until(clock.now());
  }
  Bytes exchange_raw(const Bytes& frame) {
    REQUIRE(line.host().write(frame));
    for (int i = 0; i < 20; ++i) {
      run_for(1ms);
      std::array<std::uint8_t, 600> buf{};
      const auto n = line.host().read(buf, clock.now());
      std::span<const std::uint8_t> in(buf.data(), static_cast<std::size_t>(n));
      const auto r = decoder.decode(in);
      if (r.frame) return {decoder.frame().bytes.begin(), decoder.frame().bytes.end()};
    }
    FAIL("no response");
    return {};
  }
  Bytes exchange(Command cmd, const Bytes& payload = {}) {
    std::array<std::uint8_t, kMaxFrameBytes> out{};
    const std::size_t n = encode_request(static_cast<std::uint8_t>(cmd), payload, out);
    return exchange_raw(Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n)));
  }
  Response response(Command cmd, const Bytes& payload = {}) {
    last = exchange(cmd, payload);
    FrameDecoder d;
    REQUIRE(d.feed(last) == 1);
    body.assign(d.frame().body.begin(), d.frame().body.end());
    return *parse_response(body);
  }
  Bytes last, body;
  void sync() { REQUIRE(exchange(Command::sync) == Bytes{0x10, 0x02, 0xA8, 0x00, 0x01}); }
  DriveState drive(double left_m_s, double right_m_s) {
    Bytes p = {0, 0, 0, 0};
    const auto l = static_cast<std::int16_t>(std::lround(left_m_s * 1000));
    const auto r = static_cast<std::int16_t>(std::lround(right_m_s * 1000));
    p = {static_cast<std::uint8_t>(l & 0xFF), static_cast<std::uint8_t>((l >> 8) & 0xFF), static_cast<std::uint8_t>(r & 0xFF),
         static_cast<std::uint8_t>((r >> 8) & 0xFF)};
    const Response resp = response(Command::drive, p);
    REQUIRE(resp.resp == static_cast<std::uint8_t>(Command::drive));
    return *unpack_drive(resp.payload);
  }
};

Bytes with_crc(Bytes f) {
  f.push_back(crc8(f));
  return f;
}

}  // namespace

TEST_CASE("the board answers nothing but SYNC before SYNC, and echoes SYNC unchanged", "[board][firmware]") {
  Bench b;
  CHECK(b.exchange(Command::drive, {0xC8, 0x00, 0xFA, 0x00}) == Bytes{0x10, 0x03, 0xEE, 0x02, 0x12, 0xBE});
  CHECK(b.board->required_m_s(0) == 0.0);
  // Any payload is echoed, the whole frame as it came.
  const Bytes sync_with_payload = with_crc({0x10, 0x05, 0xA8, 0x00, 0x01, 0x02, 0x03});
  CHECK(b.exchange_raw(sync_with_payload) == sync_with_payload);
  CHECK(b.board->synchronised());
  CHECK(b.board->counters().resyncs == 1);
}

TEST_CASE("the board answers each malformed request with its error code", "[board][firmware]") {
  Bench b;
  b.sync();
  CHECK(b.exchange_raw(with_crc({0x10, 0x02, 0xA9, 0x12})) == Bytes{0x10, 0x03, 0xEE, 0x03, 0x12, 0xAB});  // wrong TYPE
  CHECK(b.exchange_raw(with_crc({0x10, 0x02, 0xA8, 0x7F})) == Bytes{0x10, 0x03, 0xEE, 0x04, 0x7F, 0xC4});  // unknown
  CHECK(b.exchange(Command::set_wheel_speeds, {1, 2, 3}) == Bytes{0x10, 0x03, 0xEE, 0x06, 0x10, 0xE4});   // bad payload
  CHECK(b.exchange_raw({0x10, 0x02, 0xA8, 0x01, 0x07}) == Bytes{0x10, 0x03, 0xEE, 0x01, 0x00, 0xFF});     // checksum
  CHECK(b.exchange_raw({0x50, 0x01, 0x02}) == Bytes{0x10, 0x03, 0xEE, 0x05, 0x00, 0xAB});                  // overflow
  CHECK(b.board->counters().error_responses == 5);
  CHECK(b.board->decoder_stats().checksum == 1);
  CHECK(b.board->decoder_stats().oversize == 1);
  // Still synchronised: errors are answered, not fatal.
  const Response status = b.response(Command::status);
  REQUIRE(status.resp == 0x01);
  const auto s = unpack_status(status.payload);
  REQUIRE(s);
  CHECK((s->flags & kStatusSynchronised) != 0);
  CHECK(s->rx_errors == 2);
}

TEST_CASE("the motors follow the required speed under the PID of equation 3-1", "[board][firmware]") {
  Bench b;
  b.sync();
  (void)b.drive(0.3, -0.2);
  b.run_for(1500ms);
  CHECK(b.board->wheel_speed_m_s(0) == Approx(0.3).margin(0.006));
  CHECK(b.board->wheel_speed_m_s(1) == Approx(-0.2).margin(0.006));
  CHECK(b.board->duty(0) > 0.0);
  CHECK(b.board->duty(0) < 1.0);
  const DriveState s = b.drive(0.3, -0.2);
  CHECK(s.encoders.left_mm_s == Approx(300).margin(10));
  CHECK(s.encoders.right_mm_s == Approx(-200).margin(10));
  // The encoders count what the wheels travelled: 5000 pulses per metre (the response was read a
  // few ticks after the board took the sample: 1.5 pulses per ms at 0.3 m/s).
  CHECK(s.encoders.left_pulses == Approx(b.plant.left_m * 5000).margin(8));
  CHECK(s.encoders.right_pulses == Approx(b.plant.right_m * 5000).margin(8));
}

TEST_CASE("the PWM duty saturates and the error sum does not wind up", "[board][firmware]") {
  Bench b;
  b.sync();
  (void)b.drive(3.0, 3.0);  // above what the motors can reach at 100 % duty
  b.run_for(1s);
  CHECK(b.board->duty(0) == 1.0);
  CHECK(b.board->wheel_speed_m_s(0) == Approx(1.0).margin(0.01));  // max at a full pack
  (void)b.drive(0.4, 0.4);
  b.run_for(500ms);
  CHECK(b.board->wheel_speed_m_s(0) == Approx(0.4).margin(0.01));
  // Reversing stops the motor first, then drives the other way.
  (void)b.drive(-0.4, 0.4);
  b.run_for(11ms);
  CHECK(b.board->duty(0) == 0.0);
  b.run_for(1s);
  CHECK(b.board->wheel_speed_m_s(0) == Approx(-0.4).margin(0.01));
  // Zero stops at once.
  (void)b.drive(0.0, 0.0);
  b.run_for(11ms);
  CHECK(b.board->duty(0) == 0.0);
  CHECK(b.board->duty(1) == 0.0);
}

TEST_CASE("the link watchdog stops the motors when the master goes silent", "[board][firmware]") {
  FirmwareConfig c;
  c.link_timeout = 100ms;
  Bench b(c);
  b.sync();
  (void)b.drive(0.5, 0.5);
  b.run_for(95ms);
  CHECK_FALSE(b.board->link_lost());
  b.run_for(10ms);
  CHECK(b.board->link_lost());
  // At the first tick past the timeout after the last decoded request.
  CHECK(b.board->link_lost_at() - b.board->last_request_at() == 101ms);
  CHECK(b.board->required_m_s(0) == 0.0);
  CHECK(b.board->duty(0) == 0.0);
  CHECK(b.board->counters().watchdog_trips == 1);
  // Not synchronised any more: commands are refused until the next SYNC.
  CHECK(b.exchange(Command::drive, {0xC8, 0x00, 0xFA, 0x00}) == Bytes{0x10, 0x03, 0xEE, 0x02, 0x12, 0xBE});
  b.run_for(300ms);
  CHECK(b.board->wheel_speed_m_s(0) == Approx(0.0).margin(1e-3));
  b.sync();
  const DriveState s = b.drive(0.1, 0.1);
  CHECK((s.status & kStatusSynchronised) != 0);
  CHECK((s.status & kStatusLinkLost) == 0);
}

TEST_CASE("the battery discharges with the load and is sampled every 3 s", "[board][firmware]") {
  Bench idle;
  Bench loaded;
  idle.sync();
  loaded.sync();
  (void)loaded.response(Command::uv_lamp, {1});
  (void)loaded.response(Command::atomizer, {1, 1});
  for (int i = 0; i < 60; ++i) {  // one minute; the master keeps the link alive
    (void)idle.response(Command::status);
    (void)loaded.drive(0.5, 0.5);
    idle.run_for(1s);
    loaded.run_for(1s);
  }
  CHECK(loaded.board->state_of_charge() < idle.board->state_of_charge());
  // Loaded: idle + UV lamp + atomizer + fan + two motors at about half duty.
  CHECK(loaded.board->battery_current_a() > 2.5);
  CHECK(idle.board->battery_current_a() == Approx(0.4));
  const double drawn_ah = (1.0 - idle.board->state_of_charge()) * 10.4;
  CHECK(drawn_ah == Approx(0.4 * 62.0 / 3600.0).epsilon(0.05));
  // The reported value is the latest 3-s sample, 16.8 V full, 12 V empty.
  Bench b;
  b.sync();
  b.board->set_state_of_charge(0.5);
  auto battery = unpack_battery(b.response(Command::battery).payload);
  REQUIRE(battery);
  CHECK(battery->percent == 100);  // sampled at power-on
  b.run_for(3s);
  (void)b.response(Command::status);
  battery = unpack_battery(b.response(Command::battery).payload);
  CHECK(battery->percent == 50);
  CHECK(battery->voltage_mv == Approx(14400).margin(5));
  CHECK_FALSE(battery->charging);
}

TEST_CASE("the tank empties while atomizing and the atomizer stops dry", "[board][firmware]") {
  FirmwareConfig c = Bench::patient();
  c.tank_initial_l = 0.01;  // 1 min at 0.6 L/h
  Bench b(c);
  b.sync();
  (void)b.response(Command::atomizer, {1, 1});
  CHECK(b.board->atomizer());
  for (int i = 0; i < 70; ++i) {
    (void)b.response(Command::status);
    b.run_for(1s);
  }
  CHECK_FALSE(b.board->atomizer());
  CHECK(b.board->fan());
  CHECK(b.board->disinfectant_used_l() == Approx(0.01));
  const Response level = b.response(Command::liquid_level);
  CHECK(level.payload[0] == 0);
  CHECK(level.payload[1] == 1);
  (void)b.response(Command::atomizer, {1, 1});
  CHECK_FALSE(b.board->atomizer());  // refused while empty
  b.board->set_tank_l(1.0);
  (void)b.response(Command::atomizer, {1, 0});
  CHECK(b.board->atomizer());
}

TEST_CASE("sensors, buttons, voice and LCD over the protocol", "[board][firmware]") {
  Bench b;
  b.plant.view.ultrasonic_m = {1.2F, std::numeric_limits<float>::infinity(), 0.35F};
  b.plant.view.cliff_floor_m = {0.02F, 0.3F, 0.02F};
  b.plant.view.wall_m = {0.12F, std::numeric_limits<float>::infinity()};
  b.plant.view.bumps = 0x02;
  b.sync();
  b.run_for(20ms);
  Response r = b.response(Command::ultrasonic);
  CHECK(Bytes(r.payload.begin(), r.payload.end()) == Bytes{3, 0xB0, 0x04, 0xFF, 0xFF, 0x5E, 0x01});
  r = b.response(Command::infrared);
  CHECK(Bytes(r.payload.begin(), r.payload.end()) == Bytes{3, 2, 20, 0, 0x2C, 0x01, 20, 0, 120, 0, 0xFF, 0xFF});
  r = b.response(Command::bump);
  CHECK(Bytes(r.payload.begin(), r.payload.end()) == Bytes{0x02, 0x02, 0x00, 0x00});  // bump 1, cliff 1
  // Emergency stop: the motors brake at once and stay stopped while it is held.
  (void)b.drive(0.5, 0.5);
  b.run_for(200ms);
  b.board->set_buttons(kButtonEmergencyStop);
  CHECK(b.board->duty(0) == 0.0);
  const DriveState s = b.drive(0.5, 0.5);
  CHECK((s.status & kStatusEmergencyStop) != 0);
  CHECK(s.buttons == kButtonEmergencyStop);
  CHECK(b.board->required_m_s(0) == 0.0);
  b.board->set_buttons(0);
  r = b.response(Command::buttons);
  CHECK(Bytes(r.payload.begin(), r.payload.end()) == Bytes{0x00, kButtonEmergencyStop});  // pressed since the last read
  r = b.response(Command::buttons);
  CHECK(Bytes(r.payload.begin(), r.payload.end()) == Bytes{0x00, 0x00});
  (void)b.response(Command::voice, {3});
  CHECK(b.board->last_voice_track() == 3);
  (void)b.response(Command::lcd_text, {1, 'H', 'i'});
  CHECK(b.board->lcd_line(1) == "Hi");
  CHECK(b.exchange(Command::lcd_text, {9, 'x'}) == Bytes{0x10, 0x03, 0xEE, 0x06, 0x33, 0x0D});
}

TEST_CASE("a frame whose bytes stop coming is given up on the idle line, so the next request is answered", "[board][firmware]") {
  Bench b;
  // A SYNC whose Length was corrupted from 2 to 0xA2 (162): the board would take the next 159
  // bytes as its body, swallowing every request the host sends meanwhile.
  const Bytes corrupt{0x10, 0xA2, 0xA8, 0x00, 0x01};
  REQUIRE(b.line.host().write(corrupt));
  b.run_for(b.config.frame_idle_timeout + 2ms);  // the line idle past the timeout
  CHECK(b.board->decoder_stats().truncated == 1);
  const Bytes sync{0x10, 0x02, 0xA8, 0x00, 0x01};
  CHECK(b.exchange_raw(sync) == sync);  // echoed: the board listened again
  CHECK(b.board->synchronised());
}

// Section 3.4.3: the cliff bit follows the difference of two successive ADC readings against the
// threshold, not the distance itself: a step down sets it, a step up clears it, a floor that
// drifts slowly farther (a ramp) does not, and a sensor stuck at the floor's reading never does.
TEST_CASE("cliff judgment: ADC difference of two measurements against the pre-fixed threshold", "[board][firmware]") {
  FirmwareConfig c = Bench::patient();
  CHECK(cliff_sensor_adc(0.02) == 2482);  // 2.0 V of 3.3 V, 12 bits
  CHECK(cliff_sensor_adc(0.15) == 496);
  CHECK(cliff_sensor_adc(std::numeric_limits<double>::infinity()) == cliff_sensor_adc(0.15));  // no return: the far end
  CHECK(cliff_adc_threshold(c) == cliff_sensor_adc(0.02) - cliff_sensor_adc(0.05));
  Bench b(c);
  const auto cliff_bits = [&] {
    const Response r = b.response(Command::bump);
    return static_cast<unsigned>(r.payload[1]);  // bits 8-15 of the bitmap: the cliff judgments
  };
  b.plant.view.cliff_floor_m = {0.02F, 0.02F, 0.02F};
  b.sync();
  b.run_for(30ms);
  CHECK(cliff_bits() == 0U);
  // Sensor 1 passes a ledge: one step to no return. The bit stays set while it sees no floor
  // (the difference of two readings over the drop is zero), and clears on the step back.
  b.plant.view.cliff_floor_m[1] = std::numeric_limits<float>::infinity();
  b.run_for(30ms);
  CHECK(cliff_bits() == 0x02U);
  b.run_for(500ms);
  CHECK(cliff_bits() == 0x02U);
  b.plant.view.cliff_floor_m[1] = 0.02F;
  b.run_for(30ms);
  CHECK(cliff_bits() == 0U);
  // A step smaller than the threshold (a 2 cm sill, floor at 4 cm) is floor.
  b.plant.view.cliff_floor_m[2] = 0.04F;
  b.run_for(30ms);
  CHECK(cliff_bits() == 0U);
  // A slope: the floor goes away a millimetre per measurement. Each difference stays under the
  // threshold, so the thesis's rule does not see it (the reason the sensors look ahead of the
  // wheels: a ledge is a step).
  b.plant.view.cliff_floor_m[2] = 0.02F;
  b.run_for(30ms);
  for (int k = 0; k < 100; ++k) {
    b.plant.view.cliff_floor_m[0] = 0.02F + 0.001F * static_cast<float>(k);
    b.run_for(10ms);
  }
  CHECK(cliff_bits() == 0U);
}

TEST_CASE("cliff judgment: a robot switched on over a drop sees it at the first measurement", "[board][firmware]") {
  Bench b;
  b.plant.view.cliff_floor_m = {std::numeric_limits<float>::infinity(), 0.02F, 0.02F};
  b.sync();
  b.run_for(20ms);
  const Response r = b.response(Command::bump);
  CHECK(r.payload[1] == 0x01);
}

// Issue 42 item 5: a request waited for the next 1 ms tick before its answer (p99 1.9 ms over a
// pty). The receive interrupt answers it as soon as its bytes are in.
TEST_CASE("on_receive answers a request between ticks, as soon as its bytes have arrived", "[board][firmware]") {
  Bench b;
  b.run_for(1ms);  // the tick at 1 ms has run; the next is at 2 ms
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  const std::size_t n = encode_request(static_cast<std::uint8_t>(Command::sync), {}, out);
  REQUIRE(b.line.host().write(std::span<const std::uint8_t>(out.data(), n)));
  b.clock.advance(b.line.byte_time() * static_cast<std::int64_t>(n));  // the request is in: 1.43 ms
  std::array<std::uint8_t, 64> in{};
  b.board->run_until(b.clock.now());
  b.clock.advance(b.line.byte_time() * static_cast<std::int64_t>(n));  // 1.87 ms: an echo would be in
  CHECK(b.line.host().read(in, b.clock.now()) == 0);                   // ticks alone: not yet answered
  CHECK_FALSE(b.board->synchronised());

  b.board->on_receive(b.clock.now());
  CHECK(b.board->synchronised());
  CHECK(b.board->now() == Time{} + 1ms);                               // no tick ran early
  b.clock.advance(b.line.byte_time() * static_cast<std::int64_t>(n));  // 2.3 ms: sent at 1.87 ms
  CHECK(b.line.host().read(in, b.clock.now()) == static_cast<std::ptrdiff_t>(n));
  CHECK(std::equal(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(n), out.begin()));
}
