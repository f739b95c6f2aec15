#include "tripodal/board/board_hardware.hpp"

#include <array>
#include <catch2/catch.hpp>
#include <memory>

#include "still_plant.hpp"
#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/serial_line.hpp"

using namespace tripodal;
using namespace tripodal::board;
using tripodal::board::test::StillPlant;
using namespace std::chrono_literals;

TEST_CASE("hardware 'board': wheels through DRIVE, odometry from the encoders, sensors as resources", "[board][hardware]") {
  SimClock clock;
  SerialLine line(clock);
  StillPlant plant;
  plant.view.cliff_floor_m = {0.02F, 0.5F, 0.02F};
  plant.view.bumps = 0x01;
  BoardFirmware board(FirmwareConfig{}, line.board(), plant);
  BoardHardware hw(line.host(), BoardHardwareConfig{});
  ResourceTable table;
  hw.add_resources(table);
  REQUIRE(table.size() == 6);
  CHECK(table.at(0).name() == "board_link");
  REQUIRE(table.find<BatteryReading>("battery") != nullptr);
  REQUIRE(table.find<TankReading>("tank") != nullptr);  // the liquid level module, for the LCD
  REQUIRE(table.find<SonarReading>("ultrasonic") != nullptr);
  REQUIRE(table.find<InfraredReading>("cliff") != nullptr);
  REQUIRE(table.find<BumperReading>("bumpers") != nullptr);
  CHECK(hw.manifest().name == "board");

  const std::array<double, 2> wheels{2.0, 2.0};  // rad/s at r = 0.09 m: 180 mm/s
  std::array<double, 2> vel{}, pos{};
  bool accepted = false;
  for (int ms = 1; ms <= 2000; ++ms) {
    clock.advance(1ms);
    board.run_until(clock.now());
    if (ms % 10 == 0) {
      table.poll_all(clock.now());
      accepted = hw.wheels().write_wheel_velocities(wheels);
    }
  }
  CHECK(accepted);
  CHECK(board.required_m_s(0) == Approx(0.18));
  REQUIRE(hw.wheels().read_wheel_states(vel, pos));
  CHECK(vel[0] == Approx(2.0).margin(0.1));
  CHECK(pos[0] == Approx(board.pulses(0) / (5000.0 * 0.09)).margin(0.05));
  CHECK(table.find<BumperReading>("bumpers")->latest().pressed_mask == 0x01);
  CHECK(table.find<InfraredReading>("cliff")->latest().cliff == std::vector<std::uint8_t>{0, 1, 0});
  CHECK(table.find<SonarReading>("ultrasonic")->latest().ranges_m.size() == 3);
  CHECK(table.find<BatteryReading>("battery")->latest().percentage == Approx(1.0));

  // The board stops answering: the wheels refuse writes (the controller's hardware fault) within
  // two control periods, and the link-lost event is there to post once.
  line.board().set_connected(false);
  int refused_after_ms = -1;
  for (int ms = 1; ms <= 100 && refused_after_ms < 0; ++ms) {
    clock.advance(1ms);
    board.run_until(clock.now());
    if (ms % 10 == 0) {
      table.poll_all(clock.now());
      if (!hw.wheels().write_wheel_velocities(wheels)) refused_after_ms = ms;
    }
  }
  CHECK(refused_after_ms > 0);
  CHECK(refused_after_ms <= 20);
  CHECK(hw.take_link_lost());
  CHECK_FALSE(hw.take_link_lost());
  CHECK_FALSE(hw.wheels().read_wheel_states(vel, pos));
}

// A board power-cycled (or its process replaced) under the host: its encoders count from 0 again.
// The host's wheel positions go on from where they were (a jump back would be odometry's jump).
TEST_CASE("hardware 'board': a board restarted under the host, the wheel positions go on without a jump", "[board][hardware]") {
  SimClock clock;
  SerialLine line(clock);
  StillPlant plant;
  auto board = std::make_unique<BoardFirmware>(FirmwareConfig{}, line.board(), plant);
  BoardHardware hw(line.host(), BoardHardwareConfig{});
  ResourceTable table;
  hw.add_resources(table);
  const std::array<double, 2> wheels{2.0, 2.0};
  std::array<double, 2> vel{}, pos{};
  const auto run_ms = [&](int ms_total, bool drive) {
    for (int ms = 1; ms <= ms_total; ++ms) {
      clock.advance(1ms);
      board->run_until(clock.now());
      if (ms % 10 == 0) {
        table.poll_all(clock.now());
        (void)hw.wheels().write_wheel_velocities(drive ? wheels : std::array<double, 2>{});
        (void)hw.wheels().read_wheel_states(vel, pos);
      }
    }
  };
  run_ms(1000, true);
  run_ms(1000, false);  // at rest
  REQUIRE(hw.wheels().read_wheel_states(vel, pos));
  const double before = pos[0];
  REQUIRE(before > 1.0);  // about 0.15 m driven at r = 0.09 m

  // Unplugged, a new board plugged in on the same line: its counts start at 0.
  line.board().set_connected(false);
  run_ms(100, false);
  board = std::make_unique<BoardFirmware>(FirmwareConfig{}, line.board(), plant, clock.now());
  line.board().set_connected(true);
  run_ms(1000, false);
  REQUIRE(hw.link().stats().link_losses == 1);
  REQUIRE(hw.link().synchronised());
  REQUIRE(board->pulses(0) == 0);
  REQUIRE(hw.wheels().read_wheel_states(vel, pos));
  CHECK(pos[0] == Approx(before).margin(1e-6));
  run_ms(500, true);  // and the new counts add to them
  REQUIRE(hw.wheels().read_wheel_states(vel, pos));
  CHECK(pos[0] > before + 0.1);
}

TEST_CASE("hardware 'board' is registered with its parameters and refuses a wrong configuration", "[board][hardware]") {
  HardwareRegistry registry("hardware type");
  register_board_hardware(registry);
  REQUIRE(registry.contains("board"));
  HardwareConfig c;
  c.type = "board";
  c.where = SourceLocation{SourceFile(std::string_view("robot.yaml")), 12, 3};
  c.parameters = ParameterSet::resolve(registry.manifest("board"), {}, c.where);
  ControllerConfig base;
  base.type = "omni";
  c.base = &base;
  REQUIRE_THROWS_WITH(registry.create("board", c), Catch::Contains("robot.yaml:12:3: error: hardware 'board' drives a differential base"));
  base.type = "differential";
  base.differential = {0.42, 0.09};
  REQUIRE_THROWS_WITH(registry.create("board", c), Catch::Contains("hardware 'board' needs its port"));
  c.parameters = ParameterSet::resolve(registry.manifest("board"), {{"port", Value{std::string("/nonexistent/ttyBOARD")}}}, c.where);
  REQUIRE_THROWS_WITH(registry.create("board", c), Catch::Contains("serial port /nonexistent/ttyBOARD: open: No such file or directory"));
}
