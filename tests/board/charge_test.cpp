// Self-charging of the disinfection robot (configs/robots/disinfection.yaml on the simulated board):
// a low battery ends PrDisinfection, the recovery rules (configs/tasks/disinfection_recovery.yaml)
// insert PrDockCharge, the robot drives to the world's dock, the board reports charging, and the
// section is taken up again where it stopped. And the dock's faults: occupied, without power.
#include <spdlog/sinks/ringbuffer_sink.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/planner/recovery.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";

// The demo workspace with the charging pad at the charger node, the robot starting in room 2111
// (configs/worlds/workspace_dock.yaml), plus `extra` lines (a dock's power, a cart on it).
sim::World dock_world(
    const std::string& dock = "{name: charger, node: charger, contact_radius_m: 0.15, heading_tolerance_deg: 180}",
    const std::string& extra = "") {
  const std::string text =
      "map: workspace_map.yaml\nregions: workspace_regions.yaml\nstart_pose: [5.0, 6.0, 1.5708]\nseed: 1\n"
      "robot:\n  radius_m: 0.25\n  laser: {preset: rplidar_a1, noise_stddev_m: 0.01}\n"
      "  odometry: {noise_ratio: 0.01}\n  gyro: {noise_stddev_rad_s: 0.002}\n  bumpers: {sectors: 4}\n"
      "  cliff:\n    positions: [[0.2, 0.0], [0.1, 0.17], [0.1, -0.17]]\n"
      "docks:\n  - " +
      dock + "\n" + extra;
  return sim::parse_world(text, kConfigs / "worlds/charge_test.yaml");
}

struct ChargingRobot {
  std::shared_ptr<const sim::World> world;
  SimClock clock;
  RobotPlugins plugins;
  std::unique_ptr<Robot> robot;
  sim::SimBoardHardware* hw = nullptr;

  // `charger_a`: the dock's charger current. The realistic 5.2 A (0.5 C, about 2 h from empty) is
  // the figure's run (docs/board-protocol.md); these tests charge at 20.8 A (2 C) to stay short.
  // `profile_file`: one of the shipped disinfection profiles; `overrides`: parameters beyond the
  // lanes without a dose plan.
  explicit ChargingRobot(sim::World w, double charger_a = 20.8, const std::string& profile_file = "robots/disinfection.yaml",
                         const std::vector<ParameterOverride>& overrides = {})
      : world(std::make_shared<const sim::World>(std::move(w))) {
    register_all(plugins, world);
    RobotProfile profile = load_robot_profile(kConfigs / profile_file);
    profile.hardware->parameters["charger_current_a"] = std::to_string(charger_a);
    RobotOptions ro;
    ro.parameters.push_back({"coverage", "dose_target_j_m2", "0"});  // the lanes without a dose plan: shorter
    ro.parameters.insert(ro.parameters.end(), overrides.begin(), overrides.end());
    robot = Robot::assemble(profile, plugins, clock, ro);
    hw = &dynamic_cast<sim::SimBoardHardware&>(*robot->hardware());
    if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(world->start_pose);
    robot->run_for(100ms);
  }
  board::BoardFirmware& firmware() { return hw->embedded().firmware(); }
  template <class Fn>
  void run_task(double max_s, const Fn& each) {
    const Time end = clock.now() + from_seconds(max_s);
    while (robot->planner().busy() && clock.now() < end) {
      robot->run_for(10ms);
      each();
    }
  }
};

const ProcessRecord* nth_run(const TaskReport& r, std::string_view process, int n) {
  for (const ProcessRecord& p : r.processes) {
    if (p.step.process == process && n-- == 0) return &p;
  }
  return nullptr;
}

}  // namespace

