// Recovery rules of the planner (configs/tasks/*recovery.yaml): rejected rule files are located.
#include "../fuzz_target.hpp"
#include "tripodal/planner/recovery.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    (void)RecoveryPolicy::load_from_string(fuzz::as_text(bytes), "fuzz.yaml");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.yaml");
  }
}
