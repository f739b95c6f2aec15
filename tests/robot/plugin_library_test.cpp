// Shared-library plugins (robot/plugin_library.hpp): a plugin's types reach the application's
// plugin set and a robot; a plugin of another ABI version, one that registers a name twice or a
// name the set has, one that throws, and files that are not plugins are refused with a message
// naming the file and the reason, the set left as it was.
#include "tripodal/robot/plugin_library.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/robot/robot.hpp"

using namespace tripodal;

namespace {

// The names of every family, to show that a refused plugin changed nothing.
std::vector<std::string> all_names(const RobotPlugins& p) {
  std::vector<std::string> out;
  for (const auto& names : {p.behaviors.names(), p.controllers.names(), p.modules.names(), p.resources.names(),
                            p.hardware.names(), p.processes.names()}) {
    out.insert(out.end(), names.begin(), names.end());
  }
  return out;
}

// Loads `library` into a built-in set and requires it refused with `message`, the set unchanged.
void require_refused(const std::string& library, const std::string& message) {
  RobotPlugins plugins = builtin_plugins();
  const std::vector<std::string> before = all_names(plugins);
  REQUIRE_THROWS_WITH(load_plugin_library(library, plugins, SourceLocation{"--plugin", 0, 0}),
                      Catch::Contains("--plugin: error: plugin '" + library + "' " + message));
  CHECK(all_names(plugins) == before);
}

}  // namespace

TEST_CASE("A plugin's types join the application's plugin set and work there", "[robot][plugins]") {
  RobotPlugins plugins = builtin_plugins();
  const PluginLibraryInfo info = load_plugin_library(TRIPODAL_TEST_PLUGIN_GOOD, plugins);
  CHECK(info.types == std::vector<std::string>{"behavior type 'BhPluginWave'", "controller type 'plugin_differential'"});
  REQUIRE(plugins.behaviors.contains("BhPluginWave"));
  CHECK(plugins.behaviors.contains("BhStop"));  // the built-in ones stay
  const std::unique_ptr<CBehavior> b = plugins.behaviors.create("BhPluginWave");
  CHECK(b->manifest().name == "BhPluginWave");
  CHECK(b->manifest().parameters.at(0).name == "yaw_rate_rad_s");

  ControllerConfig c;
  c.type = "plugin_differential";
  c.differential = {0.4, 0.05};
  c.period = std::chrono::milliseconds(10);
  IdealWheelHardware two(2, c.period);
  CHECK(plugins.controllers.create(c, two)->manifest().name ==
        "differential");  // the plugin renamed the type, not the manifest it copied
}

TEST_CASE("A profile's plugins: list is loaded relative to the profile and reaches the robot", "[robot][plugins]") {
  const RobotProfile profile = load_robot_profile(TRIPODAL_TEST_PLUGIN_PROFILE);
  REQUIRE(profile.plugins.size() == 1);
  CHECK(profile.plugins[0].path == std::filesystem::path(TRIPODAL_TEST_PLUGIN_GOOD));
  CHECK(profile.plugins[0].where.line == 3);
  RobotPlugins plugins = builtin_plugins();
  const auto loaded = load_profile_plugins(profile, plugins);
  REQUIRE(loaded.size() == 1);
  Diagnostics d;
  (void)check_robot(profile, plugins, d);
  CHECK_FALSE(d.has_errors());
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  CHECK(robot != nullptr);
}

TEST_CASE("A profile naming a plugin that is not there is refused at the entry", "[robot][plugins][errors]") {
  REQUIRE_THROWS_WITH(load_robot_profile_from_string("robot: {name: r}\nplugins: [nowhere.so]\n", "r.yaml", "/tmp"),
                      Catch::Contains("r.yaml:2:11: error: plugin library 'nowhere.so' not found (looked for /tmp/nowhere.so)"));
}

TEST_CASE("Plugins that must not load are refused, each with its reason, the set unchanged", "[robot][plugins][errors]") {
  SECTION("built against another plugin ABI version") {
    require_refused(
        TRIPODAL_TEST_PLUGIN_ABI_MISMATCH,
        "was built against tripodal plugin ABI version 999, this program has version " + std::to_string(kPluginAbiVersion));
  }
  SECTION("registers one name twice") {
    require_refused(TRIPODAL_TEST_PLUGIN_DUPLICATE,
                    "failed to register its types: behavior type 'BhTwice' is already registered");
  }
  SECTION("registers a built-in name: refused whole, its other type not kept") {
    require_refused(TRIPODAL_TEST_PLUGIN_BUILTIN_NAME,
                    "registers a name this program already has: behavior type 'BhStop' is already registered");
  }
  SECTION("throws from its registration") {
    require_refused(TRIPODAL_TEST_PLUGIN_THROWING, "failed to register its types: the licence file /etc/waver.lic is missing");
  }
  SECTION("a shared library without the entry points") {
    require_refused(TRIPODAL_TEST_NOT_A_PLUGIN, "is not a tripodal plugin: it exports no tripodal_plugin_abi_version");
  }
  SECTION("a file that is not a shared library") {
    const std::filesystem::path text =
        std::filesystem::temp_directory_path() / ("tripodal_not_elf_" + std::to_string(::getpid()) + ".so");
    std::ofstream(text) << "not an ELF file\n";
    require_refused(text.string(), "cannot be loaded as a shared library: ");
    std::filesystem::remove(text);
  }
  SECTION("a file that does not exist") {
    require_refused("/nonexistent/plugin.so", "is not a file that can be read");
  }
}

TEST_CASE("The same plugin loaded twice is refused the second time", "[robot][plugins][errors]") {
  RobotPlugins plugins = builtin_plugins();
  (void)load_plugin_library(TRIPODAL_TEST_PLUGIN_GOOD, plugins);
  REQUIRE_THROWS_WITH(load_plugin_library(TRIPODAL_TEST_PLUGIN_GOOD, plugins),
                      Catch::Contains("registers a name this program already has: behavior type 'BhPluginWave', "
                                      "controller type 'plugin_differential' are already registered"));
}

TEST_CASE("Registry::merge moves all or nothing", "[robot][plugins]") {
  BehaviorRegistry a, b;
  register_builtin_behaviors(a);
  b.add(BhStop::static_manifest(), [] { return std::unique_ptr<CBehavior>(std::make_unique<BhStop>()); });
  const std::size_t before = a.size();
  REQUIRE_THROWS_WITH(a.merge(std::move(b)), "behavior type 'BhStop' already registered");
  CHECK(a.size() == before);
}
