// A recovery rule: which fault message of which process makes the planner insert which process
// steps, and what it does then. Plain data, so a process definition (processes area) can carry
// its own rules without including the planner that applies them (planner/recovery.hpp).
#pragma once

#include <string>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/processes/process_step.hpp"

namespace tripodal {

enum class RecoveryAction {
  retry,  ///< run the inserted processes, then the failed stage again
  skip,   ///< run the inserted processes, then go on after the failed stage
  abort,  ///< the task fails
  end,    ///< run the inserted processes (the robot sent to its dock), then the task fails with the fault
};

struct RecoveryRule {
  std::string fault;    ///< the fault message it handles (case-insensitive exact match)
  std::string process;  ///< only faults of this process; empty: any process
  std::vector<ProcessStep> insert;
  RecoveryAction then = RecoveryAction::retry;
  int max_retries = 1;  ///< how many times this rule may fire for one task before it gives up
  SourceLocation where;
};

}  // namespace tripodal
