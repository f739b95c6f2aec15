// `tripodal-net convert IN OUT`: native XML <-> PNML, by the files' extensions.
#include <fstream>
#include <memory>
#include <ostream>

#include "cli_tool.hpp"
#include "net_tool_util.hpp"

namespace tripodal::net_tool {
namespace {

using namespace cli;

constexpr std::string_view kDescription =
    "Converts a net between tripodal's native XML (.xml) and PNML (.pnml), by the extensions: IN\n"
    "is read like `check` reads it, OUT is written as PNML when it ends in .pnml (an ISO/IEC\n"
    "15909-2 2009 P/T net with <page>; guards, events, delays, bindings, outcomes, priorities and\n"
    "read arcs in <toolspecific tool=\"tripodal\">), else as native XML.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 written, 1 IN has errors or cannot be represented in OUT's format,\n"
    "            2 bad command line, 3 a file could not be read or written";

struct Args {
  std::filesystem::path in, target;
};

int run_convert(const Args& args, std::ostream& out, std::ostream& err) {
  const std::filesystem::path& in = args.in;
  const std::filesystem::path& target = args.target;
  if (!std::filesystem::is_regular_file(in)) {
    err << in.string() << ": error: cannot open file\n";
    return kIoError;
  }
  const auto net = load_reporting(in, err);
  if (!net) return kBadInput;
  const bool pnml = target.extension() == ".pnml";
  std::string text;
  try {
    text = net_to_string(*net, pnml ? NetFormat::pnml : NetFormat::native_xml);
  } catch (const ConfigError& e) {
    err << e.what();
    return kBadInput;
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

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  cmd.add_option("IN", a->in, "the net to read (.xml or .pnml)")->required();
  cmd.add_option("OUT", a->target, "the file to write: PNML when it ends in .pnml, else native XML")
      ->required()
      ->check(cli::writable_file());
  return [a](std::ostream& out, std::ostream& err) { return run_convert(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "convert", "convert a net between native XML and PNML (by extension)", kDescription, kExitCodes,
                     &setup);

}  // namespace tripodal::net_tool
