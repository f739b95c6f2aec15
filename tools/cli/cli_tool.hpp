// The command-line front end both tools (tripodal, tripodal-net) share: CLI11 sub-commands that
// register themselves from their own source files, one help layout, --version, and one mapping
// of command-line errors and failures to exit codes. Internal to tools/, never installed.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
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

/// For a program without sub-commands (tripodal-board-sim): gives `app` the tools' help layout,
/// --version and `exit_codes` as the last lines of its help, then parses argv as run_tool does.
/// Returns the exit code when the program should stop here: kOk after --help or --version,
/// kUsage for a bad command line (the message, a "did you mean" and where to find the usage on
/// stderr, prefixed with `name`); nullopt when the command line parsed.
[[nodiscard]] std::optional<int> parse_command_line(CLI::App& app, std::string_view name, std::string_view exit_codes, int argc,
                                                    char** argv);

/// Options that are a positive whole number (--max-states, --examples, ...): the error reads
/// "--examples: expected a whole number > 0, got 'lots'".
[[nodiscard]] CLI::Validator positive_count();
/// Options that are a whole number from 0 to max (--seed): a sign, a fraction or a number beyond
/// max is refused ("--seed: expected a whole number from 0 to 18446744073709551615, got '-1'"),
/// not wrapped or capped.
[[nodiscard]] CLI::Validator whole_number(std::uint64_t max = std::numeric_limits<std::uint64_t>::max());
/// Options that are a positive number (--max-duration-s, --realtime SPEED).
[[nodiscard]] CLI::Validator positive_number();
/// Options that are a number >= 0 (--duration-s, --tank-l): "expected a number >= 0, got '-1'".
[[nodiscard]] CLI::Validator non_negative_number();
/// Options naming a folder the command writes into (--out DIR): checked before the command runs,
/// so that an unwritable place is refused at once, not after a whole simulation. The folder may
/// not exist yet; then the nearest existing folder above it must be writable.
[[nodiscard]] CLI::Validator writable_folder();
/// Options naming a file the command writes (--record FILE, -o OUT): not a folder, and its folder
/// writable (or creatable, as for writable_folder).
[[nodiscard]] CLI::Validator writable_file();

/// What a mistyped command line probably meant, walking argv down `app`'s sub-commands: "unknown
/// command 'rnu'; did you mean 'run'?" or "unknown option '--sed'; did you mean '--seed'?"; empty
/// when every command and option is known. For any CLI11 program (tools/*), on a ParseError.
[[nodiscard]] std::string did_you_mean(const CLI::App& app, int argc, const char* const* argv);

}  // namespace tripodal::cli

#define TRIPODAL_CLI_CONCAT2(a, b) a##b
#define TRIPODAL_CLI_CONCAT(a, b) TRIPODAL_CLI_CONCAT2(a, b)
#define TRIPODAL_CLI_COMMAND(...)                                                   \
  [[maybe_unused]] static const bool TRIPODAL_CLI_CONCAT(registered_, __LINE__) = \
      ::tripodal::cli::register_command(::tripodal::cli::Command{__VA_ARGS__})
