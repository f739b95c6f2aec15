// CNaviModules, the base class of the navigation modules (the paper's class; sequencing layer):
// maps, localizers, the path and coverage planners, the section splitter, map builders. A
// navigation module is a CModule (processes/module.hpp) whose manifest says layer sequencing, kind
// navigation; the robot runs it every period of its sequencing loop.
#pragma once

#include <string>
#include <vector>

#include "tripodal/core/manifest.hpp"
#include "tripodal/processes/module.hpp"

namespace tripodal::navi {

class CNaviModules : public CModule {
 protected:
  CNaviModules() = default;
};

/// A manifest for a navigation module: layer sequencing, kind navigation.
[[nodiscard]] ModuleManifest navi_manifest(std::string name, std::string description, std::vector<std::string> inputs,
                                           std::vector<std::string> outputs, std::vector<ParameterSpec> parameters);

/// Registers the navigation modules: GridMaps, SectionSplitter, Localizer, ScanMatchingLocalizer,
/// PathPlanner, CoveragePlanner.
void register_navigation_modules(ModuleRegistry& registry);

}  // namespace tripodal::navi
