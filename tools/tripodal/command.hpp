// The sub-command table of the `tripodal` tool. Each command (or group of commands, such as
// `trace import|info|dump`) lives in its own source file and registers itself with a static
// TRIPODAL_COMMAND(...), so adding one touches no other file but this folder's CMakeLists.txt.
#pragma once

#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace tripodal::tool {

/// Exit codes shared by every sub-command.
enum ExitCode : int {
  kOk = 0,       ///< success
  kBadInput = 1,  ///< the input file is malformed (the errors are printed)
  kUsage = 2,     ///< bad command line
  kIoError = 3,   ///< a file could not be read or written
};

struct Command {
  std::string_view group;    ///< "trace" for `tripodal trace import`; empty for a top-level command
  std::string_view name;     ///< "import"
  std::string_view summary;  ///< one line for `tripodal --help` / `tripodal GROUP --help`
  std::string_view usage;    ///< full text for `tripodal [GROUP] NAME --help`
  int (*run)(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
};

/// Adds a command to the table; returns true so it can initialise a static.
bool register_command(const Command& command);
[[nodiscard]] const std::vector<Command>& commands();

/// True when args contain -h or --help.
[[nodiscard]] bool wants_help(const std::vector<std::string>& args);

}  // namespace tripodal::tool

#define TRIPODAL_TOOL_CONCAT2(a, b) a##b
#define TRIPODAL_TOOL_CONCAT(a, b) TRIPODAL_TOOL_CONCAT2(a, b)
#define TRIPODAL_COMMAND(...)                                                       \
  [[maybe_unused]] static const bool TRIPODAL_TOOL_CONCAT(registered_, __LINE__) = \
      ::tripodal::tool::register_command(::tripodal::tool::Command{__VA_ARGS__})
