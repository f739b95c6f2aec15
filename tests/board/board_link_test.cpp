#include "tripodal/board/board_link.hpp"

#include <catch2/catch.hpp>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/serial_line.hpp"
#include "still_plant.hpp"

using namespace tripodal;
using namespace tripodal::board;
using tripodal::board::test::StillPlant;
using namespace std::chrono_literals;

namespace {

// Host and board on one simulated line and clock: the board ticks every 1 ms, the host's control
// loop cycles every 10 ms.
struct Rig {
  Rig() = default;
  explicit Rig(const LinkConfig& config) : link_config(config) {}

  SimClock clock;
  SerialLine line{clock};
  StillPlant plant;
  FirmwareConfig firmware_config;
  BoardFirmware board{firmware_config, line.board(), plant};
  LinkConfig link_config{};
  BoardLink link{line.host(), link_config};
  WheelSpeeds speeds{};
  std::uint64_t losses_seen = 0;
  Time first_loss_seen{};

  void run_for(Duration d) {
    const Time end = clock.now() + d;
    while (clock.now() < end) {
      clock.advance(1ms);
      board.run_until(clock.now());
      if (to_ns(clock.now()) % 10'000'000 == 0) {
        link.cycle(clock.now(), speeds);
        if (link.take_link_lost()) {
          if (losses_seen++ == 0) first_loss_seen = clock.now();
        }
      }
    }
  }
};

}  // namespace

TEST_CASE("the host synchronises, drives every period and polls the sensors", "[board][link]") {
  Rig r;
  r.speeds = {250, 250};
  r.run_for(4s);
  CHECK(r.link.synchronised());
  CHECK(r.board.wheel_speed_m_s(0) == Approx(0.25).margin(0.01));
  CHECK(r.link.drive().encoders.left_mm_s == Approx(250).margin(10));
  CHECK(r.link.stats().missed == 0);
  CHECK(r.link.stats().error_responses == 0);
  CHECK(r.link.stats().responses >= r.link.stats().requests - 1);  // the last one is on the line
  // The loop reads once a period: a response (3.8 ms of line time) is taken at the next cycle.
  CHECK(r.link.stats().max_round_trip == 10ms);
  CHECK(r.link.has_battery());
  CHECK(r.link.battery().percent == 100);
  CHECK(r.link.ultrasonic_mm().size() == 3);
  CHECK(r.link.ultrasonic_mm()[2] == 1200);
  CHECK(r.link.tank_percent() == 100);
  CHECK(r.losses_seen == 0);
}

TEST_CASE("a board that stops answering: link lost within two periods, motors stopped by its watchdog, then resynchronised", "[board][link]") {
  Rig r;
  r.speeds = {300, 300};
  r.run_for(1s);
  REQUIRE(r.link.synchronised());
  const Time last_good = r.link.drive_stamp();
  r.line.board().set_connected(false);  // the board's answers no longer reach the host
  r.run_for(500ms);
  CHECK(r.losses_seen == 1);
  CHECK(r.first_loss_seen - last_good <= 20ms);  // two control periods
  CHECK(r.link.link_lost_at() == r.first_loss_seen);
  // The host sends SYNC until it is answered; a SYNC stops the board's motors.
  CHECK(r.board.wheel_speed_m_s(0) == Approx(0.0).margin(1e-3));
  r.line.board().set_connected(true);
  r.run_for(100ms);
  CHECK(r.link.synchronised());
  CHECK(r.link.stats().resyncs == 2);
  CHECK(r.link.stats().link_losses == 1);
}

// A host without real-time scheduling (the disinfection profiles: response_timeout 50 ms,
// max_missed 4) must ride out a stall shorter than the board's 200 ms watchdog. The stall times
// out both requests in flight each period; counted one by one they lost the link after 100 ms.
TEST_CASE("a stall misses every request in flight once: max_missed x response_timeout of silence lose the link",
          "[board][link]") {
  LinkConfig config;
  config.response_timeout = 50ms;
  config.max_missed = 4;
  Rig r(config);
  r.speeds = {300, 300};
  r.run_for(1s);
  REQUIRE(r.link.synchronised());
  const Time last_good = r.link.drive_stamp();
  const std::uint64_t missed_before = r.link.stats().missed;
  r.line.board().set_connected(false);
  r.run_for(150ms);
  CHECK(r.losses_seen == 0);  // 150 ms of silence: a blip the link rides out
  CHECK(r.link.synchronised());
  CHECK(r.link.stats().missed - missed_before >= 4);  // each request is still counted as missed
  r.run_for(350ms);
  CHECK(r.losses_seen == 1);
  CHECK(r.first_loss_seen - last_good >= 200ms);
  CHECK(r.first_loss_seen - last_good <= 230ms);
  r.line.board().set_connected(true);
  r.run_for(100ms);
  CHECK(r.link.synchronised());
  CHECK(r.link.stats().link_losses == 1);
}

TEST_CASE("the board's watchdog stops the motors when the host goes silent", "[board][link]") {
  Rig r;
  r.speeds = {300, 300};
  r.run_for(1s);
  r.line.host().set_connected(false);  // the host's requests no longer reach the board
  const Time cut = r.clock.now();
  r.run_for(400ms);
  CHECK(r.board.link_lost());
  CHECK(r.board.link_lost_at() - cut <= 210ms);  // link_timeout 200 ms after the last request
  CHECK(r.board.duty(0) == 0.0);
  CHECK(r.losses_seen == 1);
  r.line.host().set_connected(true);
  r.run_for(100ms);
  CHECK(r.link.synchronised());
  CHECK(r.board.synchronised());
  CHECK(r.board.wheel_speed_m_s(0) > 0.1);
}

TEST_CASE("actuator commands are never silently lost", "[board][link]") {
  Rig r;
  r.run_for(100ms);
  r.line.host().set_connected(false);
  REQUIRE(r.link.queue(Command::uv_lamp, std::array<std::uint8_t, 1>{1}));
  const std::array<std::uint8_t, 2> fog{1, 1};
  REQUIRE(r.link.queue(Command::atomizer, fog));
  r.run_for(300ms);
  CHECK_FALSE(r.board.uv_lamp());
  CHECK(r.link.pending_actuator_commands() == 2);
  r.line.host().set_connected(true);
  r.run_for(200ms);
  CHECK(r.board.uv_lamp());
  CHECK(r.board.atomizer());
  CHECK(r.link.pending_actuator_commands() == 0);
}