TEST_CASE("a low battery: the disinfection robot docks, charges and resumes the section where it stopped", "[board][charge]") {
  ChargingRobot r(dock_world());
  board::BoardFirmware& fw = r.firmware();
  fw.set_state_of_charge(0.18);  // 3 % above the 15 % mark: low about a third into room 2111
  auto* coverage = r.robot->module<navi::CCoveragePlanner>();
  REQUIRE(coverage != nullptr);
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);

  bool board_said_charging = false;
  bool lamp_on_at_dock = false;
  std::size_t cleaned_at_fault = 0, cleaned_at_resume = 0;
  double min_soc = 1.0, max_soc = 0.0;
  r.run_task(6000.0, [&] {
    const TaskReport& rep = r.robot->planner().report();
    const bool charging_stage = !rep.processes.empty() && rep.processes.back().step.process == "PrDockCharge";
    if (charging_stage && cleaned_at_fault == 0) cleaned_at_fault = coverage->cleaned().count();
    if (charging_stage && r.clock.now() > rep.recoveries.at(0).time + 100ms) {  // the lamp's off crosses the line
      board_said_charging = board_said_charging || r.hw->board().link().battery().charging;
      lamp_on_at_dock = lamp_on_at_dock || fw.uv_lamp() || fw.atomizer();
    }
    if (rep.processes.size() == 4 && cleaned_at_resume == 0) cleaned_at_resume = coverage->cleaned().count();
    min_soc = std::min(min_soc, fw.state_of_charge());
    max_soc = std::max(max_soc, fw.state_of_charge());
  });
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(report.state == TaskState::succeeded);
  // Once to the dock: the recovery names the low battery, the remaining plan charges and retries.
  REQUIRE(report.recoveries.size() == 1);
  CHECK(report.recoveries[0].fault == "battery low: disinfection ended safely");
  CHECK(report.recoveries[0].new_plan == "PrDockCharge() -> PrDisinfection(section=A)");
  const ProcessRecord* first = nth_run(report, "PrDisinfection", 0);
  const ProcessRecord* charge = nth_run(report, "PrDockCharge", 0);
  const ProcessRecord* resumed = nth_run(report, "PrDisinfection", 1);
  REQUIRE(first != nullptr);
  REQUIRE(charge != nullptr);
  REQUIRE(resumed != nullptr);
  CHECK(charge->success);
  CHECK(resumed->success);
  CHECK(board_said_charging);          // the board's battery reading (BATTERY response) said so
  CHECK_FALSE(lamp_on_at_dock);        // lamp and fog off from the fault to the resume
  CHECK(min_soc < 0.155);              // the board reports whole percent: 15 % from 15.5 % down
  CHECK(min_soc > 0.12);               // ended at the mark, not driven flat
  CHECK(fw.state_of_charge() > 0.85);  // charged to 95 %, then the rest of the room
  // Charged at 2 C from 15 % to 95 % (8.3 Ah at 20.8 A less the 0.4 A of the boards): 1470 s
  // plus the drive to the dock.
  const double charge_s = to_seconds(*charge->finished - charge->started);
  WARN("low battery in room 2111: first run " << to_seconds(*first->finished - first->started) << " s, to the dock and charged "
                                              << charge_s << " s, resumed " << to_seconds(*resumed->finished - resumed->started)
                                              << " s; cleaned cells " << cleaned_at_fault << " at the fault, "
                                              << coverage->cleaned().count() << " at the end");
  CHECK(charge_s > 1400.0);
  CHECK(charge_s < 1700.0);
  // Resumed, not redone: the cells cleaned before the fault are kept, and the resumed run is
  // shorter than the whole room would take at the first run's pace.
  CHECK(cleaned_at_fault > 0);
  CHECK(cleaned_at_resume >= cleaned_at_fault);
  const double first_s = to_seconds(*first->finished - first->started);
  const double resumed_s = to_seconds(*resumed->finished - resumed->started);
  const double share_before = static_cast<double>(cleaned_at_fault) / static_cast<double>(coverage->cleaned().count());
  CHECK(resumed_s < first_s / share_before * (1.0 - share_before) + 90.0);  // 90 s: back from the dock to the path
  // The section's coverage as an uninterrupted run gets it (tests/board/disinfection_test.cpp).
  CHECK(coverage->progress().at("A").finished);
  r.robot->run_for(100ms);
  CHECK_FALSE(fw.uv_lamp());
}

