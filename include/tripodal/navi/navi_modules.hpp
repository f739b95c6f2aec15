// CNaviModules, the base class of the navigation modules (the paper's class; sequencing layer):
// maps, localizers, the path and coverage planners, the section splitter, map builders. A
// navigation module is a CModule (processes/module.hpp) whose manifest says layer sequencing, kind
// navigation; the robot runs it every period of its sequencing loop.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/processes/module.hpp"
#include "tripodal/resources/resource.hpp"

namespace tripodal::navi {

class CNaviModules : public CModule {
 protected:
  CNaviModules() = default;
};

/// When a localizer attempts global position fixes (the process PrGlobalLocalization): while the
/// behavior it serves (BhGlobalLocalization) is active, once every attempt_period_s of that
/// activation. Shared by the localizers.
class GlobalFixAttempts {
 public:
  std::string serves = "BhGlobalLocalization";
  void activated(const BehaviorActivation& activation, Time now);
  void deactivated(std::string_view behavior) noexcept {
    if (behavior == serves) searching_ = false;
  }
  /// Whether an attempt is due at now (then the next one is a period later).
  [[nodiscard]] bool due(Time now) noexcept {
    if (!searching_ || now - last_ < period_) return false;
    last_ = now;
    return true;
  }

 private:
  bool searching_ = false;
  Duration period_{0};
  Time last_{};
};

/// A manifest for a navigation module: layer sequencing, kind navigation.
[[nodiscard]] ModuleManifest navi_manifest(std::string name, std::string description, std::vector<std::string> inputs,
                                           std::vector<std::string> outputs, std::vector<ParameterSpec> parameters);

/// The robot's sensor of type T that a navigation module reads: the resource named `name`, or the
/// first of its type when `name` is empty. Otherwise a ConfigError at `where`: "WHO needs NEEDS,
/// and the robot has no KIND resource" or "WHO: no KIND resource named 'NAME'".
template <class T>
[[nodiscard]] const TypedResource<T>& sensor_of(const ModuleContext& context, const std::string& name, std::string_view who,
                                                std::string_view needs, std::string_view kind, const SourceLocation& where) {
  const TypedResource<T>* r = nullptr;
  if (context.resources != nullptr) r = name.empty() ? context.resources->first<T>() : context.resources->find<T>(name);
  if (r != nullptr) return *r;
  throw ConfigError(where, name.empty() ? std::string(who) + " needs " + std::string(needs) + ", and the robot has no " + std::string(kind) + " resource"
                                        : std::string(who) + ": no " + std::string(kind) + " resource named '" + name + "'");
}

/// Registers the navigation modules: GridMaps, SectionSplitter, Localizer, ScanMatchingLocalizer,
/// MapBuilder, PathPlanner, CoveragePlanner.
void register_navigation_modules(ModuleRegistry& registry);

}  // namespace tripodal::navi
