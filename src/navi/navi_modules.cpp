#include "tripodal/navi/navi_modules.hpp"

#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/navi/mapping_module.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/navi/scan_matching_localizer.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal::navi {

ModuleManifest navi_manifest(std::string name, std::string description, std::vector<std::string> inputs,
                             std::vector<std::string> outputs, std::vector<ParameterSpec> parameters) {
  return ManifestBuilder(std::move(name), ModuleKind::navigation, Layer::sequencing)
      .description(std::move(description))
      .inputs(std::move(inputs))
      .outputs(std::move(outputs))
      .parameters(std::move(parameters))
      .build();
}

void GlobalFixAttempts::activated(const BehaviorActivation& activation, Time now) {
  if (activation.behavior != serves) return;
  const ParameterSet params = activation.resolved();
  period_ = from_seconds(params.number("attempt_period_s"));
  last_ = now;
  searching_ = true;
}

void register_navigation_modules(ModuleRegistry& registry) {
  registry.add<CGridMaps>();
  registry.add<CSectionSplitter>();
  registry.add<CGroundTruthLocalizer>();
  registry.add<CScanMatchingLocalizer>();
  registry.add<CMapBuilder>();
  registry.add<CPathPlanner>();
  registry.add<CCoveragePlanner>();
}

}  // namespace tripodal::navi
