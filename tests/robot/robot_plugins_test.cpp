// What an application registers reaches the robot: its own controller type, named in the reactive
// configuration a profile's controller entry points to, is checked and built through the
// application's plugin set (RobotPlugins::controllers); the built-in areas do not know it.
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "tripodal/builtin/register_all.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;

namespace {

// An application's controller type: one wheel (a winch) at gain times the forward speed.
class WinchController final : public CController {
 public:
  WinchController(const ControllerConfig& config, HardwareInterface& hardware)
      : CController(config.period), hardware_(hardware), gain_(config.parameters.number("gain")) {}

  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = controller_manifest(
        "winch", "one wheel at gain times the forward speed",
        {parameter::number("gain", 1.0, "rad/m", "wheel speed per forward speed", 0.0, 100.0)});
    return m;
  }
  [[nodiscard]] double gain() const noexcept { return gain_; }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  BaseCapabilities do_capabilities() const noexcept override { return {}; }
  std::span<const double> do_wheel_commands() const noexcept override { return {&wheel_, 1}; }
  ControlStatus on_update(Time, Duration, const Twist2D& command, bool, Twist2D& limited, OdometryReading&) noexcept override {
    wheel_ = gain_ * command.vx_m_s;
    limited = command;
    return hardware_.write_wheel_velocities({&wheel_, 1}) ? ControlStatus::ok : ControlStatus::hardware_fault;
  }
  [[nodiscard]] Duration command_timeout() const noexcept override { return Duration{0}; }

 private:
  HardwareInterface& hardware_;
  double gain_;
  double wheel_ = 0.0;
};

// The application's hardware for it: one ideal wheel.
class WinchHardware final : public CHardware {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = hardware_manifest("winch_board", "one ideal wheel", {}, {});
    return m;
  }
  explicit WinchHardware(const HardwareConfig& c) : wheel_(1, c.base != nullptr ? c.base->period : std::chrono::milliseconds(10)) {}

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  HardwareInterface& do_wheels() noexcept override { return wheel_; }

 private:
  IdealWheelHardware wheel_;
};

struct WinchProfile {
  std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tripodal_robot_plugins_" + std::to_string(::getpid()));
  WinchProfile() {
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "reactive.yaml") << "controllers:\n  - name: base\n    type: winch\n    gain: 2.5\n    period_s: 0.02\n";
    std::ofstream(dir / "robot.yaml") << "robot: {name: winch}\n"
                                         "hardware: {type: winch_board}\n"
                                         "controllers:\n"
                                         "  - {name: base, type: winch, parameters: {config: reactive.yaml}}\n"
                                         "loops:\n"
                                         "  - {name: motion, period_s: 0.02, controller: base}\n";
  }
  ~WinchProfile() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  WinchProfile(const WinchProfile&) = delete;
  WinchProfile& operator=(const WinchProfile&) = delete;
};

}  // namespace

TEST_CASE("An application's own controller type, registered in its plugins, drives the robot's loop", "[robot][plugins]") {
  const WinchProfile files;
  RobotPlugins plugins = builtin_plugins();
  plugins.controllers.add<WinchController>();
  plugins.hardware.add(WinchHardware::static_manifest(), [](const HardwareConfig& c) { return std::make_unique<WinchHardware>(c); });
  // Only the application's plugin set knows the type: the built-in areas do not.
  REQUIRE_FALSE(builtin_plugins().controllers.contains("winch"));

  SimClock clock;
  const RobotProfile profile = load_robot_profile(files.dir / "robot.yaml");
  const auto robot = Robot::assemble(profile, plugins, clock);
  const CController* controller = robot->behavior_loop().controller();
  REQUIRE(controller != nullptr);
  CHECK(controller->type_name() == "winch");
  CHECK(dynamic_cast<const WinchController&>(*controller).gain() == 2.5);
  CHECK(robot->behavior_loop().period() == std::chrono::milliseconds(20));

  // The base's configuration, as a simulator in another process reads it, through the same registry.
  const std::optional<ControllerConfig> base = base_controller_config(profile, plugins.controllers);
  REQUIRE(base.has_value());
  CHECK(base->parameters.number("gain") == 2.5);
}

