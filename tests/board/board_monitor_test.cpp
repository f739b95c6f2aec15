#include "tripodal/board/board_monitor.hpp"

#include <catch2/catch.hpp>

#include <optional>
#include <string>

#include "tripodal/board/embedded_board.hpp"
#include "still_plant.hpp"

using namespace std::chrono_literals;
using namespace tripodal::board;
using tripodal::ModuleContext;
using tripodal::ModuleEvent;
using tripodal::ResourceTable;
using tripodal::Time;
using tripodal::board::test::StillPlant;

namespace {

// The robot's order at each instant: the board moves to `now`, the sequencing loop (the monitor),
// then the reactive loop (the link's exchange, when its resources are polled).
struct Rig {
  StillPlant plant;
  EmbeddedBoard board{FirmwareConfig{}, plant, BoardHardwareConfig{}};
  ResourceTable table;
  BoardMonitor monitor;
  ModuleContext ctx;
  Time now{};

  explicit Rig(const tripodal::ParameterValues& params = {}) {
    board.host().add_resources(table);
    monitor.configure(params);
    ctx.hardware = &board.host();
    ctx.resources = &table;
    monitor.start(ctx);
  }
  // One control period; the fault the monitor reported, if any.
  std::optional<std::string> period() {
    now += 10ms;
    board.advance_to(now);
    ctx.now = now;
    ctx.events.clear();
    std::optional<std::string> fault;
    try {
      monitor.update(ctx);
    } catch (const std::runtime_error& e) {
      fault = e.what();
    }
    table.poll_all(now);
    return fault;
  }
  [[nodiscard]] std::string message(const std::string& event) const {
    for (const ModuleEvent& e : ctx.events) {
      if (e.name == event) return e.message;
    }
    return {};
  }
  [[nodiscard]] bool posted(const std::string& event) const {
    for (const ModuleEvent& e : ctx.events) {
      if (e.name == event) return true;
    }
    return false;
  }
};

}  // namespace

TEST_CASE("BoardMonitor: a dead link is a fault event within two control periods, and its recovery", "[board][monitor]") {
  Rig rig;
  for (int i = 0; i < 50; ++i) REQUIRE_FALSE(rig.period());
  REQUIRE(rig.board.host().link().synchronised());
  CHECK(rig.board.host().link().stats().max_round_trip <= 10ms);  // answered by the next period

  // The board stops answering (its transmitter cut) right after the exchange at `cut`.
  const Time cut = rig.now;
  rig.board.line().board().set_connected(false);
  std::optional<std::string> fault;
  int periods = 0;
  while (!fault && periods < 10) {
    fault = rig.period();
    ++periods;
  }
  REQUIRE(fault);
  // The fault's message is fixed, for a recovery rule to match; the event carries the details.
  CHECK(*fault == "link lost");
  REQUIRE(rig.posted("board.link_lost"));
  CHECK_THAT(rig.message("board.link_lost"),
             Catch::Contains("link lost at") && Catch::Contains("no valid response from the board"));
  CHECK(periods <= 2);  // the request of `cut` unanswered at cut + 10 ms, posted at cut + 20 ms
  CHECK(rig.now - cut <= 20ms);
  CHECK(rig.board.host().link().stats().link_losses == 1);

  // The board's watchdog stops the motors; answering again, SYNC restores the link.
  rig.board.line().board().set_connected(true);
  bool restored = false;
  for (int i = 0; i < 50 && !restored; ++i) {
    REQUIRE_FALSE(rig.period());
    restored = rig.posted("board.link_restored");
  }
  CHECK(restored);
  CHECK(rig.board.host().link().synchronised());
}

// A host without real-time scheduling misses the board's watchdog now and then (not scheduled for
// a few hundred ms under load): the link is lost and answers SYNC again at the host's next cycle.
// With a grace, such a blip goes on without a fault; a loss that lasts is still one.
TEST_CASE("BoardMonitor: a link that answers again within link_grace_s is a blip, not a fault", "[board][monitor]") {
  Rig rig(tripodal::ParameterValues{{"link_grace_s", "0.5"}});
  for (int i = 0; i < 50; ++i) REQUIRE_FALSE(rig.period());
  REQUIRE(rig.board.host().link().synchronised());

  // A blip: 100 ms without answers (the link is lost at its first missed response), then SYNC.
  rig.board.line().board().set_connected(false);
  bool blip = false;
  for (int i = 0; i < 10; ++i) {
    REQUIRE_FALSE(rig.period());
    CHECK_FALSE(rig.posted("board.link_lost"));
  }
  CHECK(rig.board.host().link().stats().link_losses == 1);
  rig.board.line().board().set_connected(true);
  for (int i = 0; i < 30 && !blip; ++i) {
    REQUIRE_FALSE(rig.period());
    CHECK_FALSE(rig.posted("board.link_lost"));
    CHECK_FALSE(rig.posted("board.link_restored"));
    if (rig.posted("board.link_blip")) {
      blip = true;
      CHECK_THAT(rig.message("board.link_blip"), Catch::Contains("SYNC answered again") && Catch::Contains("task goes on"));
    }
  }
  CHECK(blip);
  for (int i = 0; i < 100; ++i) REQUIRE_FALSE(rig.period());  // the grace of the blip long gone: no late fault

  // A loss that lasts: the fault once the grace has passed since the loss, then the restore as usual.
  rig.board.line().board().set_connected(false);
  const Time cut = rig.now;
  std::optional<std::string> fault;
  while (!fault && rig.now - cut < 2s) fault = rig.period();
  REQUIRE(fault);
  CHECK(*fault == "link lost");
  CHECK(rig.posted("board.link_lost"));
  CHECK(rig.now - cut >= 500ms);
  CHECK(rig.now - cut <= 530ms);
  rig.board.line().board().set_connected(true);
  bool restored = false;
  for (int i = 0; i < 50 && !restored; ++i) {
    REQUIRE_FALSE(rig.period());
    restored = rig.posted("board.link_restored");
    CHECK_FALSE(rig.posted("board.link_blip"));
  }
  CHECK(restored);
}

