#include "tripodal/processes/process_registry.hpp"

namespace tripodal {

ProcessTypeRegistry::ProcessTypeRegistry() : Registry("process type") { add<CProcess>(); }

const CProcess& ProcessRegistry::add(ProcessDefinition definition) {
  if (processes_.find(definition.name) != processes_.end()) {
    throw ConfigError(definition.where, "process '" + definition.name + "' is defined twice");
  }
  // Copies: the definition moves into the factory while these are still in use.
  const std::string name = definition.name;
  const std::string type = definition.type;
  const SourceLocation where = definition.where;
  std::unique_ptr<CProcess> p = types_.create_at(where, type, std::move(definition));
  const CProcess& ref = *p;
  processes_.emplace(name, std::move(p));
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
