// The process registry of the sequencing layer: the process modules a robot may run
// (PrCleaning, PrAutoMove, PrGlobalLocalization, ...), built from configuration by named factories
// so that application code adds its own CProcess types; the planner looks them up by name.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tripodal/processes/process.hpp"

namespace tripodal {

class ProcessRegistry {
 public:
  using Factory = std::function<std::unique_ptr<CProcess>(ProcessDefinition)>;

  /// A registry that knows the factory type "net" (a plain CProcess).
  ProcessRegistry();

  /// Registers a factory under `type`; throws std::invalid_argument when the type exists.
  void register_type(std::string type, Factory factory);
  /// Registers `P`, a CProcess subclass constructed from its definition, under `type`.
  template <class P>
  void register_type(std::string type) {
    register_type(std::move(type), [](ProcessDefinition d) { return std::unique_ptr<CProcess>(std::make_unique<P>(std::move(d))); });
  }
  [[nodiscard]] bool has_type(std::string_view type) const noexcept;

  /// Builds the process with the factory its definition names and keeps it. Throws ConfigError
  /// (at definition.where) for a duplicate name or an unknown type, and whatever the factory and
  /// CProcess's checks throw.
  const CProcess& add(ProcessDefinition definition);

  [[nodiscard]] const CProcess* find(std::string_view name) const noexcept;
  [[nodiscard]] bool contains(std::string_view name) const noexcept { return find(name) != nullptr; }
  /// Names in alphabetical order.
  [[nodiscard]] std::vector<std::string> names() const;
  [[nodiscard]] std::size_t size() const noexcept { return processes_.size(); }

 private:
  std::map<std::string, Factory, std::less<>> factories_;
  std::map<std::string, std::unique_ptr<CProcess>, std::less<>> processes_;
};

}  // namespace tripodal
