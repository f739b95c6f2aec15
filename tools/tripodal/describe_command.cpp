// `tripodal describe ROBOT.yaml [--dot]`: the layered functionality diagram of a robot profile —
// modules by layer with their inputs and outputs, or a Graphviz drawing of it (paper, Figs. 4, 6,
// 7) — after the start-up checks `tripodal run` makes before it builds the robot (check_robot).
#include <algorithm>
#include <memory>
#include <ostream>

#include "cli_tool.hpp"
#include "run_task.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/robot/layering.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::tool {
namespace {

using namespace cli;

constexpr std::string_view kDescription =
    "Prints the modules of a robot profile by layer (deliberate, sequencing, reactive) with their\n"
    "inputs and outputs, including the core components (planner, process supervisor,\n"
    "configurations, behavior coordinator). --dot prints the layered functionality diagram in\n"
    "Graphviz DOT instead (render with: dot -Tsvg). The profile is checked first, as `tripodal run`\n"
    "checks it before it builds the robot: every input needs exactly one provider, the layering\n"
    "rules must hold (docs/processes.md), every type must be registered, the process nets may bind\n"
    "only the profile's behaviors; errors are printed as FILE:LINE:COL and the exit code is 1.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 ok, 1 the profile has errors, 2 bad command line, 3 the profile cannot be read";

struct Args {
  std::string file;
  bool dot = false;
  std::vector<std::filesystem::path> plugins;
};

int describe(const Args& args, std::ostream& out, std::ostream& err) {
  const std::string& file = args.file;
  const bool dot = args.dot;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    err << "tripodal describe: cannot read '" << file << "'\n";
    return kIoError;
  }
  try {
    const RobotProfile profile = load_robot_profile(file);
    // The types `tripodal run` knows, registered by the same function: no world, as no robot is built.
    RobotPlugins plugins;
    app::register_tool_plugins(plugins, nullptr, profile, args.plugins);
    // The checks `tripodal run` makes before it builds anything (Robot::assemble runs the same).
    Diagnostics d;
    const RobotDescription r = check_robot(profile, plugins, d);
    if (d.has_errors()) {
      err << d.str() << '\n' << "robot '" << profile.name << "' would refuse to start: " << d.error_count() << " error(s)\n";
      return kBadInput;
    }
    if (!d.empty()) err << d.str() << '\n';  // warnings: types designed here, not yet registered
    out << (dot ? describe_dot(r) : describe_text(r));
    return kOk;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  }
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  cmd.add_option("ROBOT.yaml", a->file, "the robot profile")->required();
  cmd.add_flag("--dot", a->dot, "the layered functionality diagram in Graphviz DOT");
  cmd.add_option("--plugin", a->plugins, "LIB.so: a shared-library plugin with the profile's own types (repeatable; docs/plugins.md)")
      ->allow_extra_args(false);
  return [a](std::ostream& out, std::ostream& err) { return describe(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "describe", "layered functionality diagram of a robot profile (text or --dot)", kDescription,
                     kExitCodes, &setup);

}  // namespace tripodal::tool
