// Simulator worlds (configs/worlds): rejected worlds are located (errors inside the map or regions file they name are located in that file).
#include "../fuzz_target.hpp"
#include "tripodal/sim/world.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    (void)sim::parse_world(fuzz::as_text(bytes), "/nonexistent/fuzz/world.yaml");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "");
  }
}