TEST_CASE("an occupied dock: the task ends safely with the reason, lamp and fog off", "[board][charge]") {
  // A cart parked on the charging pad: the way to the dock's node is blocked.
  ChargingRobot r(dock_world({"{name: charger, node: charger, contact_radius_m: 0.15, heading_tolerance_deg: 180}"},
                             "obstacles:\n  - {name: cart, rectangle: [0.3, 0.3, 1.3, 1.3]}\n"));
  board::BoardFirmware& fw = r.firmware();
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(20.0, [] {});
  fw.set_state_of_charge(0.10);
  r.run_task(600.0, [] {});
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(report.state == TaskState::failed);
  REQUIRE(report.recoveries.size() == 1);
  CHECK(report.recoveries[0].fault == "battery low: disinfection ended safely");
  CHECK_THAT(report.reason, Catch::Contains("fault \"path blocked\" of PrDockCharge: abort"));
  r.robot->run_for(100ms);
  CHECK_FALSE(fw.uv_lamp());
  CHECK_FALSE(fw.atomizer());
  CHECK(fw.required_m_s(0) == 0.0);
  CHECK(fw.required_m_s(1) == 0.0);
}

TEST_CASE("a charger that does not charge: the task ends with the reason, the robot on the dock", "[board][charge]") {
  ChargingRobot r(
      dock_world("{name: charger, node: charger, contact_radius_m: 0.15, heading_tolerance_deg: 180, powered: false}"));
  board::BoardFirmware& fw = r.firmware();
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(20.0, [] {});
  fw.set_state_of_charge(0.10);
  r.run_task(600.0, [] {});
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(report.state == TaskState::failed);
  CHECK_THAT(report.reason, Catch::Contains("fault \"no contact with the dock\" of PrDockCharge: abort"));
  CHECK(r.hw->simulator().dock() == 0);  // on the pad, its contacts touching
  CHECK_FALSE(r.hw->board().link().battery().charging);
  CHECK(fw.state_of_charge() <= 0.10);
}

TEST_CASE("a dock's power is read from the world file, and a bad value is located", "[board][charge][config]") {
  CHECK(dock_world().docks.at(0).powered);
  CHECK_FALSE(dock_world("{name: charger, node: charger, powered: false}").docks.at(0).powered);
  CHECK_THROWS_WITH(dock_world("{name: charger, node: charger, powered: maybe}"),
                    Catch::Contains("charge_test.yaml:") && Catch::Contains("powered"));
}

// --- the panel: buttons through the net, LCD and voice ----------------------------------------------

namespace {

void press(ChargingRobot& r, std::uint8_t button) {
  r.firmware().set_buttons(button);
  r.robot->run_for(100ms);  // held over several DRIVE responses: BoardMonitor posts the edge once
  r.firmware().set_buttons(0);
  r.robot->run_for(100ms);
}

std::string lcd(ChargingRobot& r) {
  return std::string(r.firmware().lcd_line(0));
}

}  // namespace

