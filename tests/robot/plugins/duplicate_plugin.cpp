// A test plugin that registers one name twice: its registration throws, the host refuses it whole.
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/robot/plugin_library.hpp"

TRIPODAL_REGISTER_PLUGINS(plugins) {
  tripodal::ModuleManifest m = tripodal::BhStop::static_manifest();
  m.name = "BhTwice";
  const auto make = [] { return std::unique_ptr<tripodal::CBehavior>(std::make_unique<tripodal::BhStop>()); };
  plugins.behaviors.add(m, make);
  plugins.behaviors.add(m, make);
}
