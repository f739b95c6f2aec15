#include "tripodal/hardware/hardware.hpp"

namespace tripodal {

ModuleManifest hardware_manifest(std::string name, std::string description, std::vector<std::string> outputs,
                                 std::vector<ParameterSpec> parameters) {
  return ManifestBuilder(std::move(name), ModuleKind::other, Layer::reactive)
      .description(std::move(description))
      .outputs(std::move(outputs))
      .parameters(std::move(parameters))
      .build();
}

}  // namespace tripodal
