// Reactive-layer configurations (configs/reactive): rejected configurations are located.
#include "../fuzz_target.hpp"
#include "tripodal/reactive/reactive_config.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  static const ControllerRegistry controllers = [] {
    ControllerRegistry r;
    register_builtin_controllers(r);
    return r;
  }();
  try {
    (void)parse_reactive_config(fuzz::as_text(bytes), "fuzz.yaml", controllers);
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.yaml");
  }
}