TEST_CASE("BoardMonitor: the emergency stop brakes at once and is a fault, the other buttons are events", "[board][monitor]") {
  Rig rig;
  for (int i = 0; i < 30; ++i) REQUIRE_FALSE(rig.period());

  rig.board.firmware().set_buttons(kButtonStart);
  bool started = false;
  for (int i = 0; i < 3 && !started; ++i) {
    REQUIRE_FALSE(rig.period());
    started = rig.posted("board.start");
  }
  CHECK(started);
  rig.board.firmware().set_buttons(0);
  REQUIRE_FALSE(rig.period());
  CHECK_FALSE(rig.posted("board.start"));  // an edge, posted once

  // Drive, then press the e-stop between two periods: the board brakes on that tick.
  const std::array<double, 2> wheels{2.0, 2.0};
  for (int i = 0; i < 50; ++i) {
    rig.board.host().wheels().write_wheel_velocities(wheels);
    REQUIRE_FALSE(rig.period());
  }
  REQUIRE(rig.board.firmware().required_m_s(0) > 0.1);
  rig.board.firmware().set_buttons(kButtonEmergencyStop);
  CHECK(rig.board.firmware().required_m_s(0) == 0.0);
  std::optional<std::string> fault;
  int periods = 0;
  while (!fault && periods < 5) {
    rig.board.host().wheels().write_wheel_velocities(wheels);
    fault = rig.period();
    ++periods;
  }
  REQUIRE(fault);
  CHECK_THAT(*fault, Catch::Contains("emergency stop pressed"));
  CHECK(rig.posted("board.emergency_stop"));
  CHECK(periods <= 2);
  CHECK(rig.board.firmware().required_m_s(0) == 0.0);  // held whatever the host asks
}

TEST_CASE("BoardMonitor refuses a robot whose hardware is not a board", "[board][monitor]") {
  BoardMonitor monitor;
  monitor.configure();
  ModuleContext ctx;
  REQUIRE_THROWS_WITH(monitor.start(ctx), Catch::Contains("module BoardMonitor reads the control board") &&
                                              Catch::Contains("this robot's is 'none'"));
}

// On the robot's own threads the reactive loop's thread runs the link and the sequencing thread
// runs the monitor: the monitor must see the link only as the snapshot hands it over (reading
// BoardLink itself raced the link's cycle). Here the snapshot is held back by hand: a loss the
// link has already seen is not the monitor's until it is published and refreshed.
TEST_CASE("BoardMonitor reads the link through the resource snapshot, never the link itself", "[board][monitor]") {
  Rig rig;
  tripodal::ResourceSnapshot snapshot(rig.table);
  rig.ctx.resources = &snapshot.table();
  const auto hand_over = [&] {
    snapshot.publish();
    (void)snapshot.refresh();
  };
  for (int i = 0; i < 30; ++i) {
    REQUIRE_FALSE(rig.period());
    hand_over();
  }
  REQUIRE(rig.ctx.facts.size() == 1);  // board_linked true, set once the link was up
  CHECK(rig.ctx.facts[0].first == "board_linked");
  rig.ctx.facts.clear();

  rig.board.line().board().set_connected(false);
  for (int i = 0; i < 5; ++i) REQUIRE_FALSE(rig.period());  // lost by now, but not handed over
  REQUIRE(rig.board.host().link().stats().link_losses == 1);
  CHECK_FALSE(rig.posted("board.link_lost"));
  hand_over();
  const std::optional<std::string> fault = rig.period();
  REQUIRE(fault);
  CHECK(*fault == "link lost");
  CHECK(rig.posted("board.link_lost"));
  REQUIRE(rig.ctx.facts.size() == 1);
  CHECK(rig.ctx.facts[0].second == tripodal::Value{false});
}
