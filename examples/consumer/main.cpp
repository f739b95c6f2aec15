// The smallest robot application: links the installed tripodal package, builds a configuration
// net in code and reports it. CI builds this against `cmake --install` output, not the build tree.
#include <iostream>

#include "tripodal/core/petri_net.hpp"
#include "tripodal/version.hpp"

int main() {
  tripodal::PetriNet net;
  net.id = "PrHello";
  net.add_place({.id = "P0", .description = "Standby", .initial_tokens = 1});
  tripodal::Place done{.id = "P1", .description = "Completion"};
  done.outcome = tripodal::Outcome::success;
  net.add_place(done);
  net.add_transition({.id = "t0", .description = "start", .event = "user.start"});
  net.add_arc("P0", "t0");
  net.add_arc("t0", "P1");
  std::cout << "tripodal " << tripodal::version_string() << ": net " << net.id << " has "
            << net.places().size() << " places and " << net.transitions().size() << " transitions\n";
  return net.places().size() == 2 ? 0 : 1;
}
