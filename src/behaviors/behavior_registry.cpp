#include "tripodal/behaviors/behavior_registry.hpp"

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

BehaviorRegistry& default_behavior_registry() {
  static BehaviorRegistry registry = [] {
    BehaviorRegistry r;
    register_builtin_behaviors(r);
    return r;
  }();
  return registry;
}

}  // namespace tripodal
