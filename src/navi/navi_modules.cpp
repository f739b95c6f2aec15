#include "tripodal/navi/navi_modules.hpp"

#include <stdexcept>

#include "tripodal/navi/localizer.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal::navi {

void CNaviModules::configure(const ParameterValues& params, const SourceLocation& where) {
  const ParameterSet set = ParameterSet::resolve(manifest(), params, where);
  on_configure(set);
  configured_ = true;
}

void CNaviModules::update(Time now, std::vector<NaviEvent>& out) noexcept {
  if (!configured_) return;
  on_update(now, out);
}

void CNaviModules::on_update(Time /*now*/, std::vector<NaviEvent>& /*out*/) noexcept {}

ModuleManifest navi_manifest(std::string name, std::string description, std::vector<std::string> inputs,
                             std::vector<std::string> outputs, std::vector<ParameterSpec> parameters) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = Layer::sequencing;
  m.kind = ModuleKind::navigation;
  m.description = std::move(description);
  m.inputs = std::move(inputs);
  m.outputs = std::move(outputs);
  m.parameters = std::move(parameters);
  return m;
}

void NaviModuleRegistry::add(const ModuleManifest& manifest, Factory factory) {
  if (entries_.count(manifest.name) != 0) {
    throw std::invalid_argument("navigation module '" + manifest.name + "' is already registered");
  }
  entries_.emplace(manifest.name, Entry{&manifest, std::move(factory)});
}

std::unique_ptr<CNaviModules> NaviModuleRegistry::create(std::string_view name) const {
  const auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : it->second.factory();
}

const ModuleManifest* NaviModuleRegistry::manifest(std::string_view name) const {
  const auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : it->second.manifest;
}

std::vector<std::string> NaviModuleRegistry::names() const {
  std::vector<std::string> out;
  for (const auto& [name, entry] : entries_) out.push_back(name);
  return out;
}

NaviModuleRegistry NaviModuleRegistry::with_builtins() {
  NaviModuleRegistry r;
  r.add(CSectionSplitter::static_manifest(), [] { return std::make_unique<CSectionSplitter>(); });
  r.add(CLocalizer::static_manifest(), [] { return std::make_unique<CLocalizer>(); });
  return r;
}

}  // namespace tripodal::navi
