// tripodal-net: check, draw, simulate, convert and analyse configuration nets. The sub-commands
// register themselves (one source file each); tools/cli parses the command line.
#include "cli_tool.hpp"

int main(int argc, char** argv) {
  return tripodal::cli::run_tool(
      {.name = "tripodal-net",
       .description = "Author, verify and run tripodal configuration nets (native XML or PNML).",
       .exit_codes = "exit codes: 0 ok, 1 the input has errors or a check failed, 2 bad command line, 3 I/O error",
       .groups = {},
       .exception_exit = tripodal::cli::kBadInput},
      argc, argv);
}
