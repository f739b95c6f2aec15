#include "tripodal/processes/process_registry.hpp"

#include <stdexcept>

namespace tripodal {

ProcessRegistry::ProcessRegistry() {
  factories_["net"] = [](ProcessDefinition d) { return std::make_unique<CProcess>(std::move(d)); };
}

void ProcessRegistry::register_type(std::string type, Factory factory) {
  if (!factory) throw std::invalid_argument("process type '" + type + "': empty factory");
  if (!factories_.emplace(type, std::move(factory)).second) {
    throw std::invalid_argument("process type '" + type + "' is already registered");
  }
}

bool ProcessRegistry::has_type(std::string_view type) const noexcept { return factories_.find(type) != factories_.end(); }

const CProcess& ProcessRegistry::add(ProcessDefinition definition) {
  if (processes_.find(definition.name) != processes_.end()) {
    throw ConfigError(definition.where, "process '" + definition.name + "' is defined twice");
  }
  auto f = factories_.find(definition.type);
  if (f == factories_.end()) {
    std::string known;
    for (const auto& [k, v] : factories_) known += (known.empty() ? "" : ", ") + k;
    throw ConfigError(definition.where, "process '" + definition.name + "': unknown process type '" + definition.type +
                                            "' (registered: " + known + ")");
  }
  std::string name = definition.name;
  std::unique_ptr<CProcess> p = f->second(std::move(definition));
  if (!p) throw std::logic_error("process factory returned no process for '" + name + "'");
  const CProcess& ref = *p;
  processes_.emplace(std::move(name), std::move(p));
  return ref;
}

const CProcess* ProcessRegistry::find(std::string_view name) const noexcept {
  auto it = processes_.find(name);
  return it == processes_.end() ? nullptr : it->second.get();
}

std::vector<std::string> ProcessRegistry::names() const {
  std::vector<std::string> out;
  out.reserve(processes_.size());
  for (const auto& [k, v] : processes_) out.push_back(k);
  return out;
}

}  // namespace tripodal
