// `tripodal-net dot FILE [--marking P=N,...]`: Graphviz drawing of a net like the paper's figures.
#include <charconv>
#include <fstream>
#include <memory>
#include <ostream>

#include "cli_tool.hpp"
#include "net_tool_util.hpp"
#include "tripodal/core/net_dot.hpp"

namespace tripodal::net_tool {
namespace {

using namespace cli;

constexpr std::string_view kDescription =
    "Writes the net as a Graphviz digraph drawn like the paper's figures: places are circles with\n"
    "their tokens, transitions black bars, labels the ids and descriptions; read arcs dashed,\n"
    "inhibitor arcs ending in a circle, outcome places doubled (faults in red).\n"
    "Render with e.g.  tripodal-net dot net.xml | dot -Tsvg > net.svg";

constexpr std::string_view kExitCodes =
    "exit codes: 0 ok, 1 the net has errors or the marking names an unknown place,\n"
    "            2 bad command line, 3 a file could not be read or written";

struct Args {
  std::string file;
  std::optional<std::string> marking_text;
  std::optional<std::string> output;
  bool no_descriptions = false;
};

int run_dot(const Args& args, std::ostream& out, std::ostream& err) {
  const std::string& file = args.file;
  const std::optional<std::string>& marking_text = args.marking_text;
  const std::optional<std::string>& output = args.output;
  DotOptions options;
  options.descriptions = !args.no_descriptions;
  if (!std::filesystem::is_regular_file(file)) {
    err << file << ": error: cannot open file\n";
    return kIoError;
  }
  const auto net = load_reporting(file, err);
  if (!net) return kBadInput;
  Marking marking;
  if (marking_text) {
    marking.assign(net->places().size(), 0);
    std::string_view rest = *marking_text;
    while (!rest.empty()) {
      const auto comma = rest.find(',');
      const std::string_view item = rest.substr(0, comma);
      rest = comma == std::string_view::npos ? std::string_view{} : rest.substr(comma + 1);
      const auto eq = item.find('=');
      const std::string_view id = item.substr(0, eq);
      Tokens n = 1;
      if (eq != std::string_view::npos) {
        const auto count = item.substr(eq + 1);
        const auto [ptr, ec] = std::from_chars(count.data(), count.data() + count.size(), n);
        if (count.empty() || ec != std::errc() || ptr != count.data() + count.size()) {
          err << "tripodal-net dot: --marking: bad token count '" << count << "' for place '" << id << "'\n";
          return kUsage;
        }
      }
      const auto place = net->find_place(id);
      if (!place) {
        err << "tripodal-net dot: --marking: no place '" << id << "' in " << file << "\n";
        return kBadInput;
      }
      marking[*place] = n;
    }
  }
  const std::string dot = net_to_dot(*net, marking, options);
  if (!output) {
    out << dot;
    return kOk;
  }
  std::ofstream f(*output, std::ios::binary | std::ios::trunc);
  f << dot;
  f.flush();
  if (!f) {
    err << *output << ": error: cannot write file\n";
    return kIoError;
  }
  return kOk;
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  cmd.add_option("FILE", a->file, "the net (native XML or PNML)")->required();
  cmd.add_option("--marking", a->marking_text, "P=N,...: draw this marking instead of the initial one (unlisted places: 0)");
  cmd.add_flag("--no-descriptions", a->no_descriptions, "ids and annotations only");
  cmd.add_option("-o", a->output, "OUT: write to OUT instead of standard output")->check(cli::writable_file());
  return [a](std::ostream& out, std::ostream& err) { return run_dot(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "dot", "draw a net as Graphviz DOT, like the paper's figures", kDescription, kExitCodes, &setup);

}  // namespace tripodal::net_tool
