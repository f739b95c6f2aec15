// Region files of the navigation modules (configs/worlds/*_regions.yaml): rejected files are located.
#include "../fuzz_target.hpp"
#include "tripodal/navi/regions.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    (void)navi::parse_regions(fuzz::as_text(bytes), "fuzz.yaml");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.yaml");
  }
}
