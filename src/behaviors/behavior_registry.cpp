#include "tripodal/behaviors/behavior_registry.hpp"

#include "tripodal/behaviors/gesture_behaviors.hpp"
#include "tripodal/behaviors/navigation_behaviors.hpp"
#include "tripodal/behaviors/safety_behaviors.hpp"

namespace tripodal {

ModuleManifest behavior_manifest(std::string name, std::string description, std::vector<std::string> inputs,
                                 std::vector<ParameterSpec> parameters) {
  return ManifestBuilder(std::move(name), ModuleKind::behavior, Layer::reactive)
      .description(std::move(description))
      .inputs(std::move(inputs))
      .output("behavior_command")
      .parameters(std::move(parameters))
      .build();
}

void register_behaviors(BehaviorRegistry& registry) {
  register_builtin_behaviors(registry);
  register_navigation_behaviors(registry);
  register_gesture_behaviors(registry);
  register_safety_behaviors(registry);
}

}  // namespace tripodal
