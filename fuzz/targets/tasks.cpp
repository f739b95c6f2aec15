// Task templates of the planner (configs/tasks): rejected libraries are located.
#include "../fuzz_target.hpp"
#include "tripodal/planner/task_library.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    (void)TaskLibrary::load_from_string(fuzz::as_text(bytes), "fuzz.yaml");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.yaml");
  }
}
