// The disinfection robot end to end on the simulator: configs/robots/disinfection.yaml on the
// simulated board (hardware type "board", every exchange over the in-process line byte for byte),
// the task "disinfect the room ..." through PrAutoMove and PrDisinfection.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>

#include "../support/file_lines.hpp"
#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/board/board_monitor.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";

struct DisinfectionRobot {
  std::shared_ptr<const sim::World> world =
      std::make_shared<const sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml"));
  SimClock clock;
  RobotPlugins plugins;  // the robot keeps using them
  std::unique_ptr<Robot> robot;
  sim::SimBoardHardware* hw = nullptr;

  DisinfectionRobot() {
    register_all(plugins, world);
    // These tests are about the board's protocol and the net: the lanes as without a dose target
    // (the dose-planned run of a room is tests/app, tripodal_run_cli:disinfection_reaches_dose_2111).
    RobotOptions ro;
    ro.parameters.push_back({"coverage", "dose_target_j_m2", "0"});
    robot = Robot::assemble(load_robot_profile(kConfigs / "robots/disinfection.yaml"), plugins, clock, ro);
    hw = &dynamic_cast<sim::SimBoardHardware&>(*robot->hardware());
    if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(world->start_pose);
    robot->run_for(100ms);  // SYNC, the localizer's first estimate
  }
  // Runs until the task ends or `max_s` passes; `each` is called every 10 ms.
  template <class Fn>
  void run_task(double max_s, const Fn& each) {
    const Time end = clock.now() + from_seconds(max_s);
    while (robot->planner().busy() && clock.now() < end) {
      robot->run_for(10ms);
      each();
    }
  }
};

}  // namespace

namespace {

// The task "disinfect the room <room>" to its end, its figures printed, the link checked clean.
void check_disinfects(const std::string& room, double max_s) {
  DisinfectionRobot r;
  REQUIRE(r.hw->board().link().synchronised());
  const CommandAnswer answer = r.robot->command("disinfect the room " + room);
  INFO(answer.text);
  REQUIRE(answer.accepted);
  const board::BoardFirmware& fw = r.hw->embedded().firmware();
  const Time start = r.clock.now();
  Duration uv_on{0};
  bool fog_seen = false;
  r.run_task(max_s, [&] {
    if (fw.uv_lamp()) uv_on += 10ms;
    fog_seen = fog_seen || fw.atomizer();
  });
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(report.state == TaskState::succeeded);

  const board::LinkStats& link = r.hw->board().link().stats();
  const double duration_s = to_seconds(r.clock.now() - start);
  WARN("room " << room << ": task " << duration_s << " s, UV lamp on " << to_seconds(uv_on) << " s, disinfectant used "
                        << fw.disinfectant_used_l() << " l; link: " << link.requests << " requests, " << link.responses
                        << " responses, " << link.missed << " missed, max round trip " << to_seconds(link.max_round_trip)
                        << " s, " << r.hw->embedded().line().host().bytes_sent() << " bytes out, "
                        << r.hw->embedded().line().board().bytes_sent() << " bytes in");
  CHECK(link.missed == 0);
  CHECK(link.error_responses == 0);
  CHECK(link.link_losses == 0);
  CHECK(r.hw->board().link().decoder_stats().errors() == 0);
  CHECK(fw.decoder_stats().errors() == 0);
  CHECK(link.responses + 4 >= link.requests);  // the last exchanges still on the line
  CHECK(fw.counters().requests >= link.responses);
  CHECK(uv_on > 0.5 * (r.clock.now() - start) / 2);  // on while covering, off while driving between
  CHECK(fog_seen);
  CHECK(fw.disinfectant_used_l() > 0.0);
  // The process ended: lamp and fog off.
  r.robot->run_for(100ms);
  CHECK_FALSE(fw.uv_lamp());
  CHECK_FALSE(fw.atomizer());
}

}  // namespace

TEST_CASE("the disinfection robot disinfects a room over the board's protocol, byte for byte", "[board][disinfection]") {
  check_disinfects("2111", 1500.0);
}

// The thesis's task on the whole workspace (four sections): about four times as long; run by hand
// for the figures in docs/board-protocol.md.
TEST_CASE("the disinfection robot disinfects the room 3211", "[.][board][disinfection-3211]") { check_disinfects("3211", 8000.0); }

TEST_CASE("PrDisinfection: an empty tank pauses the fog and asks for disinfectant, a low battery ends it safely", "[board][disinfection]") {
  DisinfectionRobot r;
  board::BoardFirmware& fw = r.hw->embedded().firmware();
  fw.set_tank_l(0.002);  // runs dry after ~12 s of fog
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  bool fogged = false, prompted = false;
  r.run_task(60.0, [&] {
    fogged = fogged || fw.atomizer();
    prompted = prompted || fw.last_voice_track() == static_cast<std::uint8_t>(board::kTrackAddDisinfectant);
    if (prompted) r.robot->planner().cancel("stop here");  // checked below, not run to the end
  });
  CHECK(fogged);
  CHECK(prompted);
  CHECK_FALSE(fw.atomizer());
  r.robot->run_for(100ms);
  CHECK_FALSE(fw.uv_lamp());  // cancelled: every behavior deactivated, lamp off
}

