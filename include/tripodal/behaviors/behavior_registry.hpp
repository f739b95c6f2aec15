// The behavior registry: creates behaviors by their registered type name, as the process
// supervisor does when a Petri-net place binding "BhGoToPose" becomes marked. Applications
// register their own behaviors next to the built-in ones; it is the plugin Registry of
// core/registry.hpp for the CBehavior family.
#pragma once

#include <string>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/registry.hpp"

namespace tripodal {

/// Behavior types by name; a type B registers with add<B>() (B::static_manifest() and a default
/// constructor). An unknown name is a ConfigError "unknown behavior type '...'; known: ...".
class BehaviorRegistry : public Registry<CBehavior> {
 public:
  BehaviorRegistry() : Registry("behavior type") {}
};

/// The manifest of a behavior type: reactive layer, kind behavior, output "behavior_command".
[[nodiscard]] ModuleManifest behavior_manifest(std::string name, std::string description,
                                               std::vector<std::string> inputs, std::vector<ParameterSpec> parameters);

/// Adds the built-in behaviors (BhStop, BhRotateInPlace, BhGoToPose, BhBackOff,
/// BhAvoidObstacle) to `registry`.
void register_builtin_behaviors(BehaviorRegistry& registry);

/// The behaviors area's types: register_builtin_behaviors, register_navigation_behaviors
/// (navigation_behaviors.hpp) and register_gesture_behaviors (gesture_behaviors.hpp). An
/// application's plugin set gets them from register_all (builtin/register_all.hpp).
void register_behaviors(BehaviorRegistry& registry);

}  // namespace tripodal
