// The command-line front end both tools (tripodal, tripodal-net) share: CLI11 sub-commands that
// register themselves from their own source files, one help layout, --version, and one mapping
// of command-line errors and failures to exit codes. Internal to tools/, never installed.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <functional>
#include <limits>
#include <iosfwd>
#include <string_view>
#include <utility>
#include <vector>

namespace tripodal::cli {

/// Exit codes every sub-command of both tools keeps to (docs/tools.md); a command may add its
/// own above these (`tripodal run`: 4, the task failed).
enum ExitCode : int {
  kOk = 0,        ///< success; for check/analyze: every file valid / every check passed
  kBadInput = 1,  ///< the input has errors, or a check found a problem
  kUsage = 2,     ///< bad command line (CLI11 names the bad option)
  kIoError = 3,   ///< a file could not be read or written
};

/// What a sub-command runs once its command line has parsed; it reads the variables its setup
/// bound to the options.
using Action = std::function<int(std::ostream& out, std::ostream& err)>;

struct Command {
  std::string_view group;        ///< "trace" for `tripodal trace import`; empty at the top level
  std::string_view name;         ///< "import"
  std::string_view summary;      ///< one line in the tool's (or group's) --help
  std::string_view description;  ///< what the command does, after the options in its --help
  std::string_view exit_codes;   ///< the last lines of its --help
  /// Declares the command's positionals and options on `command`, returns what it runs.
  Action (*setup)(CLI::App& command);
};

/// Adds a command to this program's table; returns true so it can initialise a static.
bool register_command(const Command& command);

struct Tool {
  std::string_view name;         ///< "tripodal-net"
  std::string_view description;  ///< first lines of `NAME --help`
  std::string_view exit_codes;   ///< last lines of `NAME --help`
  /// Groups of sub-commands and their one-line summaries ({"trace", "convert and inspect traces"}).
  std::vector<std::pair<std::string_view, std::string_view>> groups;
  /// Exit code when a command throws (a located ConfigError the command did not catch).
  int exception_exit = kBadInput;
};

/// Parses argv, runs the chosen command and returns the process's exit code: 0 for --help and
/// --version, kUsage (message naming the option, on stderr) for a bad command line.
int run_tool(const Tool& tool, int argc, char** argv);

/// Options that are a positive whole number (--max-states, --examples, ...): the error reads
/// "--examples: expected a whole number > 0, got 'lots'".
[[nodiscard]] CLI::Validator positive_count();
/// Options that are a whole number from 0 to max (--seed): a sign, a fraction or a number beyond
/// max is refused ("--seed: expected a whole number from 0 to 18446744073709551615, got '-1'"),
/// not wrapped or capped.
[[nodiscard]] CLI::Validator whole_number(std::uint64_t max = std::numeric_limits<std::uint64_t>::max());
/// Options that are a positive number (--max-duration-s, --realtime SPEED).
[[nodiscard]] CLI::Validator positive_number();

}  // namespace tripodal::cli

#define TRIPODAL_CLI_CONCAT2(a, b) a##b
#define TRIPODAL_CLI_CONCAT(a, b) TRIPODAL_CLI_CONCAT2(a, b)
#define TRIPODAL_CLI_COMMAND(...)                                                   \
  [[maybe_unused]] static const bool TRIPODAL_CLI_CONCAT(registered_, __LINE__) = \
      ::tripodal::cli::register_command(::tripodal::cli::Command{__VA_ARGS__})