// workspace.yaml has no dock (the dock and charge: tests/board/charge_test.cpp): the robot goes to
// the charger node to charge, finds no contacts there and the task ends with that reason.
TEST_CASE("PrDisinfection: a low battery ends the disinfection safely, lamp and fog off, and sends the robot to charge",
          "[board][disinfection]") {
  DisinfectionRobot r;
  board::BoardFirmware& fw = r.hw->embedded().firmware();
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(20.0, [] {});
  REQUIRE(fw.uv_lamp());
  fw.set_state_of_charge(0.10);  // sampled at the board's next 3 s, polled by the host every 3 s
  bool lamp_after_fault = false;
  r.run_task(300.0, [&] {
    // Off at the board within a few control periods of the fault (the commands cross the line).
    const auto& rec = r.robot->planner().report().recoveries;
    if (!rec.empty() && r.clock.now() > rec[0].time + 100ms) lamp_after_fault = lamp_after_fault || fw.uv_lamp() || fw.atomizer();
  });
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  CHECK(report.state == TaskState::failed);
  REQUIRE(report.recoveries.size() == 1);
  CHECK(report.recoveries[0].fault == "battery low: disinfection ended safely");
  CHECK(report.recoveries[0].new_plan == "PrDockCharge() -> PrDisinfection(section=A)");
  CHECK_THAT(report.reason, Catch::Contains("fault \"no contact with the dock\" of PrDockCharge: abort"));
  CHECK_FALSE(lamp_after_fault);
  r.robot->run_for(100ms);
  CHECK_FALSE(fw.uv_lamp());
  CHECK_FALSE(fw.atomizer());
}

// The board's cable pulled mid-task and plugged in again 3 s later. The process faults within two
// control periods, the board's watchdog stops the motors, the robot stands still while the link is
// down, and the recovery rules (disinfection_recovery.yaml, as the lidar profile's) wait for SYNC
// and take the section up again: the task ends in success. Before those rules were the plain
// profile's the task failed with "module board failed: link lost".
TEST_CASE("a dead board link stops the motors within two periods, and the task resumes once SYNC answers again",
          "[board][disinfection]") {
  DisinfectionRobot r;
  board::BoardFirmware& fw = r.hw->embedded().firmware();
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(20.0, [] {});
  REQUIRE(r.robot->planner().busy());
  const Time cut = r.clock.now();
  r.hw->embedded().line().host().set_connected(false);  // the cable pulled: no request reaches the board
  r.run_task(1.0, [] {});
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(r.robot->planner().busy());  // not ended: recovering
  REQUIRE(report.recoveries.size() == 1);
  CHECK(report.recoveries[0].fault == "module board failed: link lost");
  CHECK(report.recoveries[0].new_plan == "PrBoardReconnect() -> PrDisinfection(section=A)");
  // The request already on the line at the cut is answered; the first lost one is sent at
  // cut + 10 ms, missed at the link's cycle 10 ms later, and the process faults 10 ms after that.
  CHECK(report.recoveries[0].time - cut <= 30ms);
  // The board's watchdog (200 ms without a valid request) has stopped the motors: the robot stands.
  CHECK(fw.counters().watchdog_trips == 1);
  CHECK(fw.link_lost());
  CHECK(fw.required_m_s(0) == 0.0);
  CHECK(fw.required_m_s(1) == 0.0);
  const Pose2D stopped = r.hw->simulator().pose();
  r.run_task(2.0, [] {});
  CHECK(std::hypot(r.hw->simulator().pose().x_m - stopped.x_m, r.hw->simulator().pose().y_m - stopped.y_m) < 0.001);
  // Plugged in again: SYNC answered, PrBoardReconnect succeeds, the section is taken up again.
  r.hw->embedded().line().host().set_connected(true);
  r.run_task(1500.0, [] {});
  INFO(report.str());
  CHECK(report.state == TaskState::succeeded);
  CHECK(report.recoveries.size() == 1);
  int reconnects = 0, disinfections = 0;
  for (const ProcessRecord& p : report.processes) {
    reconnects += p.step.process == "PrBoardReconnect" && p.success ? 1 : 0;
    disinfections += p.step.process == "PrDisinfection" ? 1 : 0;
  }
  CHECK(reconnects == 1);
  CHECK(disinfections == 2);  // the failed run and the one taken up again
  CHECK(r.hw->board().link().synchronised());
  CHECK(r.hw->board().link().stats().resyncs >= 1);
}

