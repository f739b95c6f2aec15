// The YAML half of a map_server map: rejected descriptions are located.
#include "../fuzz_target.hpp"
#include "tripodal/navi/map_io.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    (void)navi::parse_map_yaml(fuzz::as_text(bytes), "fuzz.yaml");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.yaml");
  }
}
