#include "tripodal/core/manifest.hpp"

#include <stdexcept>

namespace tripodal {

std::string_view to_string(Layer layer) noexcept {
  switch (layer) {
    case Layer::deliberate: return "deliberate";
    case Layer::sequencing: return "sequencing";
    case Layer::reactive: return "reactive";
  }
  return "?";
}

std::string_view to_string(ModuleKind kind) noexcept {
  switch (kind) {
    case ModuleKind::behavior: return "behavior";
    case ModuleKind::resource: return "resource";
    case ModuleKind::controller: return "controller";
    case ModuleKind::process: return "process";
    case ModuleKind::navigation: return "navigation";
    case ModuleKind::planner: return "planner";
    case ModuleKind::hri: return "hri";
    case ModuleKind::other: return "other";
  }
  return "?";
}

std::optional<Layer> parse_layer(std::string_view text) noexcept {
  if (text == "deliberate") return Layer::deliberate;
  if (text == "sequencing") return Layer::sequencing;
  if (text == "reactive") return Layer::reactive;
  return std::nullopt;
}

const ParameterSpec* ModuleManifest::find_parameter(std::string_view parameter) const noexcept {
  for (const auto& p : parameters) {
    if (p.name == parameter) return &p;
  }
  return nullptr;
}

ParameterSet ParameterSet::resolve(const ModuleManifest& manifest, const ParameterValues& given,
                                   const SourceLocation& where) {
  Diagnostics diags;
  ParameterSet out;
  for (const auto& [name, value] : given) {
    if (manifest.find_parameter(name) == nullptr) {
      std::string known;
      for (const auto& p : manifest.parameters) known += (known.empty() ? "" : ", ") + p.name;
      diags.error(where, manifest.name + ": unknown parameter '" + name + "' (expected one of: " +
                             (known.empty() ? std::string("none") : known) + ")");
    }
  }
  for (const auto& spec : manifest.parameters) {
    auto it = given.find(spec.name);
    if (it == given.end()) {
      if (spec.default_value) {
        out.values_.emplace(spec.name, *spec.default_value);
      } else {
        diags.error(where, manifest.name + ": missing required parameter '" + spec.name + "' (" +
                               std::string(to_string(spec.type)) + ")");
      }
      continue;
    }
    Value v = it->second;
    // Net bindings carry text: a string that parses as the declared type is accepted.
    if (type_of(v) != spec.type && type_of(v) == ValueType::string) {
      if (auto parsed = parse_value(spec.type, std::get<std::string>(v))) v = *parsed;
    }
    if (type_of(v) != spec.type) {
      diags.error(where, manifest.name + ": parameter '" + spec.name + "' expects a " +
                             std::string(to_string(spec.type)) + ", got " + to_string(it->second));
      continue;
    }
    if (spec.type == ValueType::number) {
      const double x = std::get<double>(v);
      if ((spec.min && x < *spec.min) || (spec.max && x > *spec.max)) {
        std::string range = "[" + (spec.min ? to_string(Value{*spec.min}) : std::string("-inf")) + ", " +
                            (spec.max ? to_string(Value{*spec.max}) : std::string("inf")) + "]";
        diags.error(where, manifest.name + ": parameter '" + spec.name + "' = " + to_string(v) +
                               (spec.unit.empty() ? "" : " " + spec.unit) + " is outside " + range);
        continue;
      }
    }
    out.values_.emplace(spec.name, std::move(v));
  }
  if (diags.has_errors()) throw ConfigError(std::move(diags));
  return out;
}

const Value& ParameterSet::value(std::string_view name) const {
  auto it = values_.find(name);
  if (it == values_.end()) throw std::out_of_range("no parameter '" + std::string(name) + "'");
  return it->second;
}
double ParameterSet::number(std::string_view name) const { return std::get<double>(value(name)); }
bool ParameterSet::boolean(std::string_view name) const { return std::get<bool>(value(name)); }
const std::string& ParameterSet::string(std::string_view name) const {
  return std::get<std::string>(value(name));
}
bool ParameterSet::contains(std::string_view name) const noexcept { return values_.find(name) != values_.end(); }

}  // namespace tripodal
