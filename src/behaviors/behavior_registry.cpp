#include "tripodal/behaviors/behavior_registry.hpp"

#include <stdexcept>

namespace tripodal {

void BehaviorRegistry::add(const ModuleManifest& manifest, Factory factory) {
  if (manifest.name.empty()) throw std::invalid_argument("a behavior needs a name");
  if (!factory) throw std::invalid_argument("behavior '" + manifest.name + "' has no factory");
  if (!entries_.emplace(manifest.name, Entry{&manifest, std::move(factory)}).second) {
    throw std::invalid_argument("behavior '" + manifest.name + "' is already registered");
  }
}

bool BehaviorRegistry::contains(std::string_view name) const noexcept { return entries_.find(name) != entries_.end(); }

std::unique_ptr<CBehavior> BehaviorRegistry::create(std::string_view name) const {
  auto it = entries_.find(name);
  if (it == entries_.end()) {
    std::string known;
    for (const auto& [n, e] : entries_) known += (known.empty() ? "" : ", ") + n;
    throw std::out_of_range("unknown behavior '" + std::string(name) + "' (registered: " + known + ")");
  }
  return it->second.factory();
}

const ModuleManifest* BehaviorRegistry::manifest(std::string_view name) const noexcept {
  auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : it->second.manifest;
}

std::vector<std::string> BehaviorRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [n, e] : entries_) out.push_back(n);
  return out;
}

BehaviorRegistry& default_behavior_registry() {
  static BehaviorRegistry registry = [] {
    BehaviorRegistry r;
    register_builtin_behaviors(r);
    return r;
  }();
  return registry;
}

}  // namespace tripodal
