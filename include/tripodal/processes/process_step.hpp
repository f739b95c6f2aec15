// One process module to run with its parameters: the unit of the deliberate layer's plans and of
// the steps a recovery rule inserts. Kept in the processes area (below the planner) because a
// process definition carries its own recovery rules.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "tripodal/core/petri_net.hpp"

namespace tripodal {

/// One process module to run, with its parameters (values already substituted).
struct ProcessStep {
  std::string process;  ///< e.g. "PrCleaning"
  std::vector<BindingParam> params;
  friend bool operator==(const ProcessStep& a, const ProcessStep& b) {
    if (a.process != b.process || a.params.size() != b.params.size()) return false;
    for (std::size_t i = 0; i < a.params.size(); ++i) {
      if (a.params[i].name != b.params[i].name || a.params[i].value != b.params[i].value) return false;
    }
    return true;
  }
};

}  // namespace tripodal
