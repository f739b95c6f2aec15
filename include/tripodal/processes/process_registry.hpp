// The process registry of the sequencing layer: the process modules a robot may run
// (PrCleaning, PrAutoMove, PrGlobalLocalization, ...), built from configuration by registered
// process types so that application code adds its own CProcess types; the planner looks them up
// by name.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/registry.hpp"
#include "tripodal/processes/process.hpp"

namespace tripodal {

/// Process types by name: the plugin Registry of the CProcess family, each type building a process
/// from its definition. "net" (a plain CProcess, entirely configuration) is always registered; an
/// application adds its CProcess subclasses with add<T>() (T::static_manifest() and a constructor
/// T(ProcessDefinition)).
class ProcessTypeRegistry : public Registry<CProcess, ProcessDefinition> {
 public:
  ProcessTypeRegistry();
};

/// The processes a robot is configured with, by name, each built by the type its definition names.
class ProcessRegistry {
 public:
  /// A registry that builds its processes with `types` ("net" and whatever was added to them).
  explicit ProcessRegistry(ProcessTypeRegistry types = {}) : types_(std::move(types)) {}

  [[nodiscard]] ProcessTypeRegistry& types() noexcept { return types_; }
  [[nodiscard]] const ProcessTypeRegistry& types() const noexcept { return types_; }

  /// Builds the process with the type its definition names and keeps it. Throws ConfigError
  /// (at definition.where) for a duplicate name or an unknown type, and whatever the type's
  /// constructor and CProcess's checks throw.
  const CProcess& add(ProcessDefinition definition);

  [[nodiscard]] const CProcess* find(std::string_view name) const noexcept;
  [[nodiscard]] bool contains(std::string_view name) const noexcept { return find(name) != nullptr; }
  /// Names in alphabetical order.
  [[nodiscard]] std::vector<std::string> names() const;
  [[nodiscard]] std::size_t size() const noexcept { return processes_.size(); }

 private:
  ProcessTypeRegistry types_;
  std::map<std::string, std::unique_ptr<CProcess>, std::less<>> processes_;
};

}  // namespace tripodal
