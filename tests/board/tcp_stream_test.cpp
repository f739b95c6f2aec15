// The board's backup transport (the ESP8266 Wi-Fi link, seed 001 sections 2.2 and 3.1) on
// loopback: the same frames over TCP, the same link monitoring (SYNC, reconnect after the module
// drops the connection). Simulated time for both ends; the kernel's loopback is real; bounded
// loops, no sleeps.
#include "tripodal/board/tcp_stream.hpp"

#include <catch2/catch.hpp>

#include <array>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/board_hardware.hpp"
#include "tripodal/board/board_link.hpp"
#include "still_plant.hpp"

using namespace tripodal;
using namespace tripodal::board;
using tripodal::board::test::StillPlant;
using namespace std::chrono_literals;

namespace {

struct TcpRig {
  SimClock clock;
  SteadyClock real;
  TcpServerStream server{real};  // the board's module, listening on 127.0.0.1
  TcpStream client{server.spec(), real};
  StillPlant plant;
  BoardFirmware board{FirmwareConfig{}, server, plant};
  BoardLink link{client, [] {
                   LinkConfig c;
                   // Loopback delivers within the sender's call; a margin for a loaded machine.
                   c.response_timeout = 50ms;
                   return c;
                 }()};

  void run_for(Duration d) {
    const Time end = clock.now() + d;
    while (clock.now() < end) {
      clock.advance(1ms);
      board.run_until(clock.now());
      if (to_ns(clock.now()) % 10'000'000 == 0) link.cycle(clock.now(), WheelSpeeds{150, 150});
    }
  }
};

}  // namespace

TEST_CASE("the link runs over TCP as over the UART: SYNC, DRIVE, polls, commands", "[board][tcp]") {
  TcpRig r;
  r.run_for(2s);
  const std::array<std::uint8_t, 2> fog{1, 1};
  REQUIRE(r.link.queue(Command::atomizer, fog));
  r.run_for(2s);
  CHECK(r.link.synchronised());
  CHECK(r.server.connections() == 1);
  CHECK(r.link.stats().resyncs == 1);
  CHECK(r.link.stats().responses > 300);
  CHECK(r.link.stats().error_responses == 0);
  CHECK(r.link.has_battery());
  CHECK(r.board.atomizer());
  CHECK(r.board.wheel_speed_m_s(0) == Approx(0.15).margin(0.01));
  CHECK(r.board.decoder_stats().errors() == 0);
}

TEST_CASE("a dropped TCP connection is noticed, reconnected and resynchronised", "[board][tcp]") {
  TcpRig r;
  r.run_for(1s);
  REQUIRE(r.link.synchronised());
  r.server.drop();  // the module resets: the host's read sees the connection closed
  r.run_for(100ms);
  // Lost (the request outstanding when it closed is missed), reconnected at once, then SYNC.
  CHECK(r.link.stats().port_failures >= 1);
  CHECK(r.link.take_link_lost());
  r.run_for(2s);
  CHECK(r.link.synchronised());
  CHECK(r.link.stats().reopens >= 1);
  CHECK(r.link.stats().resyncs == 2);
  CHECK(r.server.connections() == 2);
}

TEST_CASE("a TCP port spec is checked and a refused connection named", "[board][tcp]") {
  SteadyClock clock;
  CHECK(is_tcp_port("tcp://127.0.0.1:4000"));
  CHECK_FALSE(is_tcp_port("/dev/ttyUSB0"));
  REQUIRE_THROWS_WITH(TcpStream("tcp://127.0.0.1", clock), Catch::Contains("tcp://127.0.0.1: expected tcp://HOST:PORT with PORT 1 to 65535"));
  REQUIRE_THROWS_WITH(TcpStream("tcp://127.0.0.1:70000", clock), Catch::Contains("expected tcp://HOST:PORT"));
  // A port nobody listens on: take one from a listener, then close it.
  std::uint16_t port = 0;
  {
    TcpServerStream s(clock);
    port = s.port();
  }
  const std::string spec = "tcp://127.0.0.1:" + std::to_string(port);
  REQUIRE_THROWS_WITH(TcpStream(spec, clock), Catch::Contains(spec + ": connect: Connection refused"));

  // Hardware 'board' with a tcp:// port: connects (here to a listener that never answers).
  TcpServerStream board_end(clock);
  HardwareRegistry registry("hardware type");
  register_board_hardware(registry);
  HardwareConfig c;
  c.type = "board";
  ControllerConfig base;
  base.type = "differential";
  base.differential = {0.42, 0.09};
  c.base = &base;
  c.parameters = ParameterSet::resolve(registry.manifest("board"), {{"port", Value{board_end.spec()}}}, c.where);
  CHECK(registry.create("board", c) != nullptr);
}
