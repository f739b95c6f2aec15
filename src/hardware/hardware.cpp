#include "tripodal/hardware/hardware.hpp"

namespace tripodal {

ModuleManifest hardware_manifest(std::string name, std::string description, std::vector<std::string> outputs,
                                 std::vector<ParameterSpec> parameters) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = Layer::reactive;
  m.kind = ModuleKind::other;
  m.description = std::move(description);
  m.outputs = std::move(outputs);
  m.parameters = std::move(parameters);
  return m;
}

}  // namespace tripodal
