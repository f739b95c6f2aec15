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
#include "tripodal/core/registry.hpp"
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
    "only the profile's behaviors, every fact a net's guards read must be an output of a module (or\n"
    "listed under external_facts:); errors are printed as FILE:LINE:COL and the exit code is 1.\n"
    "--type NAME prints the manifest of a registered type instead: its family and layer, inputs,\n"
    "outputs and parameters with their types, defaults, units and bounds.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 ok, 1 the profile has errors or the type is unknown, 2 bad command line, 3 the profile "
    "cannot be read";

struct Args {
  std::string file;
  bool dot = false;
  std::string type;
  std::vector<std::filesystem::path> plugins;
};

// "[0.01, 2]", "> 0", ">= 0", "" for a parameter's bounds.
std::string bounds_text(const ParameterSpec& p) {
  auto num = [](double v) { return to_string(Value{v}); };
  if (p.min && p.max) return std::string(p.min_exclusive ? "(" : "[") + num(*p.min) + ", " + num(*p.max) + "]";
  if (p.min) return std::string(p.min_exclusive ? "> " : ">= ") + num(*p.min);
  if (p.max) return "<= " + num(*p.max);
  return {};
}

std::string list_text(const std::vector<std::string>& names) {
  if (names.empty()) return "-";
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// A registered type's manifest, as `describe --type` prints it.
std::string manifest_text(const ModuleManifest& m, std::string_view family) {
  std::string out = m.name + " (" + std::string(family) + ", " + std::string(to_string(m.layer)) + " layer)\n";
  if (!m.description.empty()) out += "  " + m.description + "\n";
  out += "  in:  " + list_text(m.inputs) + "\n";
  out += "  out: " + list_text(m.outputs) + "\n";
  if (m.parameters.empty()) return out + "  parameters: none\n";
  out += "  parameters:\n";
  std::size_t width = 0;
  for (const ParameterSpec& p : m.parameters) width = std::max(width, p.name.size());
  for (const ParameterSpec& p : m.parameters) {
    std::string line = "    " + p.name + std::string(width - p.name.size() + 2, ' ') + std::string(to_string(p.type));
    if (p.default_value) {
      line += " = " + to_string(*p.default_value);
    } else {
      line += p.optional ? " (optional)" : " (required)";
    }
    if (!p.unit.empty()) line += " " + p.unit;
    if (const std::string b = bounds_text(p); !b.empty()) line += ", " + b;
    if (!p.description.empty()) line += ": " + p.description;
    out += line + "\n";
  }
  return out;
}

// `describe --type NAME`: the type in whichever family registers it (a name in several: each).
int describe_type(const std::string& type, const std::vector<std::filesystem::path>& libraries, std::ostream& out,
                  std::ostream& err) {
  RobotPlugins plugins;
  app::register_tool_plugins(plugins, nullptr, RobotProfile{}, libraries);
  std::vector<std::string> known;
  bool found = false;
  auto look = [&](const auto& registry, std::string_view family) {
    if (const ModuleManifest* m = registry.find(type)) {
      out << (found ? "\n" : "") << manifest_text(*m, family);
      found = true;
    }
    for (std::string& n : registry.names()) known.push_back(std::move(n));
  };
  look(plugins.behaviors, "behavior type");
  look(plugins.processes, "process type");
  look(plugins.modules, "module type");
  look(plugins.resources, "resource type");
  look(plugins.hardware, "hardware type");
  look(plugins.controllers, "controller type");
  if (found) return kOk;
  std::sort(known.begin(), known.end());
  known.erase(std::unique(known.begin(), known.end()), known.end());
  err << "tripodal describe: " << unknown_name_message("type", type, known) << '\n';
  return kBadInput;
}

int describe(const Args& args, std::ostream& out, std::ostream& err) {
  if (!args.type.empty()) return describe_type(args.type, args.plugins, out, err);
  if (args.file.empty()) {
    err << "tripodal describe: give a robot profile (ROBOT.yaml) or --type NAME\nrun 'tripodal describe "
           "--help' for the usage\n";
    return kUsage;
  }
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
  CLI::Option* file = cmd.add_option("ROBOT.yaml", a->file, "the robot profile");
  CLI::Option* type = cmd.add_option("--type", a->type, "NAME: print the manifest of a registered type instead");
  cmd.add_flag("--dot", a->dot, "the layered functionality diagram in Graphviz DOT")->excludes(type);
  file->excludes(type);
  cmd.add_option("--plugin", a->plugins,
                 "LIB.so: a shared-library plugin with the profile's own types (repeatable; docs/plugins.md)")
      ->allow_extra_args(false);
  return [a](std::ostream& out, std::ostream& err) { return describe(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "describe", "layered functionality diagram of a robot profile (text or --dot), or a type's manifest",
                     kDescription, kExitCodes, &setup);

}  // namespace tripodal::tool