TEST_CASE("A controller type the application did not register is refused at the reactive file, with the known ones", "[robot][plugins][errors]") {
  const WinchProfile files;
  RobotPlugins plugins = builtin_plugins();
  plugins.hardware.add(WinchHardware::static_manifest(), [](const HardwareConfig& c) { return std::make_unique<WinchHardware>(c); });
  SimClock clock;
  const RobotProfile profile = load_robot_profile(files.dir / "robot.yaml");
  REQUIRE_THROWS_WITH(Robot::assemble(profile, plugins, clock),
                      Catch::Contains("robot.yaml:4:5: error: unknown controller type 'winch'; known: differential, mecanum, omni") &&
                          Catch::Contains("reactive.yaml:3:11: error: controller 'base': unknown controller type 'winch'"));
}

TEST_CASE("A type declared in the profile but not registered is refused at assembly, at its entry, and check_robot only warns",
          "[robot][plugins][errors]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tripodal_declared_types_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "robot.yaml") << "robot: {name: designed}\n"
                                       "hardware: {type: lidar_rig, layer: reactive, outputs: [laser_scan]}\n"
                                       "loops:\n"
                                       "  - {name: motion, period_s: 0.02}\n"
                                       "behaviors:\n"
                                       "  - {name: BhDance, type: BhDance, layer: reactive, inputs: [laser_scan], outputs: [behavior_command]}\n";
  const RobotProfile profile = load_robot_profile(dir / "robot.yaml");
  const RobotPlugins plugins = builtin_plugins();

  // The diagram of a design: both drawn, both noted.
  Diagnostics d;
  const RobotDescription r = check_robot(profile, plugins, d);
  CHECK_FALSE(d.has_errors());
  CHECK_THAT(d.str(), Catch::Contains("robot.yaml:2:11: warning: hardware 'hardware' cannot be started: its type 'lidar_rig' is declared here"));
  CHECK_THAT(d.str(), Catch::Contains("robot.yaml:6:5: warning: behavior 'BhDance' cannot be started: its type 'BhDance' is declared here"));
  CHECK(std::any_of(r.modules.begin(), r.modules.end(), [](const DescribedModule& m) { return m.name == "BhDance"; }));

  // Running it: refused, both at once, each at its entry (the robot once started without hardware
  // and with a behavior that failed only when a net activated it).
  SimClock clock;
  try {
    (void)Robot::assemble(profile, plugins, clock);
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    INFO(what);
    CHECK(e.diagnostics().error_count() == 2);
    CHECK_THAT(what, Catch::Contains("robot.yaml:2:11: error: hardware 'hardware' cannot be started: its type 'lidar_rig' is declared "
                                     "here (layer, inputs, outputs), which draws the diagram, but no hardware type of that name is registered"));
    CHECK_THAT(what, Catch::Contains("robot.yaml:6:5: error: behavior 'BhDance' cannot be started"));
  }
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

TEST_CASE("check_robot refuses a net binding a behavior the profile does not list, as assembly does", "[robot][plugins][errors]") {
  const RobotProfile profile =
      load_robot_profile(std::filesystem::path(TRIPODAL_SOURCE_DIR) / "tests/data/robot/net-binds-unlisted-behavior.yaml");
  const RobotPlugins plugins = builtin_plugins();
  Diagnostics d;
  (void)check_robot(profile, plugins, d);
  CHECK(d.error_count() == 1);
  CHECK_THAT(d.str(), Catch::Contains("PrAutoMove.xml:17:") && Catch::Contains("error: unknown behavior 'BhAutoMove'"));
  SimClock clock;
  REQUIRE_THROWS_WITH(Robot::assemble(profile, plugins, clock), Catch::Contains("error: unknown behavior 'BhAutoMove'"));
}

namespace {

// The robot of tests/data/robot/dock_charge.yaml, which runs the dock-and-charge net
// (configs/petri/PrDockCharge.xml), without its BatteryMonitor and with `extra` appended: the
// modules that provide the net's facts, or an external_facts list.
RobotProfile dock_profile(const std::string& extra) {
  const std::filesystem::path dir = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "tests/data/robot";
  std::ifstream in(dir / "dock_charge.yaml");
  std::string text, line;
  bool skipping = false;
  while (std::getline(in, line)) {
    if (line == "modules:")
      skipping = true;
    else if (!line.empty() && line[0] != ' ')
      skipping = false;
    if (!skipping) text += line + "\n";
  }
  return load_robot_profile_from_string(text + extra, "robot.yaml", dir);
}

// The built-in types and the simulator's hardware "sim" (no world: none is built here).
RobotPlugins dock_plugins() {
  RobotPlugins p = builtin_plugins();
  return p;
}

}  // namespace

TEST_CASE(
    "A fact a net reads that no module provides is refused by check_robot and assembly, at the guard and the "
    "profile",
    "[robot][plugins][errors][facts]") {
  const RobotPlugins plugins = dock_plugins();
  const RobotProfile profile = dock_profile("");
  Diagnostics d;
  (void)check_robot(profile, plugins, d);
  INFO(d.str());
  CHECK(d.error_count() == 2);
  CHECK_THAT(d.str(),
             Catch::Contains("PrDockCharge.xml:34:") &&
                 Catch::Contains("error: process 'PrDockCharge': the guard of transition 't3' reads fact 'charging', which no "
                                 "module of robot 'psr2_dock' provides (lists among its outputs)") &&
                 Catch::Contains("or list it under external_facts: when the application sets it"));
  CHECK_THAT(d.str(), Catch::Contains("PrDockCharge.xml:36:") && Catch::Contains("transition 't5' reads fact 'battery_percent'"));
  CHECK_THAT(d.str(), Catch::Contains("robot.yaml:35:5: note: process 'PrDockCharge' is listed here"));
  SimClock clock;
  REQUIRE_THROWS_WITH(Robot::assemble(profile, plugins, clock), Catch::Contains("reads fact 'charging', which no module"));
}

TEST_CASE(
    "A fact the profile lists under external_facts is a warning, BatteryMonitor provides charging and "
    "battery_percent",
    "[robot][plugins][facts]") {
  const RobotPlugins plugins = dock_plugins();
  SECTION("external") {
    Diagnostics d;
    (void)check_robot(dock_profile("external_facts: [charging, battery_percent]\n"), plugins, d);
    INFO(d.str());
    CHECK_FALSE(d.has_errors());
    CHECK_THAT(d.str(), Catch::Contains("PrDockCharge.xml:34:") && Catch::Contains("warning: process 'PrDockCharge'") &&
                            Catch::Contains("the profile lists it under external_facts (robot.yaml:38:17), "
                                            "so the application must set it"));
  }
  SECTION("one external, one missing") {
    Diagnostics d;
    (void)check_robot(dock_profile("external_facts: [charging]\n"), plugins, d);
    CHECK(d.error_count() == 1);
    CHECK_THAT(d.str(), Catch::Contains("reads fact 'battery_percent'"));
  }
  SECTION("a module whose type lists them among its outputs") {
    Diagnostics d;
    (void)check_robot(dock_profile("modules:\n  - {name: battery_monitor, type: BatteryMonitor}\n"), plugins, d);
    INFO(d.str());
    CHECK(d.empty());
  }
  SECTION("a near miss: did you mean") {
    Diagnostics d;
    (void)check_robot(dock_profile("modules:\n  - {name: power, type: PowerBoard, layer: sequencing, inputs: [battery], outputs: "
                                   "[chargin, battery_percent]}\n"),
                      plugins, d);
    CHECK(d.error_count() == 1);
    CHECK_THAT(d.str(),
               Catch::Contains("reads fact 'charging', which no module of robot 'psr2_dock' provides (lists among its outputs); "
                               "did you mean 'chargin'?"));
  }
}
