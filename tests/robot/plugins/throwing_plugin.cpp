// A test plugin whose registration throws after it registered a type: the host refuses it with
// the exception's message and keeps nothing of it.
#include <stdexcept>

#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/robot/plugin_library.hpp"

TRIPODAL_REGISTER_PLUGINS(plugins) {
  tripodal::ModuleManifest m = tripodal::BhStop::static_manifest();
  m.name = "BhBeforeThrow";
  plugins.behaviors.add(m, [] { return std::unique_ptr<tripodal::CBehavior>(std::make_unique<tripodal::BhStop>()); });
  throw std::runtime_error("the licence file /etc/waver.lic is missing");
}
