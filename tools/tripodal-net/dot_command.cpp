// `tripodal-net dot FILE [--marking P=N,...]`: Graphviz drawing of a net like the paper's figures.
#include <charconv>
#include <fstream>
#include <ostream>

#include "command.hpp"
#include "net_tool_util.hpp"
#include "tripodal/core/net_dot.hpp"

namespace tripodal::net_tool {
namespace {

constexpr std::string_view kHelp =
    "usage: tripodal-net dot FILE [--marking P=N,...] [--no-descriptions] [-o OUT]\n\n"
    "Writes the net as a Graphviz digraph drawn like the paper's figures: places are circles with\n"
    "their tokens, transitions black bars, labels the ids and descriptions; read arcs dashed,\n"
    "inhibitor arcs ending in a circle, outcome places doubled (faults in red).\n"
    "Render with e.g.  tripodal-net dot net.xml | dot -Tsvg > net.svg\n\n"
    "  --marking P=N,...   draw this marking instead of the initial one (unlisted places: 0)\n"
    "  --no-descriptions   ids and annotations only\n"
    "  -o OUT              write to OUT instead of standard output\n\n"
    "exit codes: 0 ok, 1 the net has errors or the marking names an unknown place,\n"
    "            2 bad command line, 3 a file could not be read or written\n";

int run_dot(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string file;
  std::optional<std::string> marking_text;
  std::optional<std::string> output;
  DotOptions options;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--marking") {
      marking_text = option_value(args, i, err);
      if (!marking_text) return kUsage;
    } else if (args[i] == "-o") {
      output = option_value(args, i, err);
      if (!output) return kUsage;
    } else if (args[i] == "--no-descriptions") {
      options.descriptions = false;
    } else if (args[i].size() > 1 && args[i][0] == '-') {
      err << "tripodal-net dot: unknown option " << args[i] << "\n" << kHelp;
      return kUsage;
    } else if (file.empty()) {
      file = args[i];
    } else {
      err << "tripodal-net dot: one net at a time\n" << kHelp;
      return kUsage;
    }
  }
  if (file.empty()) {
    err << kHelp;
    return kUsage;
  }
  if (!std::filesystem::is_regular_file(file)) {
    err << file << ": error: cannot open file\n";
    return kIoError;
  }
  const auto net = load_reporting(file, err);
  if (!net) return kFindings;
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
        return kFindings;
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

}  // namespace

TRIPODAL_NET_COMMAND("dot", "draw a net as Graphviz DOT, like the paper's figures", kHelp, &run_dot);

}  // namespace tripodal::net_tool
