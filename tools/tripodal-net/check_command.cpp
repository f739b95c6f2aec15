// `tripodal-net check FILE...`: loads each net and reports every error and structural warning,
// then runs the deadlock and outcome checks of the state-space analysis on nets small enough, and
// checks recovery rules against the process nets (rules no net's fault can match).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <ostream>
#include <string>

#include "cli_tool.hpp"
#include "net_tool_util.hpp"
#include "parameter_sets.hpp"
#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/planner/recovery.hpp"
#include "tripodal/robot/plugin_library.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::net_tool {
namespace {

using namespace cli;

constexpr std::string_view kDescription =
    "Loads each configuration net (native XML or PNML, by extension then root element) and prints\n"
    "every problem gcc-style, FILE:LINE:COL: error|warning|note: MESSAGE, then one summary line per\n"
    "file. A directory stands for its *.xml and *.pnml files (not recursive).\n"
    "A net that loads is then explored with its default parameters (or each set given by --param,\n"
    "--params or a --profile that runs it), every event order included (docs/analysis.md): a\n"
    "reachable deadlock, a reachable marking from which no outcome place can be reached, a behavior\n"
    "place that can hold two tokens (started twice), a place that grows without end, and a process\n"
    "net without an outcome place are errors, each with the firing sequence that leads there.\n"
    "Guards are evaluated with the parameters known and the facts unknown (three-valued): where the\n"
    "verdict rests on facts taking any value, the summary says so. A net with more reachable states\n"
    "than --max-states (200000), or\n"
    "whose states would not fit in --max-memory-mb, or with too many combinations of parameters\n"
    "without defaults, gets a note naming the limit instead, and its summary says the behaviour was\n"
    "not checked (raise the limit, or use tripodal-net analyze).\n"
    "With --profile ROBOT.yaml, the profile's process nets (and module nets) are checked with the\n"
    "parameters its process entries give them.\n"
    "With --recovery RULES.yaml, the recovery rules are checked against the low-level nets given\n"
    "(a net's id is its process name): a rule whose fault message none of them can post, or that\n"
    "names or inserts a process without a net, is an error.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 every net is valid (warnings allowed), 1 a net has errors, 2 bad command line,\n"
    "            3 a file or directory could not be read";

struct Args {
  std::vector<std::string> inputs;
  std::vector<std::string> params;
  std::vector<std::filesystem::path> params_files;
  std::vector<std::filesystem::path> profiles;
  std::vector<std::filesystem::path> plugins;
  std::vector<std::filesystem::path> recovery_files;
  bool no_warnings = false;
  bool no_behaviour = false;
  std::size_t max_states = analysis::kCheckStateLimit;
  std::size_t max_memory_mb = 2048;
};

enum class FileStatus { valid, invalid, unreadable };

std::string file_head(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string head(512, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head;
}

// The parameter sets of one file: those of the profiles that run it, and those of the command line.
struct FileSets {
  std::vector<ParameterSetText> sets;  // from --param / --params: every declared name must exist
  std::vector<ProfileNet> profile;     // from --profile
};

std::string key_of(const std::filesystem::path& p) {
  std::error_code ec;
  const auto c = std::filesystem::weakly_canonical(p, ec);
  return ec ? p.lexically_normal().string() : c.string();
}

// Checks one net file: the loader's diagnostics, then the behavioural checks on a net that loaded.
FileStatus check_file(const std::filesystem::path& file, const LoadOptions& options, const Args& args,
                      const FileSets& given, std::vector<PetriNet>& loaded, std::ostream& out,
                      std::ostream& err) {
  const bool behaviour = !args.no_behaviour;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    err << file.string() << ": error: cannot open file\n";
    return FileStatus::unreadable;
  }
  Diagnostics diagnostics;
  const auto net = load_net(file, diagnostics, options);
  if (!net) {
    err << diagnostics.str();
    out << file.string() << ": " << diagnostics.error_count() << " error(s)\n";
    return FileStatus::invalid;
  }
  const std::size_t warnings = diagnostics.all().size();
  bool checked = false;
  analysis::BehaviourCheckResult result;
  if (behaviour) {
    analysis::BehaviourCheckOptions check;
    check.semantics = analysis::default_semantics_for(file.string(), file_head(file));
    // PNML nets are written for other tools; native low-level nets are run by the supervisor.
    check.process_net = check.semantics == analysis::Semantics::engine && net->level == NetLevel::low;
    check.max_states = args.max_states;
    check.max_memory_bytes = args.max_memory_mb << 20;
    for (const ParameterSetText& s : given.sets)
      check.parameter_sets.push_back(typed_set(*net, s, false, diagnostics));
    for (const ProfileNet& p : given.profile)
      check.parameter_sets.push_back(typed_set(*net, p.set, p.module, diagnostics));
    if (!diagnostics.has_errors()) {
      try {
        result = analysis::check_behaviour_detailed(*net, diagnostics, check);
        checked = result.checked;
      } catch (const ConfigError& e) {
        // A guard reading an undeclared name: the loader accepts it only without a registry.
        diagnostics.append(e.diagnostics());
      }
    }
  }
  err << diagnostics.str();
  if (diagnostics.has_errors()) {
    out << file.string() << ": " << diagnostics.error_count() << " error(s)\n";
    return FileStatus::invalid;
  }
  std::size_t arcs = 0;
  for (const auto& t : net->transitions()) arcs += t.inputs.size() + t.outputs.size() + t.reads.size() + t.inhibitors.size();
  // "ok" only when everything asked for was checked: a cut search is reported as such.
  out << file.string() << (!behaviour || checked ? ": ok (" : ": valid, behaviour NOT CHECKED (") << net->places().size()
      << " places, " << net->transitions().size() << " transitions, " << arcs << " arcs";
  if (warnings > 0) out << ", " << warnings << " warning(s)";
  if (behaviour && result.parameter_sets > 1) out << "; " << result.parameter_sets << " parameter sets";
  if (behaviour) out << (checked ? "; no deadlock, no marking that cannot reach an outcome" : "; see the note");
  // The verdict rests on facts being free: say so, naming them.
  if (behaviour && checked && !result.assumed_facts.empty()) {
    out << "; OK under " << analysis::assumption_text(result.assumed_facts);
  }
  out << ")\n";
  loaded.push_back(*net);
  return FileStatus::valid;
}

FileStatus check_recovery(const std::filesystem::path& file, const std::vector<PetriNet>& nets, std::ostream& out,
                          std::ostream& err) {
  Diagnostics diagnostics;
  check_recovery_file(file, nets, diagnostics);
  err << diagnostics.str();
  if (diagnostics.has_errors()) out << file.string() << ": " << diagnostics.error_count() << " error(s)\n";
  else out << file.string() << ": ok (every rule can match a fault of the nets)\n";
  return diagnostics.has_errors() ? FileStatus::invalid : FileStatus::valid;
}

int run_check(const Args& args, std::ostream& out, std::ostream& err) {
  LoadOptions options;
  options.structural_warnings = !args.no_warnings;
  std::vector<std::filesystem::path> files;
  bool unreadable = false;
  if (args.inputs.empty() && args.profiles.empty()) {
    err << "tripodal-net check: give nets (FILE|DIR) or --profile ROBOT.yaml\n";
    return kUsage;
  }
  // Parameter sets: the command line's apply to every net; a profile's to the nets it runs.
  std::vector<ParameterSetText> sets;
  std::map<std::string, std::vector<ProfileNet>> by_file;
  try {
    if (!args.params.empty()) {
      ParameterSetText set;
      set.origin = "--param";
      for (const std::string& kv : args.params) {
        const auto eq = kv.find('=');
        if (eq == std::string::npos || eq == 0) {
          err << "tripodal-net check: --param expects NAME=VALUE, not '" << kv << "'\n";
          return kUsage;
        }
        set.values[kv.substr(0, eq)] = kv.substr(eq + 1);
      }
      sets.push_back(std::move(set));
    }
    for (const auto& f : args.params_files) {
      for (auto& s : load_parameter_sets(f)) sets.push_back(std::move(s));
    }
    // The plugin set the profiles' types come from, as `tripodal run` builds it: a plugin refused
    // here would refuse the robot too.
    RobotPlugins plugins = builtin_plugins();
    for (const auto& l : args.plugins) (void)load_plugin_library(l, plugins, SourceLocation{"--plugin", 0, 0});
    for (const auto& profile : args.profiles) {
      (void)load_profile_plugins(load_robot_profile(profile), plugins);
      for (ProfileNet& n : profile_nets(profile, &options.behavior_names)) {
        const std::string key = key_of(n.file);
        if (!by_file.count(key) && args.inputs.empty()) files.push_back(n.file);
        by_file[key].push_back(std::move(n));
      }
    }
  } catch (const ConfigError& e) {
    err << e.diagnostics().str();
    return kBadInput;
  }
  // With profiles, the behaviors a net may bind are theirs: an unknown one gets a suggestion.
  if (!args.profiles.empty()) {
    options.is_known_behavior = [&options](std::string_view n) {
      return std::find(options.behavior_names.begin(), options.behavior_names.end(), n) != options.behavior_names.end();
    };
  }
  for (const auto& a : args.inputs) {
    if (std::filesystem::is_directory(a)) {
      std::vector<std::filesystem::path> found;
      std::error_code ec;
      for (const auto& entry : std::filesystem::directory_iterator(a, ec)) {
        const auto ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".xml" || ext == ".pnml")) found.push_back(entry.path());
      }
      if (ec) {
        err << a << ": error: cannot read directory\n";
        unreadable = true;
      }
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else {
      files.emplace_back(a);
    }
  }
  if (files.empty() && !unreadable) {
    err << "tripodal-net check: no net files in "
        << (args.inputs.empty() ? std::string("the profiles") : args.inputs.front()) << '\n';
    return kUsage;
  }
  bool invalid = false;
  std::vector<PetriNet> loaded;
  for (const auto& f : files) {
    FileSets given;
    given.sets = sets;
    if (const auto it = by_file.find(key_of(f)); it != by_file.end()) given.profile = it->second;
    const FileStatus s = check_file(f, options, args, given, loaded, out, err);
    unreadable = unreadable || s == FileStatus::unreadable;
    invalid = invalid || s == FileStatus::invalid;
  }
  for (const auto& f : args.recovery_files) invalid = check_recovery(f, loaded, out, err) == FileStatus::invalid || invalid;
  if (unreadable) return kIoError;
  return invalid ? kBadInput : kOk;
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  cmd.add_option("FILE|DIR", a->inputs, "nets, or directories of *.xml and *.pnml nets");
  cmd.add_option("--param", a->params, "NAME=VALUE: check with this parameter value (repeatable: one set)")
      ->allow_extra_args(false);
  cmd.add_option(
         "--params", a->params_files,
         "FILE: YAML parameter sets to check with, a map NAME: VALUE or a list of such maps (repeatable)")
      ->allow_extra_args(false);
  cmd.add_option("--profile", a->profiles,
                 "ROBOT.yaml: check the profile's process nets with the parameters its process entries give "
                 "(without FILE: all of its nets; repeatable)")
      ->allow_extra_args(false);
  cmd.add_option("--plugin", a->plugins,
                 "LIB.so: a shared-library plugin the profiles' types come from (repeatable; docs/plugins.md)")
      ->allow_extra_args(false);
  cmd.add_flag("--no-warnings", a->no_warnings,
               "leave out the structural warnings (places never marked, transitions never enabled)");
  cmd.add_flag("--no-behaviour", a->no_behaviour, "skip the deadlock and outcome checks");
  cmd.add_option("--max-states", a->max_states,
                 "explore at most N states per net and parameter combination; a net with more gets a note")
      ->check(cli::positive_count())
      ->capture_default_str();
  cmd.add_option("--max-memory-mb", a->max_memory_mb, "stop a net's exploration before its state store exceeds N MiB")
      ->check(cli::positive_count())
      ->capture_default_str();
  cmd.add_option("--recovery", a->recovery_files,
                 "RULES.yaml: also check these recovery rules against the low-level nets given (repeatable)")
      ->allow_extra_args(false);
  return [a](std::ostream& out, std::ostream& err) { return run_check(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "check", "validate nets: located errors and warnings, deadlock and outcome checks", kDescription,
                     kExitCodes, &setup);

}  // namespace tripodal::net_tool
