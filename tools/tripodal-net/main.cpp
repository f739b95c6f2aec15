// tripodal-net: check, draw, simulate, convert and analyse configuration nets.
#include <algorithm>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "command.hpp"
#include "tripodal/version.hpp"

namespace tripodal::net_tool {

namespace {
std::vector<Command>& table() {
  static std::vector<Command> t;
  return t;
}

void print_help(std::ostream& out) {
  out << "usage: tripodal-net COMMAND [ARGS...]\n"
         "       tripodal-net COMMAND --help\n\n"
         "Author, verify and run tripodal configuration nets (native XML or PNML).\n\ncommands:\n";
  auto sorted = table();
  std::sort(sorted.begin(), sorted.end(), [](const Command& a, const Command& b) { return a.name < b.name; });
  for (const auto& c : sorted) {
    out << "  " << c.name << std::string(c.name.size() < 12 ? 12 - c.name.size() : 1, ' ') << c.summary << '\n';
  }
  out << "\nexit codes: 0 ok, 1 the input has errors or a check failed, 2 bad command line, 3 I/O error\n";
}
}  // namespace

bool register_command(const Command& command) {
  table().push_back(command);
  return true;
}

const std::vector<Command>& commands() { return table(); }

bool wants_help(const std::vector<std::string>& args) {
  return std::any_of(args.begin(), args.end(), [](const std::string& a) { return a == "-h" || a == "--help"; });
}

}  // namespace tripodal::net_tool

int main(int argc, char** argv) {
  using namespace tripodal::net_tool;
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    print_help(std::cerr);
    return kUsage;
  }
  if (args[0] == "-h" || args[0] == "--help" || args[0] == "help") {
    print_help(std::cout);
    return kOk;
  }
  if (args[0] == "--version") {
    std::cout << "tripodal-net " << tripodal::version_string() << '\n';
    return kOk;
  }
  for (const auto& c : commands()) {
    if (c.name == args[0]) {
      args.erase(args.begin());
      if (wants_help(args)) {
        std::cout << c.usage;
        return kOk;
      }
      try {
        return c.run(args, std::cout, std::cerr);
      } catch (const std::exception& e) {
        std::cerr << "tripodal-net " << c.name << ": " << e.what() << '\n';
        return kFindings;
      }
    }
  }
  std::cerr << "tripodal-net: unknown command '" << args[0] << "'\n\n";
  print_help(std::cerr);
  return kUsage;
}
