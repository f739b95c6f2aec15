// A test plugin that registers a name the host already has (the built-in behavior BhStop) next to
// a fresh one: the host refuses it and keeps neither.
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/robot/plugin_library.hpp"

TRIPODAL_REGISTER_PLUGINS(plugins) {
  const auto make = [] { return std::unique_ptr<tripodal::CBehavior>(std::make_unique<tripodal::BhStop>()); };
  tripodal::ModuleManifest fresh = tripodal::BhStop::static_manifest();
  fresh.name = "BhFresh";
  plugins.behaviors.add(fresh, make);
  plugins.behaviors.add(tripodal::BhStop::static_manifest(), make);
}