TEST_CASE("the pause button stops base, lamp and fog, start takes the section up again, the LCD says so", "[board][panel]") {
  ChargingRobot r(dock_world());
  board::BoardFirmware& fw = r.firmware();
  auto* coverage = r.robot->module<navi::CCoveragePlanner>();
  REQUIRE(coverage != nullptr);
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(30.0, [] {});
  REQUIRE(fw.uv_lamp());
  // State, battery (the board's whole percent) and tank (the liquid level module's) on line 0.
  CHECK_THAT(lcd(r), Catch::Matches("DISINFECT B (99|100)% T [0-9]+%"));

  press(r, board::kButtonPause);
  r.robot->run_for(1s);
  CHECK(r.robot->planner().busy());
  CHECK_FALSE(fw.uv_lamp());
  CHECK_FALSE(fw.atomizer());
  CHECK(fw.required_m_s(0) == 0.0);
  CHECK(fw.required_m_s(1) == 0.0);
  CHECK_THAT(lcd(r), Catch::Matches("PAUSED B [0-9]+% T [0-9]+%"));
  const std::size_t cleaned = coverage->cleaned().count();
  const Pose2D at = r.hw->simulator().pose();
  r.robot->run_for(10s);
  CHECK(coverage->cleaned().count() == cleaned);
  CHECK(std::hypot(r.hw->simulator().pose().x_m - at.x_m, r.hw->simulator().pose().y_m - at.y_m) < 0.01);

  press(r, board::kButtonStart);
  r.robot->run_for(10s);
  CHECK(fw.uv_lamp());
  CHECK_THAT(lcd(r), Catch::StartsWith("DISINFECT B "));
  CHECK(coverage->cleaned().count() > cleaned);  // going on from where it stopped
  r.robot->planner().cancel("checked");
}

TEST_CASE("voice: start when the disinfection starts, stop when the section is done, battery low before the charge",
          "[board][panel]") {
  ChargingRobot r(dock_world());
  board::BoardFirmware& fw = r.firmware();
  fw.set_state_of_charge(0.18);  // low about a third into the room: the run of the first test
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  std::vector<int> tracks;  // as the board played them
  std::uint64_t prompts = fw.counters().voice_prompts;
  r.run_task(6000.0, [&] {
    if (fw.counters().voice_prompts != prompts) {
      prompts = fw.counters().voice_prompts;
      tracks.push_back(fw.last_voice_track());
    }
  });
  r.robot->run_for(100ms);  // the last track crosses the line after the process has ended
  if (fw.counters().voice_prompts != prompts) tracks.push_back(fw.last_voice_track());
  INFO(r.robot->planner().report().str());
  REQUIRE(r.robot->planner().report().state == TaskState::succeeded);
  // start, battery low (the fault), start again (the retry after the charge), stop (section done)
  CHECK(tracks == std::vector<int>{static_cast<int>(board::kTrackStart), static_cast<int>(board::kTrackBatteryLow),
                                   static_cast<int>(board::kTrackStart), static_cast<int>(board::kTrackStop)});
}

TEST_CASE("the home button sends the robot to its dock and ends the task there", "[board][panel]") {
  ChargingRobot r(dock_world());
  board::BoardFirmware& fw = r.firmware();
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  r.run_task(30.0, [] {});
  press(r, board::kButtonHome);
  r.run_task(600.0, [] {});
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(report.state == TaskState::failed);
  REQUIRE(report.recoveries.size() == 1);
  CHECK(report.recoveries[0].fault == "home button: sent to the dock");
  CHECK(report.recoveries[0].new_plan == "PrDockCharge()");
  CHECK(report.reason ==
        "fault \"home button: sent to the dock\" of PrDisinfection: insert PrDockCharge, then end the task (1/1)");
  const ProcessRecord* charge = nth_run(report, "PrDockCharge", 0);
  REQUIRE(charge != nullptr);
  CHECK(charge->success);
  CHECK(r.hw->simulator().dock() == 0);  // on the pad
  CHECK_FALSE(fw.uv_lamp());
  CHECK(nth_run(report, "PrDisinfection", 1) == nullptr);  // not taken up again
}

// --- the start button at rest: the robot waiting at its dock starts its round ------------------------

namespace {

// What spdlog's default logger says while it lives (the robot's log lines).
class LogCapture {
 public:
  LogCapture() : sink_(std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(64)) {
    spdlog::default_logger()->sinks().push_back(sink_);
  }
  ~LogCapture() { spdlog::default_logger()->sinks().pop_back(); }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;
  [[nodiscard]] std::string text() const {
    std::string all;
    for (const std::string& l : sink_->last_formatted()) all += l;
    return all;
  }

