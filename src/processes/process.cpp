#include "tripodal/processes/process.hpp"

#include <algorithm>
#include <set>

#include "tripodal/core/registry.hpp"

namespace tripodal {

namespace {

const VariableDecl* declared(const PetriNet& net, std::string_view name) { return net.find_parameter(name); }

}  // namespace

CProcess::CProcess(ProcessDefinition definition) : definition_(std::move(definition)) {
  Diagnostics d;
  const PetriNet& net = definition_.net;
  const SourceLocation& at = definition_.where;
  if (definition_.name.empty()) d.error(at, "a process needs a name");
  if (net.level == NetLevel::high) {
    d.error(at, "process '" + definition_.name + "': net '" + net.id +
                    "' is a high-level net; a process runs a low-level net of behaviors");
  }
  const bool has_outcome = std::any_of(net.places().begin(), net.places().end(),
                                       [](const Place& p) { return p.outcome != Outcome::none; });
  if (!has_outcome) {
    d.error(at, "process '" + definition_.name + "': net '" + net.id +
                    "' has no outcome place, so its result (success or fault) could never be reported");
  }
  for (const BindingParam& p : definition_.parameters) {
    const VariableDecl* decl = declared(net, p.name);
    const SourceLocation& loc = p.where.line > 0 ? p.where : at;
    if (decl == nullptr) {
      std::string known;
      for (const auto& v : net.parameters) known += (known.empty() ? "" : ", ") + v.name;
      std::vector<std::string> names;
      for (const auto& v : net.parameters) names.push_back(v.name);
      const auto close = closest_name(p.name, names);
      d.error(loc, "process '" + definition_.name + "': parameter '" + p.name + "' is not declared by net '" + net.id +
                       "' (declared: " + (known.empty() ? "none" : known) + ")" +
                       (close ? "; did you mean '" + *close + "'?" : std::string()));
    } else if (!parse_value(decl->type, p.value)) {
      d.error(loc, "process '" + definition_.name + "': parameter '" + p.name + "' expects a " +
                       std::string(to_string(decl->type)) + ", got '" + p.value + "'");
    }
  }
  for (const Place& place : net.places()) {
    if (!place.behavior) continue;
    for (const BindingParam& bp : place.behavior->params) {
      if (bp.value.size() > 1 && bp.value[0] == '$' && declared(net, std::string_view(bp.value).substr(1)) == nullptr) {
        d.error(bp.where.line > 0 ? bp.where : (place.where.line > 0 ? place.where : at),
                "process '" + definition_.name + "': place '" + place.id + "' passes " + bp.value + " to " +
                    place.behavior->behavior + ", but the net declares no parameter '" + bp.value.substr(1) + "'");
      }
    }
  }
  if (d.has_errors()) throw ConfigError(d);

  ManifestBuilder b(definition_.name, ModuleKind::process, Layer::sequencing);
  std::string bound;
  for (const auto& behavior : behaviors()) bound += (bound.empty() ? "" : ", ") + behavior;
  b.description("process module of low-level net '" + net.id + "'" + (bound.empty() ? "" : ", binding " + bound));
  for (const VariableDecl& v : net.parameters) {
    ParameterSpec spec;
    spec.name = v.name;
    spec.type = v.type;
    spec.default_value = v.default_value;
    spec.description = v.description;
    b.parameter(std::move(spec));
  }
  manifest_ = std::move(b).build();
}

const ModuleManifest& CProcess::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("net", ModuleKind::process, Layer::sequencing)
          .description("a process given entirely by configuration: its low-level net, parameters and recovery rules")
          .build();
  return m;
}

std::vector<std::string> CProcess::behaviors() const {
  std::set<std::string> names;
  for (const Place& p : definition_.net.places()) {
    if (p.behavior) names.insert(p.behavior->behavior);
  }
  return {names.begin(), names.end()};
}

std::string CProcess::on_bind(ParameterValues& /*values*/) const { return {}; }

BoundParameters CProcess::bind(const std::vector<BindingParam>& step) const {
  BoundParameters out;
  const PetriNet& net = definition_.net;
  for (const VariableDecl& v : net.parameters) {
    if (v.default_value) out.values[v.name] = *v.default_value;
  }
  auto apply = [&](const BindingParam& p) -> bool {
    const VariableDecl* decl = declared(net, p.name);
    if (decl == nullptr) {
      out.error = name() + ": parameter '" + p.name + "' is not declared by its net";
      return false;
    }
    auto v = parse_value(decl->type, p.value);
    if (!v) {
      out.error = name() + ": parameter '" + p.name + "' expects a " + std::string(to_string(decl->type)) +
                  ", got '" + p.value + "'";
      return false;
    }
    out.values[p.name] = std::move(*v);
    return true;
  };
  for (const BindingParam& p : definition_.parameters) {
    if (!apply(p)) return out;
  }
  for (const BindingParam& p : step) {
    if (!apply(p)) return out;
  }
  for (const VariableDecl& v : net.parameters) {
    if (out.values.find(v.name) == out.values.end()) {
      out.error = name() + ": parameter '" + v.name + "' is required";
      return out;
    }
  }
  try {
    out.error = on_bind(out.values);
  } catch (const std::exception& e) {
    out.error = name() + ": " + e.what();
  }
  out.ok = out.error.empty();
  return out;
}

bool resolve_binding_params(const std::vector<BindingParam>& params, const ParameterValues& run,
                            ParameterValues& out, std::string& error) {
  out.clear();
  for (const BindingParam& p : params) {
    if (p.value.size() > 1 && p.value[0] == '$') {
      auto it = run.find(std::string_view(p.value).substr(1));
      if (it == run.end()) {
        error = "parameter '" + p.name + "' refers to " + p.value + ", which the process does not have";
        return false;
      }
      out[p.name] = it->second;
    } else {
      out[p.name] = Value{p.value};
    }
  }
  return true;
}

}  // namespace tripodal
