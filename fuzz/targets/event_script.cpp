// Event scripts (the .events scenarios of tripodal-net simulate): rejected scripts are located.
#include "../fuzz_target.hpp"
#include "tripodal/core/event_script.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    (void)parse_event_script(fuzz::as_text(bytes), "fuzz.events");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.events");
  }
}