 private:
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink_;
};

bool refused_a_command(const LifecycleRecorder& life) {
  for (const LifecycleEntry& e : life.entries()) {
    if (e.text.find("command refused") != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("the start button with no task running starts the profile's start task, once", "[board][panel]") {
  LifecycleRecorder life;  // outlives the robot, whose planner holds it
  ChargingRobot r(dock_world());
  r.robot->planner().add_observer(life);
  board::BoardFirmware& fw = r.firmware();
  r.robot->run_for(2s);
  REQUIRE_FALSE(r.robot->planner().busy());  // waiting: nothing runs until the operator presses start

  press(r, board::kButtonStart);
  REQUIRE(r.robot->planner().busy());
  CHECK(r.robot->planner().report().command == "disinfect the room 2111");  // BoardMonitor's start_task
  REQUIRE_FALSE(life.entries().empty());
  CHECK_THAT(life.entries().front().text, Catch::StartsWith("task disinfect started (\"disinfect the room 2111\")"));
  r.run_task(30.0, [] {});
  CHECK(fw.uv_lamp());  // the round is under way: section A disinfected

  // Pressed again while it runs: the net's button (PrDisinfection resumes on it), no second task.
  press(r, board::kButtonStart);
  r.robot->run_for(1s);
  CHECK(r.robot->planner().busy());
  CHECK_FALSE(refused_a_command(life));
  CHECK(fw.uv_lamp());
  r.robot->planner().cancel("checked");
  r.robot->planner().remove_observer(life);
}

TEST_CASE("the start button with no task running and no start task: nothing starts, the log says why", "[board][panel]") {
  ChargingRobot r(dock_world(), 20.8, "robots/disinfection.yaml", {{"board", "start_task", ""}});
  const LogCapture log;
  press(r, board::kButtonStart);
  r.robot->run_for(1s);
  CHECK_FALSE(r.robot->planner().busy());
  CHECK(r.robot->planner().state() == TaskState::idle);
  CHECK_THAT(log.text(), Catch::Contains("disinfection.yaml:") &&
                             Catch::Contains("start button pressed, no task running and none to start: BoardMonitor's "
                                             "parameter start_task names none"));
}

// --- every shipped disinfection profile charges ------------------------------------------------------

TEST_CASE("every shipped disinfection profile docks and charges on a low battery: rules, process, facts",
          "[board][charge][config]") {
  std::vector<std::filesystem::path> profiles;
  for (const auto& e : std::filesystem::directory_iterator(kConfigs / "robots")) {
    if (e.path().filename().string().starts_with("disinfection")) profiles.push_back(e.path());
  }
  REQUIRE(profiles.size() >= 2);  // disinfection.yaml, disinfection_lidar.yaml
  auto world = std::make_shared<const sim::World>(dock_world());
  RobotPlugins plugins;
  register_all(plugins, world);
  for (const std::filesystem::path& file : profiles) {
    INFO(file.filename().string());
    const RobotProfile profile = load_robot_profile(file);
    Diagnostics d;
    (void)check_robot(profile, plugins, d);
    CHECK(d.error_count() == 0);
    CHECK(std::any_of(profile.processes.begin(), profile.processes.end(),
                      [](const ProcessEntry& p) { return p.name == "PrDockCharge"; }));
    CHECK(std::any_of(profile.modules.begin(), profile.modules.end(),
                      [](const ModuleEntry& m) { return m.type == "BatteryMonitor"; }));
    REQUIRE_FALSE(profile.recovery.empty());
    const RecoveryPolicy rules = RecoveryPolicy::load(profile.recovery);
    const ProcessStep disinfection{"PrDisinfection", {{"section", "A", {}}}};
    const RecoveryDecision low = rules.decide(disinfection, "battery low: disinfection ended safely", 0);
    CHECK(low.action == RecoveryAction::retry);
    REQUIRE(low.insert.size() == 1);
    CHECK(low.insert[0].process == "PrDockCharge");
    CHECK(rules.decide(disinfection, "home button: sent to the dock", 0).action == RecoveryAction::end);
    CHECK(rules.decide({"PrDockCharge", {}}, "charging stopped", 0).action == RecoveryAction::abort);
  }
}

// Issue 35's closing note: disinfection.yaml had no rule for the board's link lost (its task failed)
// and disinfection_lidar.yaml no safety reflex (its robot drove down a stairwell). Every shipped
// disinfection profile now has both: the link lost waits for SYNC and retries the step, and the
// cliff, bump and ultrasonic guards are safety inputs.
TEST_CASE("every shipped disinfection profile recovers a lost board link and has the safety reflexes",
          "[board][safety][config]") {
  std::vector<std::filesystem::path> profiles;
  for (const auto& e : std::filesystem::directory_iterator(kConfigs / "robots")) {
    if (e.path().filename().string().starts_with("disinfection")) profiles.push_back(e.path());
  }
  REQUIRE(profiles.size() >= 2);
  for (const std::filesystem::path& file : profiles) {
    INFO(file.filename().string());
    const RobotProfile profile = load_robot_profile(file);
    CHECK(std::any_of(profile.processes.begin(), profile.processes.end(),
                      [](const ProcessEntry& p) { return p.name == "PrBoardReconnect"; }));
    REQUIRE_FALSE(profile.recovery.empty());
    const RecoveryPolicy rules = RecoveryPolicy::load(profile.recovery);
    for (const ProcessStep& step : {ProcessStep{"PrDisinfection", {{"section", "A", {}}}}, ProcessStep{"PrAutoMove", {}},
                                    ProcessStep{"PrDockCharge", {}}}) {
      INFO(step.process);
      const RecoveryDecision lost = rules.decide(step, "module board failed: link lost", 0);
      CHECK(lost.action == RecoveryAction::retry);
      REQUIRE(lost.insert.size() == 1);
      CHECK(lost.insert[0].process == "PrBoardReconnect");
    }
    for (const char* guard : {"BhCliffGuard", "BhBumperGuard", "BhSonarGuard"}) {
      INFO(guard);
      CHECK(std::any_of(profile.behaviors.begin(), profile.behaviors.end(),
                        [&](const ModuleEntry& b) { return b.type == guard && b.safety; }));
    }
  }
}

TEST_CASE("the lidar profile: a low battery docks, charges and resumes the section where it stopped", "[board][charge]") {
  // The scan-matching localizer starts where the world puts the robot (room 2111), not at the
  // profile's charger pose.
  ChargingRobot r(
      dock_world(), 20.8, "robots/disinfection_lidar.yaml",
      {{"localizer", "initial_x_m", "5.0"}, {"localizer", "initial_y_m", "6.0"}, {"localizer", "initial_theta_rad", "1.5708"}});
  board::BoardFirmware& fw = r.firmware();
  fw.set_state_of_charge(0.18);
  REQUIRE(r.robot->command("disinfect the room 2111").accepted);
  bool board_said_charging = false;
  r.run_task(6000.0, [&] { board_said_charging = board_said_charging || r.hw->board().link().battery().charging; });
  const TaskReport& report = r.robot->planner().report();
  INFO(report.str());
  REQUIRE(report.state == TaskState::succeeded);
  REQUIRE(report.recoveries.size() == 1);
  CHECK(report.recoveries[0].fault == "battery low: disinfection ended safely");
  CHECK(report.recoveries[0].new_plan == "PrDockCharge() -> PrDisinfection(section=A)");
  const ProcessRecord* charge = nth_run(report, "PrDockCharge", 0);
  const ProcessRecord* resumed = nth_run(report, "PrDisinfection", 1);
  REQUIRE(charge != nullptr);
  REQUIRE(resumed != nullptr);
  CHECK(charge->success);
  CHECK(resumed->success);
  CHECK(board_said_charging);
  CHECK(fw.state_of_charge() > 0.85);
  CHECK(r.robot->module<navi::CCoveragePlanner>()->progress().at("A").finished);
}
