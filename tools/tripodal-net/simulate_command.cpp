// `tripodal-net simulate FILE [--param K=V]... [--events SCRIPT]`: runs a net against a script of
// timed events and prints the firing trace.
#include <charconv>
#include <ostream>

#include "command.hpp"
#include "net_tool_util.hpp"
#include "tripodal/core/net_simulation.hpp"

namespace tripodal::net_tool {
namespace {

constexpr std::string_view kHelp =
    "usage: tripodal-net simulate FILE [--param NAME=VALUE]... [--events SCRIPT] [--until SECONDS]\n"
    "                             [--no-stop] [--allow-unknown-events]\n\n"
    "Runs the net from its initial marking at time 0 against a script of timed events and fact\n"
    "changes (format in docs/engine.md, e.g. configs/petri/scenarios/*.events) and prints every\n"
    "firing with its time, consumed event, description and the marking after it, then the outcome.\n\n"
    "  --param NAME=VALUE       a process parameter (typed by its declaration in the net)\n"
    "  --events SCRIPT          the event script (none: only immediate and delayed transitions)\n"
    "  --until SECONDS          stop at this time at the latest (default 3600)\n"
    "  --no-stop                keep running after an outcome place is marked\n"
    "  --allow-unknown-events   accept script events no transition waits for (they are dropped)\n\n"
    "exit codes: 0 the simulation ran (whatever outcome it reached), 1 the net, the parameters or\n"
    "            the script have errors, or the net livelocked, 2 bad command line,\n"
    "            3 a file could not be read\n";

int run_simulate(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string file;
  std::vector<std::string> params;
  std::optional<std::string> events;
  SimulationOptions options;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--param") {
      auto v = option_value(args, i, err);
      if (!v) return kUsage;
      params.push_back(*v);
    } else if (a == "--events") {
      events = option_value(args, i, err);
      if (!events) return kUsage;
    } else if (a == "--until") {
      auto v = option_value(args, i, err);
      if (!v) return kUsage;
      double s = 0;
      const auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), s);
      if (ec != std::errc() || ptr != v->data() + v->size() || !(s >= 0.0) || s > 1e9) {
        err << "tripodal-net simulate: --until: bad time '" << *v << "' (seconds)\n";
        return kUsage;
      }
      options.end_time = from_seconds(s);
    } else if (a == "--no-stop") {
      options.stop_at_outcome = false;
    } else if (a == "--allow-unknown-events") {
      options.allow_unknown_events = true;
    } else if (a.size() > 1 && a[0] == '-') {
      err << "tripodal-net simulate: unknown option " << a << "\n" << kHelp;
      return kUsage;
    } else if (file.empty()) {
      file = a;
    } else {
      err << "tripodal-net simulate: one net at a time (the script goes after --events)\n" << kHelp;
      return kUsage;
    }
  }
  if (file.empty()) {
    err << kHelp;
    return kUsage;
  }
  for (const auto& path : {std::optional<std::string>(file), events}) {
    if (path && !std::filesystem::is_regular_file(*path)) {
      err << *path << ": error: cannot open file\n";
      return kIoError;
    }
  }
  const auto net = load_reporting(file, err);
  if (!net) return kFindings;

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
      err << "tripodal-net simulate: the net declares no parameter '" << name << "' (declared: "
          << (declared.empty() ? "none" : declared) << ")\n";
      return kFindings;
    }
    auto value = parse_value(decl->type, text);
    if (!value) {
      err << "tripodal-net simulate: parameter '" << name << "' is a " << to_string(decl->type) << ", not '" << text
          << "'\n";
      return kFindings;
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
    return kFindings;
  }
  return kOk;
}

}  // namespace

TRIPODAL_NET_COMMAND("simulate", "run a net against a script of timed events, print the firings", kHelp,
                     &run_simulate);

}  // namespace tripodal::net_tool
