#include "tripodal/navi/navi_modules.hpp"

namespace tripodal::navi {

ModuleManifest navi_manifest(std::string name, std::string description, std::vector<std::string> inputs,
                             std::vector<std::string> outputs, std::vector<ParameterSpec> parameters) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = Layer::sequencing;
  m.kind = ModuleKind::navigation;
  m.description = std::move(description);
  m.inputs = std::move(inputs);
  m.outputs = std::move(outputs);
  m.parameters = std::move(parameters);
  return m;
}

}  // namespace tripodal::navi
