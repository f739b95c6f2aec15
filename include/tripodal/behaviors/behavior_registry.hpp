// The behavior registry: creates behaviors by their registered type name, as the process
// supervisor does when a Petri-net place binding "BhGoToPose" becomes marked. Applications
// register their own behaviors next to the built-in ones.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/core/manifest.hpp"

namespace tripodal {

/// Factory of behaviors by name. Not thread-safe for registration; creation may run concurrently
/// with other creations once registration is over.
class BehaviorRegistry {
 public:
  using Factory = std::function<std::unique_ptr<CBehavior>()>;

  /// Registers a type under manifest.name. Throws std::invalid_argument for an empty or
  /// already registered name.
  void add(const ModuleManifest& manifest, Factory factory);
  /// Registers `B`, which must provide `static const ModuleManifest& static_manifest()` and a
  /// default constructor.
  template <class B>
  void add() {
    add(B::static_manifest(), [] { return std::unique_ptr<CBehavior>(std::make_unique<B>()); });
  }

  [[nodiscard]] bool contains(std::string_view name) const noexcept;
  /// A new behavior of type `name`. Throws std::out_of_range naming the unknown type and the
  /// registered ones.
  [[nodiscard]] std::unique_ptr<CBehavior> create(std::string_view name) const;
  /// The manifest of `name`; nullptr when not registered.
  [[nodiscard]] const ModuleManifest* manifest(std::string_view name) const noexcept;
  /// Registered names in alphabetical order.
  [[nodiscard]] std::vector<std::string> names() const;

 private:
  struct Entry {
    const ModuleManifest* manifest;
    Factory factory;
  };
  std::map<std::string, Entry, std::less<>> entries_;
};

/// Adds the built-in behaviors (BhStop, BhRotateInPlace, BhGoToPose, BhBackOff,
/// BhAvoidObstacle) to `registry`.
void register_builtin_behaviors(BehaviorRegistry& registry);

/// A process-wide registry holding the built-in behaviors, created on first use.
[[nodiscard]] BehaviorRegistry& default_behavior_registry();

}  // namespace tripodal
