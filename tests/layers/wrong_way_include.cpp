// Must not compile (tests/layers/CMakeLists.txt): it belongs to a target that links only the
// controllers area, which sits below behaviors, so the behaviors header is out of its sight.
#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/controllers/controller.hpp"
