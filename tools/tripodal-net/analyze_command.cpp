// tripodal-net analyze: the state-space analysis of one net (docs/analysis.md).
#include <charconv>
#include <filesystem>
#include <fstream>
#include <ostream>

#include "command.hpp"
#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/core/net_loader.hpp"

namespace tripodal::net_tool {

namespace {

constexpr std::string_view kAnalyzeUsage =
    "usage: tripodal-net analyze FILE [--max-states N] [--max-memory-mb N] [--json] [--param K=V]...\n"
    "                            [--semantics engine|interleaving] [--examples N] [--continue-after-outcome]\n"
    "\n"
    "Explores every marking the net can reach, with events, delays and guards over facts as free\n"
    "choices, and reports: states, edges, time and memory; deadlocks (with the shortest firing\n"
    "sequence and the events it needs); the bound of every place and 1-safeness (Karp-Miller for\n"
    "unboundedness); dead transitions; never-marked places; whether an outcome place can be reached\n"
    "from every reachable marking; place and transition invariants.\n"
    "\n"
    "  --max-states N        stop after N states with a partial report (default 5000000)\n"
    "  --max-memory-mb N     stop before the state store exceeds N MiB (default 2048)\n"
    "  --json                the report as JSON (schema in docs/analysis.md)\n"
    "  --param K=V           value of process parameter K for guards (default: declared defaults)\n"
    "  --semantics S         engine: the engine's urgency and priorities (default for native XML);\n"
    "                        interleaving: plain P/T semantics (default for PNML)\n"
    "  --examples N          deadlocks and stuck markings listed with paths (default 10)\n"
    "  --continue-after-outcome  explore past outcome markings (the supervisor stops there)\n"
    "\n"
    "exit: 0 every check passed, 1 a problem was found, the net has errors or the search was cut\n"
    "short, 2 bad command line, 3 the file cannot be read\n";

bool parse_count(const std::string& text, std::size_t& out) {
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc{} && ptr == text.data() + text.size() && out > 0;
}

int run_analyze(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string file;
  bool json = false;
  std::optional<analysis::Semantics> semantics;
  std::vector<std::string> params;
  analysis::AnalysisOptions options;
  auto usage_error = [&](const std::string& message) {
    err << "tripodal-net analyze: " << message << "\n\n" << kAnalyzeUsage;
    return kUsage;
  };
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](std::string& v) {
      if (i + 1 >= args.size()) return false;
      v = args[++i];
      return true;
    };
    std::string v;
    if (a == "--json") {
      json = true;
    } else if (a == "--continue-after-outcome") {
      options.stop_at_outcome = false;
    } else if (a == "--max-states") {
      if (!value(v) || !parse_count(v, options.max_states)) return usage_error("--max-states needs a positive number");
    } else if (a == "--max-memory-mb") {
      std::size_t mb = 0;
      if (!value(v) || !parse_count(v, mb)) return usage_error("--max-memory-mb needs a positive number");
      options.max_memory_bytes = mb << 20;
    } else if (a == "--examples") {
      if (!value(v) || !parse_count(v, options.max_examples)) return usage_error("--examples needs a positive number");
    } else if (a == "--param") {
      if (!value(v)) return usage_error("--param needs NAME=VALUE");
      params.push_back(v);
    } else if (a == "--semantics") {
      if (!value(v) || (v != "engine" && v != "interleaving")) {
        return usage_error("--semantics must be engine or interleaving");
      }
      semantics = v == "engine" ? analysis::Semantics::engine : analysis::Semantics::interleaving;
    } else if (!a.empty() && a[0] == '-') {
      return usage_error("unknown option '" + a + "'");
    } else if (file.empty()) {
      file = a;
    } else {
      return usage_error("one FILE only");
    }
  }
  if (file.empty()) return usage_error("missing FILE");

  std::ifstream in(file, std::ios::binary);
  if (!in) {
    err << "tripodal-net analyze: cannot read '" << file << "'\n";
    return kIoError;
  }
  std::string head(512, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));

  Diagnostics diagnostics;
  const auto net = load_net(file, diagnostics);
  if (!net) {
    err << diagnostics.str();
    return kFindings;
  }
  options.semantics = semantics.value_or(analysis::default_semantics_for(file, head));
  try {
    options.parameters = analysis::parse_parameter_assignments(*net, params);
    const analysis::AnalysisReport report = analysis::analyze(*net, options);
    out << (json ? analysis::format_json(report, *net) : analysis::format_text(report, *net));
    return report.ok() ? kOk : kFindings;
  } catch (const ConfigError& e) {
    err << e.diagnostics().str();
    return kFindings;
  }
}

}  // namespace

TRIPODAL_NET_COMMAND("analyze", "state-space analysis: deadlocks, bounds, outcomes, invariants", kAnalyzeUsage,
                     run_analyze);

}  // namespace tripodal::net_tool