// --- the board's actuators as command channels -------------------------------------------------------

namespace {

// The disinfection profile without its nets' driver and BoardMonitor (nothing else could switch an
// actuator), plus BhLcdText, so that the behaviors alone drive the board through their channels.
struct ChannelRobot {
  std::shared_ptr<const sim::World> world =
      std::make_shared<const sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml"));
  SimClock clock;
  RobotPlugins plugins = builtin_plugins(world);
  std::unique_ptr<Robot> robot;
  sim::SimBoardHardware* hw = nullptr;

  ChannelRobot() {
    RobotProfile profile = load_robot_profile(kConfigs / "robots/disinfection.yaml");
    // BoardMonitor out; BatteryMonitor stays: PrDockCharge's guards read its facts.
    std::erase_if(profile.modules, [](const ModuleEntry& m) { return m.type == "BoardMonitor"; });
    // ...and with it the process that waits for its fact board_linked after a lost link, and the
    // rules that insert it (no task runs here).
    std::erase_if(profile.processes, [](const ProcessEntry& p) { return p.name == "PrBoardReconnect"; });
    profile.recovery.clear();
    ModuleEntry lcd;
    lcd.kind = ModuleKind::behavior;
    lcd.name = lcd.type = "BhLcdText";
    profile.behaviors.push_back(lcd);
    robot = Robot::assemble(profile, plugins, clock);
    hw = &dynamic_cast<sim::SimBoardHardware&>(*robot->hardware());
    robot->run_for(100ms);  // SYNC
  }
  void activate(const std::string& type, ParameterValues params = {}) {
    robot->behavior_loop().activate(plugins.behaviors.create(type), params, type);
  }
};

}  // namespace

TEST_CASE("The board's lamp, atomizer, voice and LCD are command channels the behaviors write and the board applies",
          "[board][channels]") {
  ChannelRobot r;
  const board::BoardFirmware& fw = r.hw->embedded().firmware();
  CommandChannels& channels = r.hw->command_channels();
  for (const char* name : {"uv_lamp", "atomizer", "atomizer_fan", "voice", "lcd"}) CHECK(channels.find(name).has_value());
  REQUIRE_FALSE(fw.uv_lamp());

  r.activate("BhUvLamp");
  r.activate("BhAtomize", {{"fan", Value{false}}});
  r.activate("BhVoicePrompt", {{"track", Value{5.0}}});
  r.activate("BhLcdText", {{"text", Value{std::string("UV ON - KEEP OUT")}}});
  r.robot->run_for(100ms);
  CHECK(fw.uv_lamp());
  CHECK(fw.atomizer());
  CHECK_FALSE(fw.fan());
  CHECK(fw.last_voice_track() == 5);
  CHECK(fw.lcd_line(0) == "UV ON - KEEP OUT");
  const CBehaviorCoordinator& co = r.robot->behavior_loop().coordinator();
  CHECK(co.channel_output(*co.find_channel("uv_lamp")).writer == "BhUvLamp");
  CHECK(co.channel_output(*co.find_channel("voice")).value.number == 0.0);  // played once: back to its safe value

  // Withdrawn: every channel falls to its safe value and the board switches off.
  for (const char* b : {"BhUvLamp", "BhAtomize", "BhLcdText"}) r.robot->behavior_loop().deactivate(std::string_view(b));
  r.robot->run_for(100ms);
  CHECK_FALSE(fw.uv_lamp());
  CHECK_FALSE(fw.atomizer());
  CHECK(fw.lcd_line(0).empty());
}

TEST_CASE("A behavior writing a channel the hardware does not export is refused at assembly, located", "[board][channels]") {
  const auto world = std::make_shared<const sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml"));
  SimClock clock;
  RobotPlugins plugins = builtin_plugins(world);
  RobotProfile profile = load_robot_profile(kConfigs / "robots/disinfection.yaml");
  profile.modules.clear();
  profile.hardware->type = "sim";
  profile.hardware->parameters.clear();
  try {
    (void)Robot::assemble(profile, plugins, clock);
    FAIL("assembled");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::Contains("disinfection.yaml:"));
    CHECK_THAT(what, Catch::Contains(tripodal::test::located_line(kConfigs / "robots/disinfection.yaml", "  - BhUvLamp")));
    CHECK_THAT(what,
               Catch::Contains("behavior 'BhUvLamp' writes the command channel 'uv_lamp' (digital), which hardware 'sim' does "
                               "not export; it exports none (rule R6)"));
    CHECK_THAT(what, Catch::Contains("behavior 'BhAtomize' writes the command channel 'atomizer' (analog)"));
    CHECK_THAT(what, Catch::Contains("behavior 'BhVoicePrompt' writes the command channel 'voice' (track)"));
  }
}
