// tripodal-net analyze: the state-space analysis of one net (docs/analysis.md).
#include <filesystem>
#include <fstream>
#include <memory>
#include <ostream>

#include "cli_tool.hpp"
#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/core/net_loader.hpp"

namespace tripodal::net_tool {

namespace {

using namespace cli;

constexpr std::string_view kDescription =
    "Explores every marking the net can reach, with events, delays and guards over facts as free\n"
    "choices, and reports: states, edges, time and memory; deadlocks (with the shortest firing\n"
    "sequence and the events it needs); the bound of every place and 1-safeness (Karp-Miller for\n"
    "unboundedness); dead transitions; never-marked places; whether an outcome place can be reached\n"
    "from every reachable marking; place and transition invariants.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 every check passed, 1 a problem was found, the net has errors or the search was\n"
    "            cut short, 2 bad command line, 3 the file cannot be read";

struct Args {
  std::string file;
  bool json = false;
  std::string semantics;
  std::vector<std::string> params;
  std::size_t max_memory_mb = 2048;
  bool continue_after_outcome = false;
  analysis::AnalysisOptions options;
};

int run_analyze(Args& a, std::ostream& out, std::ostream& err) {
  const std::string& file = a.file;
  analysis::AnalysisOptions& options = a.options;
  options.max_memory_bytes = a.max_memory_mb << 20;
  options.stop_at_outcome = !a.continue_after_outcome;
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
    return kBadInput;
  }
  options.semantics = a.semantics.empty()   ? analysis::default_semantics_for(file, head)
                      : a.semantics == "engine" ? analysis::Semantics::engine
                                                : analysis::Semantics::interleaving;
  try {
    options.parameters = analysis::parse_parameter_assignments(*net, a.params);
    const analysis::AnalysisReport report = analysis::analyze(*net, options);
    out << (a.json ? analysis::format_json(report, *net) : analysis::format_text(report, *net));
    return report.ok() ? kOk : kBadInput;
  } catch (const ConfigError& e) {
    err << e.diagnostics().str();
    return kBadInput;
  }
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  cmd.add_option("FILE", a->file, "the net (native XML or PNML)")->required();
  cmd.add_option("--max-states", a->options.max_states, "stop after N states with a partial report")
      ->check(cli::positive_count())
      ->capture_default_str();
  cmd.add_option("--max-memory-mb", a->max_memory_mb, "stop before the state store exceeds N MiB")
      ->check(cli::positive_count())
      ->capture_default_str();
  cmd.add_option("--max-structural-size", a->options.max_structural_size,
                 "places + transitions above which invariants and Karp-Miller are skipped")
      ->check(cli::positive_count())
      ->capture_default_str();
  cmd.add_flag("--json", a->json, "the report as JSON (schema in docs/analysis.md)");
  cmd.add_option("--param", a->params, "K=V: value of process parameter K for guards (default: declared defaults)")
      ->allow_extra_args(false);
  cmd.add_option("--semantics", a->semantics,
                 "engine: the engine's urgency and priorities (default for native XML); "
                 "interleaving: plain P/T semantics (default for PNML)")
      ->check(CLI::IsMember({"engine", "interleaving"}));
  cmd.add_option("--examples", a->options.max_examples, "deadlocks and stuck markings listed with paths")
      ->check(cli::positive_count())
      ->capture_default_str();
  cmd.add_flag("--continue-after-outcome", a->continue_after_outcome,
               "explore past outcome markings (the supervisor stops there)");
  return [a](std::ostream& out, std::ostream& err) { return run_analyze(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "analyze", "state-space analysis: deadlocks, bounds, outcomes, invariants", kDescription,
                     kExitCodes, &setup);

}  // namespace tripodal::net_tool
