// tripodal: the framework's command-line tool (run, describe, trace import|info|dump). The
// sub-commands register themselves (one source file each); tools/cli parses the command line.
#include "cli_tool.hpp"

int main(int argc, char** argv) {
  return tripodal::cli::run_tool(
      {.name = "tripodal",
       .description = "Tools of the tripodal robot framework.",
       .exit_codes = "exit codes: 0 ok, 1 bad input, 2 bad command line, 3 I/O error",
       .groups = {{"trace", "convert CARMEN logs to tripodal traces and inspect traces"}},
       .exception_exit = tripodal::cli::kBadInput},
      argc, argv);
}
