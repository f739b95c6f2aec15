// Internal: the manifest parameters every controller type shares.
#pragma once

#include "tripodal/core/manifest.hpp"

namespace tripodal::detail {

ModuleManifest controller_manifest(std::string name, std::string description,
                                   std::vector<ParameterSpec> specific);

}  // namespace tripodal::detail
