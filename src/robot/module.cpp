#include "tripodal/robot/module.hpp"

#include <stdexcept>

namespace tripodal {

void ModulePort::post_event(std::string event) const {
  if (supervisor_) supervisor_->post_event(std::move(event));
}
void ModulePort::heartbeat() const {
  if (supervisor_) supervisor_->heartbeat(module_);
}
void ModulePort::report_fault(std::string reason) const {
  if (supervisor_) supervisor_->report_module_fault(module_, std::move(reason));
}
void ModulePort::set_fact(std::string name, Value value) const {
  if (supervisor_) supervisor_->set_fact(std::move(name), std::move(value));
}

void ModuleRegistry::add(ModuleManifest manifest, Factory factory) {
  if (manifest.name.empty()) throw std::invalid_argument("module type without a name");
  std::string name = manifest.name;
  if (!entries_.emplace(name, Entry{std::move(manifest), std::move(factory)}).second) {
    throw std::invalid_argument("module type '" + name + "' is already registered");
  }
}

bool ModuleRegistry::contains(std::string_view type) const noexcept { return entries_.find(type) != entries_.end(); }

const ModuleManifest* ModuleRegistry::manifest(std::string_view type) const noexcept {
  auto it = entries_.find(type);
  return it == entries_.end() ? nullptr : &it->second.manifest;
}

bool ModuleRegistry::can_create(std::string_view type) const noexcept {
  auto it = entries_.find(type);
  return it != entries_.end() && static_cast<bool>(it->second.factory);
}

std::unique_ptr<RobotModule> ModuleRegistry::create(const ModuleConfig& config) const {
  auto it = entries_.find(config.type);
  if (it == entries_.end()) throw ConfigError(config.where, "module '" + config.name + "': unknown module type '" + config.type + "'");
  if (!it->second.factory) {
    throw ConfigError(config.where, "module '" + config.name + "': type '" + config.type +
                                        "' is declared but no factory is registered, so it cannot be started");
  }
  auto m = it->second.factory(config);
  if (!m) throw ConfigError(config.where, "module '" + config.name + "': the factory of '" + config.type + "' built nothing");
  return m;
}

std::vector<std::string> ModuleRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : entries_) out.push_back(k);
  return out;
}

}  // namespace tripodal
