#include "parameter_sets.hpp"

#include "tripodal/core/registry.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal::net_tool {

std::vector<ParameterSetText> load_parameter_sets(const std::filesystem::path& file) {
  const std::string name = file.string();
  const std::string text = yaml::read_file(file);
  return yaml::guarded(name, [&] {
    const YAML::Node root = yaml::parse(text, name);
    Diagnostics d;
    yaml::Reader r(name, d);
    std::vector<ParameterSetText> sets;
    auto read_set = [&](const YAML::Node& map, const std::string& what) {
      if (!r.expect_map(map, what)) return;
      ParameterSetText set;
      set.where = r.at(map);
      set.origin = set.where.str();
      for (const auto& kv : map) {
        const auto key = r.key(kv.first, what);
        const auto value = r.text(kv.second, what + ": parameter '" + (key ? *key : std::string("?")) + "'");
        if (key && value) set.values[*key] = *value;
      }
      sets.push_back(std::move(set));
    };
    if (root.IsSequence()) {
      for (std::size_t i = 0; i < root.size(); ++i)
        read_set(root[i], "parameter set " + std::to_string(i + 1));
    } else {
      read_set(root, "parameter set");
    }
    if (d.has_errors()) throw ConfigError(std::move(d));
    return sets;
  });
}

std::vector<ProfileNet> profile_nets(const std::filesystem::path& profile, std::vector<std::string>* behaviors) {
  const RobotProfile p = load_robot_profile(profile);
  if (behaviors != nullptr) {
    for (const ModuleEntry& b : p.behaviors) behaviors->push_back(b.name);
  }
  std::vector<ProfileNet> out;
  for (const ProcessEntry& e : p.processes) {
    ParameterSetText set;
    set.origin = profile.filename().string() + ": process " + e.name;
    set.where = e.where;
    for (const BindingParam& b : e.parameters) set.values[b.name] = b.value;
    out.push_back({e.net.lexically_normal(), set, false});
    if (!e.module.empty()) out.push_back({e.module.lexically_normal(), set, true});
  }
  return out;
}

ParameterValues typed_set(const PetriNet& net, const ParameterSetText& set, bool only_declared,
                          Diagnostics& diagnostics) {
  ParameterValues out;
  std::vector<std::string> declared;
  for (const auto& d : net.parameters) declared.push_back(d.name);
  for (const auto& [name, text] : set.values) {
    const VariableDecl* decl = net.find_parameter(name);
    if (decl == nullptr) {
      if (only_declared) continue;
      const auto close = closest_name(name, declared);
      diagnostics.error(set.where, set.origin + ": net '" + net.id + "' declares no parameter '" + name +
                                       "'" + (close ? "; did you mean '" + *close + "'?" : std::string()));
      continue;
    }
    auto value = parse_value(decl->type, text);
    if (!value) {
      diagnostics.error(set.where, set.origin + ": parameter '" + name + "' of net '" + net.id + "' is a " +
                                       std::string(to_string(decl->type)) + ", not '" + text + "'");
      continue;
    }
    out[name] = std::move(*value);
  }
  return out;
}

}  // namespace tripodal::net_tool
