// `tripodal describe ROBOT.yaml [--dot]`: the layered functionality diagram of a robot profile —
// modules by layer with their inputs and outputs, or a Graphviz drawing of it (paper, Figs. 4, 6,
// 7) — after the start-up checks (one provider per input, layering rules).
#include <algorithm>
#include <ostream>

#include "command.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/robot/layering.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::tool {
namespace {

constexpr std::string_view kDescribeUsage =
    "usage: tripodal describe ROBOT.yaml [--dot]\n\n"
    "Prints the modules of a robot profile by layer (deliberate, sequencing, reactive) with their\n"
    "inputs and outputs, including the core components (planner, process supervisor,\n"
    "configurations, behavior coordinator). --dot prints the layered functionality diagram in\n"
    "Graphviz DOT instead (render with: dot -Tsvg). The profile is checked first: every input\n"
    "needs exactly one provider and the layering rules must hold (docs/processes.md); errors are\n"
    "printed as FILE:LINE:COL and the exit code is 1.\n";

int describe(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::vector<std::string> files;
  bool dot = false;
  for (const auto& a : args) {
    if (a == "--dot") {
      dot = true;
    } else if (a.size() > 1 && a[0] == '-') {
      err << "tripodal describe: unknown option " << a << '\n' << kDescribeUsage;
      return kUsage;
    } else {
      files.push_back(a);
    }
  }
  if (files.size() != 1) {
    err << "tripodal describe: expected one robot profile\n" << kDescribeUsage;
    return kUsage;
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(files[0], ec)) {
    err << "tripodal describe: cannot read '" << files[0] << "'\n";
    return kIoError;
  }
  try {
    const RobotProfile profile = load_robot_profile(files[0]);
    Diagnostics d;
    std::vector<std::string> processes;
    for (const auto& p : profile.processes) processes.push_back(p.name);
    TaskLibrary tasks;
    if (!profile.tasks.empty()) {
      try {
        tasks = TaskLibrary::load(profile.tasks, TaskLoadOptions{[&](std::string_view n) {
                                    return std::find(processes.begin(), processes.end(), n) != processes.end();
                                  }});
      } catch (const ConfigError& e) {
        d.append(e.diagnostics());
      }
    }
    // The types this program knows: the framework's own and the simulator's hardware.
    RobotPlugins plugins = RobotPlugins::with_builtins();
    sim::register_sim_hardware(plugins.hardware);
    const RobotDescription r = describe_robot(profile, plugins, knowledge_inputs(tasks), d);
    if (d.has_errors()) {
      err << d.str() << '\n' << "robot '" << profile.name << "' would refuse to start: " << d.error_count() << " error(s)\n";
      return kBadInput;
    }
    out << (dot ? describe_dot(r) : describe_text(r));
    return kOk;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  }
}

}  // namespace

TRIPODAL_COMMAND("", "describe", "layered functionality diagram of a robot profile (text or --dot)", kDescribeUsage,
                 describe);

}  // namespace tripodal::tool
