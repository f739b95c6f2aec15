// Robot profiles (configs/robots): rejected profiles are located. Files the profile names are looked up in a folder that does not exist, so the target reads nothing from disk for relative names.
#include "../fuzz_target.hpp"
#include "tripodal/robot/robot_profile.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    (void)load_robot_profile_from_string(fuzz::as_text(bytes), "fuzz.yaml", "/nonexistent/fuzz");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "");
  }
}
