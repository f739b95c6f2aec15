// `tripodal-net convert IN OUT`: native XML <-> PNML, by the files' extensions.
#include <fstream>
#include <ostream>

#include "command.hpp"
#include "net_tool_util.hpp"

namespace tripodal::net_tool {
namespace {

constexpr std::string_view kHelp =
    "usage: tripodal-net convert IN OUT\n\n"
    "Converts a net between tripodal's native XML (.xml) and PNML (.pnml), by the extensions: IN\n"
    "is read like `check` reads it, OUT is written as PNML when it ends in .pnml (an ISO/IEC\n"
    "15909-2 2009 P/T net with <page>; guards, events, delays, bindings, outcomes, priorities and\n"
    "read arcs in <toolspecific tool=\"tripodal\">), else as native XML.\n\n"
    "exit codes: 0 written, 1 IN has errors or cannot be represented in OUT's format,\n"
    "            2 bad command line, 3 a file could not be read or written\n";

int run_convert(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.size() != 2 || (args[0].size() > 1 && args[0][0] == '-') || (args[1].size() > 1 && args[1][0] == '-')) {
    err << kHelp;
    return kUsage;
  }
  const std::filesystem::path in = args[0];
  const std::filesystem::path target = args[1];
  if (!std::filesystem::is_regular_file(in)) {
    err << in.string() << ": error: cannot open file\n";
    return kIoError;
  }
  const auto net = load_reporting(in, err);
  if (!net) return kFindings;
  const bool pnml = target.extension() == ".pnml";
  std::string text;
  try {
    text = net_to_string(*net, pnml ? NetFormat::pnml : NetFormat::native_xml);
  } catch (const ConfigError& e) {
    err << e.what();
    return kFindings;
  }
  std::ofstream f(target, std::ios::binary | std::ios::trunc);
  f << text;
  f.flush();
  if (!f) {
    err << target.string() << ": error: cannot write file\n";
    return kIoError;
  }
  out << in.string() << " -> " << target.string() << " (" << (pnml ? "PNML" : "native XML") << ", "
      << net->places().size() << " places, " << net->transitions().size() << " transitions)\n";
  return kOk;
}

}  // namespace

TRIPODAL_NET_COMMAND("convert", "convert a net between native XML and PNML (by extension)", kHelp, &run_convert);

}  // namespace tripodal::net_tool
