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

std::optional<std::string> check_parameter_value(const ParameterSpec& spec, const Value& value) {
  if (type_of(value) != spec.type) {
    return "parameter '" + spec.name + "' expects a " + std::string(to_string(spec.type)) + ", got " + to_string(value);
  }
  if (spec.type != ValueType::number) return std::nullopt;
  const double x = std::get<double>(value);
  const bool below = spec.min && (spec.min_exclusive ? !(x > *spec.min) : !(x >= *spec.min));
  const bool above = spec.max && !(x <= *spec.max);
  if (!below && !above) return std::nullopt;
  const std::string range = (spec.min_exclusive ? "(" : "[") +
                            (spec.min ? to_string(Value{*spec.min}) : std::string("-inf")) + ", " +
                            (spec.max ? to_string(Value{*spec.max}) : std::string("inf")) + "]";
  return "parameter '" + spec.name + "' = " + to_string(value) + (spec.unit.empty() ? "" : " " + spec.unit) +
         " is outside " + range;
}

namespace parameter {

ParameterSpec number(std::string name, std::optional<double> default_value, std::string unit, std::string description,
                     std::optional<double> min, std::optional<double> max) {
  ParameterSpec p;
  p.name = std::move(name);
  p.type = ValueType::number;
  if (default_value) p.default_value = Value{*default_value};
  p.unit = std::move(unit);
  p.description = std::move(description);
  p.min = min;
  p.max = max;
  return p;
}

ParameterSpec positive(std::string name, std::optional<double> default_value, std::string unit, std::string description) {
  ParameterSpec p = number(std::move(name), default_value, std::move(unit), std::move(description), 0.0);
  p.min_exclusive = true;
  return p;
}

ParameterSpec text(std::string name, std::optional<std::string> default_value, std::string description) {
  ParameterSpec p;
  p.name = std::move(name);
  p.type = ValueType::string;
  if (default_value) p.default_value = Value{std::move(*default_value)};
  p.description = std::move(description);
  return p;
}

ParameterSpec flag(std::string name, std::optional<bool> default_value, std::string description) {
  ParameterSpec p;
  p.name = std::move(name);
  p.type = ValueType::boolean;
  if (default_value) p.default_value = Value{*default_value};
  p.description = std::move(description);
  return p;
}

ParameterSpec optional(ParameterSpec spec) {
  spec.default_value.reset();
  spec.optional = true;
  return spec;
}

}  // namespace parameter

ManifestBuilder::ManifestBuilder(std::string name, ModuleKind kind, Layer layer) {
  manifest_.name = std::move(name);
  manifest_.kind = kind;
  manifest_.layer = layer;
}
ManifestBuilder& ManifestBuilder::layer(Layer layer) {
  manifest_.layer = layer;
  return *this;
}
ManifestBuilder& ManifestBuilder::kind(ModuleKind kind) {
  manifest_.kind = kind;
  return *this;
}
ManifestBuilder& ManifestBuilder::description(std::string text) {
  manifest_.description = std::move(text);
  return *this;
}
ManifestBuilder& ManifestBuilder::input(std::string information) {
  manifest_.inputs.push_back(std::move(information));
  return *this;
}
ManifestBuilder& ManifestBuilder::inputs(std::vector<std::string> information) {
  for (auto& i : information) manifest_.inputs.push_back(std::move(i));
  return *this;
}
ManifestBuilder& ManifestBuilder::output(std::string information) {
  manifest_.outputs.push_back(std::move(information));
  return *this;
}
ManifestBuilder& ManifestBuilder::outputs(std::vector<std::string> information) {
  for (auto& o : information) manifest_.outputs.push_back(std::move(o));
  return *this;
}
ManifestBuilder& ManifestBuilder::writes(std::string channel, ChannelType type, std::string description) {
  manifest_.writes.push_back(ChannelWrite{std::move(channel), {}, type, std::move(description)});
  return *this;
}
ManifestBuilder& ManifestBuilder::writes_named_by(std::string parameter, ChannelType type, std::string description) {
  manifest_.writes.push_back(ChannelWrite{{}, std::move(parameter), type, std::move(description)});
  return *this;
}
ManifestBuilder& ManifestBuilder::command_channel(ChannelSpec spec) {
  manifest_.command_channels.push_back(std::move(spec));
  return *this;
}
ManifestBuilder& ManifestBuilder::parameter(ParameterSpec spec) {
  manifest_.parameters.push_back(std::move(spec));
  return *this;
}
ManifestBuilder& ManifestBuilder::parameters(std::vector<ParameterSpec> specs) {
  for (auto& p : specs) manifest_.parameters.push_back(std::move(p));
  return *this;
}
ManifestBuilder& ManifestBuilder::number(std::string name, std::optional<double> default_value, std::string unit,
                                         std::string description, std::optional<double> min, std::optional<double> max) {
  return parameter(tripodal::parameter::number(std::move(name), default_value, std::move(unit), std::move(description), min, max));
}
ManifestBuilder& ManifestBuilder::text(std::string name, std::optional<std::string> default_value, std::string description) {
  return parameter(tripodal::parameter::text(std::move(name), std::move(default_value), std::move(description)));
}
ManifestBuilder& ManifestBuilder::flag(std::string name, std::optional<bool> default_value, std::string description) {
  return parameter(tripodal::parameter::flag(std::move(name), default_value, std::move(description)));
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
      } else if (!spec.optional) {
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
    if (auto problem = check_parameter_value(spec, v)) {
      diags.error(where, manifest.name + ": " + *problem);
      continue;
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
