// The sub-command table of tripodal-net. Each sub-command lives in its own source file and
// registers itself with a static TRIPODAL_NET_COMMAND(...) so that adding one touches no other file.
#pragma once

#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace tripodal::net_tool {

/// Exit codes shared by every sub-command (documented in docs/tools.md).
enum ExitCode : int {
  kOk = 0,            ///< success; for check/analyze: every file valid / every check passed
  kFindings = 1,      ///< the input has errors, or a check found a problem
  kUsage = 2,         ///< bad command line
  kIoError = 3,       ///< a file could not be read or written
};

struct Command {
  std::string_view name;
  std::string_view summary;  ///< one line for `tripodal-net --help`
  std::string_view usage;    ///< full text for `tripodal-net NAME --help`
  int (*run)(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
};

/// Adds a command to the table; returns true so it can initialise a static.
bool register_command(const Command& command);
[[nodiscard]] const std::vector<Command>& commands();

/// True when args contain -h or --help.
[[nodiscard]] bool wants_help(const std::vector<std::string>& args);

}  // namespace tripodal::net_tool

#define TRIPODAL_NET_CONCAT2(a, b) a##b
#define TRIPODAL_NET_CONCAT(a, b) TRIPODAL_NET_CONCAT2(a, b)
#define TRIPODAL_NET_COMMAND(...)                                              \
  [[maybe_unused]] static const bool TRIPODAL_NET_CONCAT(registered_, __LINE__) = \
      ::tripodal::net_tool::register_command(::tripodal::net_tool::Command{__VA_ARGS__})
