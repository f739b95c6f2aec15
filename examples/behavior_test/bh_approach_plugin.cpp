// The tutorial's behavior as a shared-library plugin (docs/behavior-tutorial.md, section 8): the
// profile approach_robot.yaml names bh_approach_plugin.so in its `plugins:`, so `tripodal run`,
// `tripodal describe` and the robot harness all find BhApproach the same way.
#include "bh_approach.hpp"
#include "tripodal/robot/plugin_library.hpp"

TRIPODAL_REGISTER_PLUGINS(plugins) {
  plugins.behaviors.add<example::BhApproach>();
}
