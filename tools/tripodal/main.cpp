// tripodal: the framework's command-line tool (run, describe, trace import|info|dump, localization
// eval, map build). The sub-commands register themselves (one source file each); tools/cli parses
// the command line.
#include "cli_tool.hpp"

int main(int argc, char** argv) {
  return tripodal::cli::run_tool(
      {.name = "tripodal",
       .description = "Tools of the tripodal robot framework.",
       .exit_codes = "exit codes: 0 ok, 1 bad input, 2 bad command line, 3 I/O error",
       .groups = {{"trace", "convert CARMEN logs to tripodal traces and inspect traces"},
                  {"localization", "score the scan-matching localizer on recorded logs"},
                  {"map", "build maps from recorded laser and odometry"}},
       .exception_exit = tripodal::cli::kBadInput},
      argc, argv);
}
