// The disinfection robot end to end on the simulator: configs/robots/disinfection.yaml on the
// simulated board (hardware type "board", every exchange over the in-process line byte for byte),
// the task "disinfect the room ..." through PrAutoMove and PrDisinfection.
#include <catch2/catch.hpp>

#include <filesystem>
#include <memory>
#include <string>

#include "tripodal/builtin/register_all.hpp"
#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/board/board_monitor.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_board.hpp"

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
    robot = Robot::assemble(load_robot_profile(kConfigs / "robots/disinfection.yaml"), plugins, clock);
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

TEST_CASE("PrDisinfection: a low battery ends the task safely, lamp and fog off", "[board][disinfection]") {
  DisinfectionRobot r;
  board::BoardFirmware& fw = r.hw->embedded().firmware();
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(20.0, [] {});
  REQUIRE(fw.uv_lamp());
  fw.set_state_of_charge(0.10);  // sampled at the board's next 3 s, polled by the host every 3 s
  r.run_task(10.0, [] {});
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  CHECK(report.state == TaskState::failed);
  CHECK_THAT(report.reason, Catch::Contains("battery low: disinfection ended safely"));
  r.robot->run_for(100ms);
  CHECK_FALSE(fw.uv_lamp());
  CHECK_FALSE(fw.atomizer());
}

TEST_CASE("the disinfection task faults within two periods of a dead board link, and the board stops the motors", "[board][disinfection]") {
  DisinfectionRobot r;
  board::BoardFirmware& fw = r.hw->embedded().firmware();
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(20.0, [] {});
  REQUIRE(r.robot->planner().busy());
  const Time cut = r.clock.now();
  r.hw->embedded().line().host().set_connected(false);  // the cable pulled: no request reaches the board
  Time failed_at{};
  r.run_task(1.0, [&] {
    if (!r.robot->planner().busy() && failed_at == Time{}) failed_at = r.clock.now();
  });
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(report.state == TaskState::failed);
  CHECK_THAT(report.reason, Catch::Contains("module board failed: link lost at"));
  // The request already on the line at the cut is answered; the first lost one is sent at
  // cut + 10 ms, missed at the link's cycle 10 ms later, and the process faults 10 ms after that.
  CHECK(failed_at - cut <= 30ms);
  r.robot->run_for(300ms);  // the board's watchdog: 200 ms without a valid request
  CHECK(fw.counters().watchdog_trips == 1);
  CHECK(fw.link_lost());
  CHECK(fw.required_m_s(0) == 0.0);
  CHECK(fw.required_m_s(1) == 0.0);
}
