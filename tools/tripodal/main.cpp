// tripodal: the framework's command-line tool (trace import/info/dump; more groups register
// themselves in their own files).
#include <algorithm>
#include <exception>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "command.hpp"
#include "tripodal/version.hpp"

namespace tripodal::tool {

namespace {

std::vector<Command>& table() {
  static std::vector<Command> t;
  return t;
}

std::vector<Command> sorted() {
  auto s = table();
  std::sort(s.begin(), s.end(), [](const Command& a, const Command& b) {
    return a.group != b.group ? a.group < b.group : a.name < b.name;
  });
  return s;
}

void line(std::ostream& out, std::string_view name, std::string_view summary) {
  out << "  " << name << std::string(name.size() < 16 ? 16 - name.size() : 1, ' ') << summary << '\n';
}

void print_help(std::ostream& out) {
  out << "usage: tripodal COMMAND [ARGS...]\n"
         "       tripodal GROUP COMMAND [ARGS...]\n"
         "       tripodal [GROUP] COMMAND --help\n\n"
         "Tools of the tripodal robot framework.\n\ncommands:\n";
  for (const auto& c : sorted()) {
    line(out, c.group.empty() ? std::string(c.name) : std::string(c.group) + " " + std::string(c.name), c.summary);
  }
  out << "\nexit codes: 0 ok, 1 bad input, 2 bad command line, 3 I/O error\n";
}

void print_group_help(std::ostream& out, std::string_view group) {
  out << "usage: tripodal " << group << " COMMAND [ARGS...]\n\ncommands:\n";
  for (const auto& c : sorted()) {
    if (c.group == group) line(out, c.name, c.summary);
  }
}

int run(const Command& c, std::vector<std::string> args) {
  if (wants_help(args)) {
    std::cout << c.usage;
    return kOk;
  }
  try {
    return c.run(args, std::cout, std::cerr);
  } catch (const std::exception& e) {
    std::cerr << "tripodal " << (c.group.empty() ? "" : std::string(c.group) + " ") << c.name << ": " << e.what()
              << '\n';
    return kBadInput;
  }
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

}  // namespace tripodal::tool

int main(int argc, char** argv) {
  using namespace tripodal::tool;
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
    std::cout << "tripodal " << tripodal::version_string() << '\n';
    return kOk;
  }
  const bool is_group = std::any_of(commands().begin(), commands().end(),
                                    [&](const Command& c) { return !c.group.empty() && c.group == args[0]; });
  if (is_group) {
    const std::string group = args[0];
    if (args.size() < 2 || args[1] == "-h" || args[1] == "--help") {
      print_group_help(args.size() < 2 ? std::cerr : std::cout, group);
      return args.size() < 2 ? kUsage : kOk;
    }
    for (const auto& c : commands()) {
      if (c.group == group && c.name == args[1]) return run(c, std::vector<std::string>(args.begin() + 2, args.end()));
    }
    std::cerr << "tripodal " << group << ": unknown command '" << args[1] << "'\n\n";
    print_group_help(std::cerr, group);
    return kUsage;
  }
  for (const auto& c : commands()) {
    if (c.group.empty() && c.name == args[0]) return run(c, std::vector<std::string>(args.begin() + 1, args.end()));
  }
  std::cerr << "tripodal: unknown command '" << args[0] << "'\n\n";
  print_help(std::cerr);
  return kUsage;
}
