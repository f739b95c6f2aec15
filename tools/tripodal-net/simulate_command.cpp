// `tripodal-net simulate FILE [--param K=V]... [--events SCRIPT]`: runs a net against a script of
// timed events and prints the firing trace.
#include <memory>
#include <ostream>

#include "cli_tool.hpp"
#include "net_tool_util.hpp"
#include "tripodal/core/net_simulation.hpp"
#include "tripodal/core/registry.hpp"

namespace tripodal::net_tool {
namespace {

using namespace cli;

constexpr std::string_view kDescription =
    "Runs the net from its initial marking at time 0 against a script of timed events and fact\n"
    "changes (format in docs/engine.md, e.g. configs/petri/scenarios/*.events) and prints every\n"
    "firing with its time, consumed event, description and the marking after it, then the outcome.\n"
    "A run that ends without reaching an outcome place (the net waits for an event that never comes,\n"
    "or hangs) fails; with --expect, so does a run whose outcome differs.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 the run reached an outcome (the one --expect names, if given), 1 the run ended\n"
    "            without an outcome or with another one than expected, the net, the parameters or\n"
    "            the script have errors, or the net livelocked, 2 bad command line,\n"
    "            3 a file could not be read";

struct Args {
  std::string file;
  std::vector<std::string> params;
  std::optional<std::string> events;
  double until_s = 3600.0;
  bool no_stop = false;
  bool allow_unknown_events = false;
  std::string expect;  ///< "success", "failure" or empty
};

int run_simulate(const Args& args, std::ostream& out, std::ostream& err) {
  const std::string& file = args.file;
  const std::vector<std::string>& params = args.params;
  const std::optional<std::string>& events = args.events;
  SimulationOptions options;
  options.end_time = time_from_seconds(args.until_s);
  options.stop_at_outcome = !args.no_stop;
  options.allow_unknown_events = args.allow_unknown_events;
  for (const auto& path : {std::optional<std::string>(file), events}) {
    if (path && !std::filesystem::is_regular_file(*path)) {
      err << *path << ": error: cannot open file\n";
      return kIoError;
    }
  }
  const auto net = load_reporting(file, err);
  if (!net) return kBadInput;

  ParameterValues values;
  for (const auto& p : params) {
    const auto eq = p.find('=');
    if (eq == std::string::npos || eq == 0) {
      err << "tripodal-net simulate: --param expects NAME=VALUE, not '" << p << "'\n";
      return kUsage;
    }
    const std::string name = p.substr(0, eq);
    const std::string text = p.substr(eq + 1);
    const VariableDecl* decl = net->find_parameter(name);
    if (decl == nullptr) {
      std::string declared;
      for (const auto& d : net->parameters) declared += (declared.empty() ? "" : ", ") + d.name;
      std::vector<std::string> names;
      for (const auto& d : net->parameters) names.push_back(d.name);
      const auto close = closest_name(name, names);
      err << "tripodal-net simulate: the net declares no parameter '" << name
          << "' (declared: " << (declared.empty() ? "none" : declared) << ")"
          << (close ? "; did you mean '" + *close + "'?" : std::string()) << "\n";
      return kBadInput;
    }
    auto value = parse_value(decl->type, text);
    if (!value) {
      err << "tripodal-net simulate: parameter '" << name << "' is a " << to_string(decl->type) << ", not '" << text
          << "'\n";
      return kBadInput;
    }
    values[name] = std::move(*value);
  }

  EventScript script;
  if (events) script = load_event_script(*events);  // ConfigError: located lines, exit 1 in main
  NetSimulation simulation(*net, values, options);
  const SimulationResult result = simulation.run(script);
  out << "net " << net->id << " (" << (net->level == NetLevel::high ? "high" : "low") << "-level), " << file;
  if (!values.empty()) {
    out << ", parameters:";
    for (const auto& [k, v] : values) out << ' ' << k << '=' << to_string(v);
  }
  if (events) out << ", events " << *events;
  out << "\n" << result.str(*net);
  if (!result.error.empty() || result.status != StepStatus::ok) {
    err << "tripodal-net simulate: " << (result.error.empty() ? std::string(to_string(result.status)) : result.error)
        << "\n";
    return kBadInput;
  }
  // A run that ends without an outcome is a process that never finishes: not a success.
  if (result.outcome == Outcome::none) {
    err << "tripodal-net simulate: the run ended at " << format_seconds(result.end_time)
        << " s without reaching an outcome place (marking " << format_marking(*net, result.final_marking)
        << "): the net waits for an event that did not come, or hangs\n";
    return kBadInput;
  }
  const bool success = result.outcome == Outcome::success;
  if (!args.expect.empty() && (args.expect == "success") != success) {
    err << "tripodal-net simulate: expected " << args.expect << ", the run ended in "
        << (success ? "success at " + result.outcome_place
                    : "failure at " + result.outcome_place + ": " + result.fault_message)
        << "\n";
    return kBadInput;
  }
  return kOk;
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  cmd.add_option("FILE", a->file, "the net (native XML or PNML)")->required();
  cmd.add_option("--param", a->params, "NAME=VALUE: a process parameter (typed by its declaration in the net)")
      ->allow_extra_args(false);
  cmd.add_option("--events", a->events, "SCRIPT: the event script (none: only immediate and delayed transitions)");
  cmd.add_option("--until", a->until_s, "SECONDS: stop at this time at the latest")
      ->check(CLI::Range(0.0, 1e9))
      ->capture_default_str();
  cmd.add_flag("--no-stop", a->no_stop, "keep running after an outcome place is marked");
  cmd.add_flag("--allow-unknown-events", a->allow_unknown_events,
               "accept script events no transition waits for (they are dropped)");
  cmd.add_option("--expect", a->expect,
                 "success|failure: fail (exit 1) when the run ends in the other outcome")
      ->check(CLI::IsMember({"success", "failure"}));
  return [a](std::ostream& out, std::ostream& err) { return run_simulate(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "simulate", "run a net against a script of timed events, print the firings", kDescription,
                     kExitCodes, &setup);

}  // namespace tripodal::net_tool
