#include "tripodal/reactive/reactive_config.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <numbers>
#include <set>
#include <sstream>

#include "tripodal/core/value.hpp"
#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal {

const ControllerConfig* ReactiveConfig::find_controller(std::string_view name) const noexcept {
  for (const auto& c : controllers) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

const LoopConfig* ReactiveConfig::find_loop(std::string_view name) const noexcept {
  for (const auto& l : loops) {
    if (l.name == name) return &l;
  }
  return nullptr;
}

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

enum class Bound { any, positive, non_negative };

// Reads typed values out of yaml-cpp nodes, collecting located diagnostics: the shared
// yaml::Reader for the structure, and the bounds of controller and loop parameters.
class Reader {
 public:
  Reader(std::string file, Diagnostics& diags) : r_(std::move(file), diags) {}

  SourceLocation at(const YAML::Node& node) const { return r_.at(node); }
  void error(const YAML::Node& node, std::string message) { r_.error(node, std::move(message)); }

  bool is_map(const YAML::Node& node, const std::string& what) { return r_.expect_map(node, what); }

  // Reports keys of `map` not in `allowed`, at the key itself.
  void check_keys(const YAML::Node& map, yaml::KeyList allowed, const std::string& what) {
    r_.expect_keys(map, allowed, what);
  }

  std::optional<double> number(const YAML::Node& map, const std::string& key, bool required, Bound bound,
                               const std::string& what) {
    const YAML::Node v = map[key];
    if (!v) {
      if (required) error(map, what + ": missing '" + key + "' (a number)");
      return std::nullopt;
    }
    std::optional<Value> parsed = v.IsScalar() ? parse_value(ValueType::number, v.Scalar()) : std::nullopt;
    if (!parsed) {
      error(v, what + ": '" + key + "' must be a number, got " + (v.IsScalar() ? "'" + v.Scalar() + "'" : std::string("a non-scalar")));
      return std::nullopt;
    }
    const double x = std::get<double>(*parsed);
    if (bound == Bound::positive && !(x > 0.0)) {
      error(v, what + ": '" + key + "' must be > 0, got " + v.Scalar());
      return std::nullopt;
    }
    if (bound == Bound::non_negative && !(x >= 0.0)) {
      error(v, what + ": '" + key + "' must be >= 0, got " + v.Scalar());
      return std::nullopt;
    }
    return x;
  }

  std::optional<std::string> text(const YAML::Node& map, const std::string& key, bool required, const std::string& what) {
    const YAML::Node v = map[key];
    if (!v) {
      if (required) error(map, what + ": missing '" + key + "'");
      return std::nullopt;
    }
    if (!v.IsScalar()) {
      error(v, what + ": '" + key + "' must be a string");
      return std::nullopt;
    }
    return v.Scalar();
  }

  std::optional<int> integer(const YAML::Node& map, const std::string& key, int lo, int hi, const std::string& what) {
    const std::optional<double> x = number(map, key, false, Bound::any, what);
    if (!x) return std::nullopt;
    if (*x != std::floor(*x) || *x < lo || *x > hi) {
      error(map[key], what + ": '" + key + "' must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                          "], got " + map[key].Scalar());
      return std::nullopt;
    }
    return static_cast<int>(*x);
  }

 private:
  yaml::Reader r_;
};

// The omni wheel lists: read by the omni geometry code below, since a manifest parameter is a
// scalar (the manifest declares them for the allowed keys and the documentation).
bool is_wheel_list(std::string_view key) noexcept { return key == "wheel_angles_deg" || key == "wheels"; }

// Reports the keys of `map` that no parameter of `manifest` under `prefix` names, at the key,
// listing the allowed ones; recurses into the maps of dotted names ("limits" -> "limits.vx").
void check_parameter_keys(Reader& r, const YAML::Node& map, const ModuleManifest& manifest, const std::string& prefix,
                          const std::string& entry, bool& ok) {
  const std::string what = prefix.empty() ? entry : entry + " " + prefix.substr(0, prefix.size() - 1);
  std::vector<std::string> allowed;
  if (prefix.empty()) allowed = {"name", "type"};
  for (const auto& spec : manifest.parameters) {
    if (spec.name.compare(0, prefix.size(), prefix) != 0) continue;
    std::string key = spec.name.substr(prefix.size(), spec.name.find('.', prefix.size()) - prefix.size());
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) allowed.push_back(std::move(key));
  }
  for (const auto& kv : map) {
    const std::string key = kv.first.Scalar();
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      const auto suggestion = closest_name(key, allowed);
      r.error(kv.first, "unknown key '" + key + "' in " + what + "; expected one of: " + list +
                            (suggestion ? "; did you mean '" + *suggestion + "'?" : std::string()));
      ok = false;
    } else if (manifest.find_parameter(prefix + key) == nullptr && !(prefix.empty() && (key == "name" || key == "type"))) {
      const std::string group = prefix + key;  // the map of some dotted names
      if (!r.is_map(kv.second, entry + " " + group)) {
        ok = false;
      } else {
        check_parameter_keys(r, kv.second, manifest, group + ".", entry, ok);
      }
    }
  }
}

// The controller's parameters as its type's manifest declares them, each checked at its value;
// nullopt when any problem was reported.
std::optional<ParameterSet> read_parameters(Reader& r, const YAML::Node& node, const ModuleManifest& manifest,
                                            const std::string& what) {
  bool ok = true;
  check_parameter_keys(r, node, manifest, "", what, ok);
  ParameterValues given;
  for (const auto& spec : manifest.parameters) {
    if (is_wheel_list(spec.name)) continue;
    // A dotted name is a path through nested maps; a missing map is a missing value. (YAML::Node
    // assignment writes into the document: the walk rebinds with reset() and looks up const.)
    YAML::Node v(node);
    bool found = true;
    for (std::size_t from = 0; found;) {
      const std::size_t dot = spec.name.find('.', from);
      const std::string key = spec.name.substr(from, dot - from);
      const YAML::Node& map = v;
      found = map.IsMap() && map[key];
      if (found) v.reset(map[key]);
      if (dot == std::string::npos) break;
      from = dot + 1;
    }
    if (!found) {
      if (!spec.default_value && !spec.optional) {
        r.error(node, what + ": missing '" + spec.name + "' (a " + std::string(to_string(spec.type)) + ")");
        ok = false;
      }
      continue;
    }
    if (!v.IsScalar()) {
      r.error(v, what + ": parameter '" + spec.name + "' expects a " + std::string(to_string(spec.type)) +
                     (v.IsSequence() ? ", got a list" : ", got a map"));
      ok = false;
      continue;
    }
    Value value{v.Scalar()};
    if (auto parsed = parse_value(spec.type, v.Scalar())) value = *parsed;
    if (auto problem = check_parameter_value(spec, value)) {
      r.error(v, what + ": " + *problem);
      ok = false;
      continue;
    }
    given.emplace(spec.name, std::move(value));
  }
  if (!ok) return std::nullopt;
  return ParameterSet::resolve(manifest, given, r.at(node));
}

ControllerConfig read_controller(Reader& r, const YAML::Node& node, std::size_t index, const ControllerRegistry& registry) {
  ControllerConfig c;
  c.where = r.at(node);
  std::string what = "controller #" + std::to_string(index + 1);
  if (!r.is_map(node, what)) return c;
  if (auto n = r.text(node, "name", true, what)) {
    c.name = *n;
    what = "controller '" + c.name + "'";
  }
  const ModuleManifest* manifest = nullptr;
  if (auto t = r.text(node, "type", true, what)) {
    c.type = *t;
    manifest = registry.find(c.type);
    if (manifest == nullptr) r.error(node["type"], what + ": " + unknown_name_message(registry.kind(), c.type, registry.names()));
  }
  if (manifest == nullptr) return c;
  if (auto parameters = read_parameters(r, node, *manifest, what)) {
    c.parameters = std::move(*parameters);
    apply_parameters(c);
  }

  if (c.type == "omni") {
    const YAML::Node angles = node["wheel_angles_deg"];
    const YAML::Node wheels = node["wheels"];
    if (angles && wheels) {
      r.error(wheels, what + ": give either 'wheel_angles_deg' (with 'base_radius_m') or 'wheels', not both");
    } else if (angles) {
      std::optional<double> base;
      if (c.parameters.contains("base_radius_m")) {
        base = c.parameters.number("base_radius_m");
      } else if (!node["base_radius_m"]) {
        r.error(node, what + ": missing 'base_radius_m' (a number)");
      }
      std::vector<double> a;
      if (!angles.IsSequence()) {
        r.error(angles, what + ": 'wheel_angles_deg' must be a list of angles in degrees");
      } else {
        for (const auto& e : angles) {
          auto v = e.IsScalar() ? parse_value(ValueType::number, e.Scalar()) : std::nullopt;
          if (!v) {
            r.error(e, what + ": a wheel angle must be a number (degrees)");
          } else {
            a.push_back(std::get<double>(*v) * kDeg);
          }
        }
        if (angles.size() < 3 || angles.size() > HolonomicConfig::kMaxWheels) {
          r.error(angles, what + ": an omni base needs 3 to " + std::to_string(HolonomicConfig::kMaxWheels) +
                              " wheels, got " + std::to_string(angles.size()));
        }
      }
      if (base) {
        const double radius = c.holonomic.wheel_radius_m;
        c.holonomic = omni_base(radius, *base, a);
      }
    } else if (wheels) {
      if (!wheels.IsSequence()) {
        r.error(wheels, what + ": 'wheels' must be a list of {x_m, y_m, drive_angle_deg, roller_angle_deg}");
      } else {
        std::size_t i = 0;
        for (const auto& w : wheels) {
          const std::string ww = what + " wheel #" + std::to_string(++i);
          if (!r.is_map(w, ww)) continue;
          r.check_keys(w, {"x_m", "y_m", "drive_angle_deg", "roller_angle_deg"}, ww);
          OmniWheelConfig wc;
          wc.x_m = r.number(w, "x_m", true, Bound::any, ww).value_or(0.0);
          wc.y_m = r.number(w, "y_m", true, Bound::any, ww).value_or(0.0);
          wc.drive_angle_rad = r.number(w, "drive_angle_deg", true, Bound::any, ww).value_or(0.0) * kDeg;
          wc.roller_angle_rad = r.number(w, "roller_angle_deg", false, Bound::any, ww).value_or(0.0) * kDeg;
          if (std::abs(std::cos(wc.roller_angle_rad)) < 1e-3) r.error(w, ww + ": roller_angle_deg must not be +-90");
          c.holonomic.wheels.push_back(wc);
        }
        if (wheels.size() < 3 || wheels.size() > HolonomicConfig::kMaxWheels) {
          r.error(wheels, what + ": an omni base needs 3 to " + std::to_string(HolonomicConfig::kMaxWheels) +
                              " wheels, got " + std::to_string(wheels.size()));
        }
      }
    } else {
      r.error(node, what + ": missing wheel geometry: give 'wheel_angles_deg' with 'base_radius_m', or 'wheels'");
    }
  }
  return c;
}

LoopConfig read_loop(Reader& r, const YAML::Node& node, std::size_t index) {
  LoopConfig l;
  l.where = r.at(node);
  std::string what = "loop #" + std::to_string(index + 1);
  if (!r.is_map(node, what)) return l;
  if (auto n = r.text(node, "name", true, what)) {
    l.name = *n;
    what = "loop '" + l.name + "'";
  }
  r.check_keys(node, {"name", "period_s", "controller", "realtime_priority", "cpu", "max_behaviors", "coordinator"}, what);
  if (auto p = r.number(node, "period_s", true, Bound::positive, what)) {
    // Shorter than a microsecond rounds to no period at all; beyond kMaxSeconds it would be capped.
    if (*p < yaml::kMinPeriodSeconds || *p > kMaxSeconds) {
      r.error(node["period_s"], fmt::format("{}: 'period_s': expected seconds from {:g} to {:g}, got {}", what, yaml::kMinPeriodSeconds,
                                            kMaxSeconds, node["period_s"].Scalar()));
    } else {
      l.period = from_seconds(*p);
    }
  }
  if (auto c = r.text(node, "controller", false, what)) l.controller = *c;
  if (auto p = r.integer(node, "realtime_priority", 0, 99, what)) l.timing.realtime_priority = *p;
  if (auto p = r.integer(node, "cpu", -1, 1023, what)) l.timing.cpu = *p;
  if (auto p = r.integer(node, "max_behaviors", 1, 1024, what)) l.max_behaviors = static_cast<std::size_t>(*p);
  const YAML::Node co = node["coordinator"];
  if (!co) return l;
  const std::string cw = what + " coordinator";
  if (!r.is_map(co, cw)) return l;
  r.check_keys(co, {"mode", "inputs", "locks"}, cw);
  if (auto m = r.text(co, "mode", false, cw)) {
    if (*m == "priority") {
      l.coordinator.mode = CoordinationMode::priority;
    } else if (*m == "weighted_sum") {
      l.coordinator.mode = CoordinationMode::weighted_sum;
    } else {
      r.error(co["mode"], cw + ": unknown mode '" + *m + "' (expected priority or weighted_sum)");
    }
  }
  std::set<std::string> names;
  if (const YAML::Node inputs = co["inputs"]) {
    if (!inputs.IsSequence()) {
      r.error(inputs, cw + ": 'inputs' must be a list");
    } else {
      std::size_t i = 0;
      for (const auto& in : inputs) {
        const std::string iw = cw + " input #" + std::to_string(++i);
        if (!r.is_map(in, iw)) continue;
        r.check_keys(in, {"name", "priority", "timeout_s", "weight", "role"}, iw);
        CoordinatorInputConfig c;
        c.name = r.text(in, "name", true, iw).value_or("");
        if (!c.name.empty() && !names.insert(c.name).second) r.error(in["name"], iw + ": duplicate input '" + c.name + "'");
        c.priority = r.integer(in, "priority", -1000000, 1000000, iw).value_or(0);
        c.timeout = from_seconds(r.number(in, "timeout_s", false, Bound::non_negative, iw).value_or(0.0));
        c.weight = r.number(in, "weight", false, Bound::non_negative, iw).value_or(1.0);
        if (auto role = r.text(in, "role", false, iw)) {
          if (*role == "safety") {
            c.role = InputRole::safety;
          } else if (*role != "normal") {
            r.error(in["role"], iw + ": unknown role '" + *role + "' (expected normal or safety)");
          }
        }
        l.coordinator.inputs.push_back(std::move(c));
      }
    }
  }
  if (const YAML::Node locks = co["locks"]) {
    if (!locks.IsSequence()) {
      r.error(locks, cw + ": 'locks' must be a list");
    } else {
      std::size_t i = 0;
      for (const auto& lk : locks) {
        const std::string lw = cw + " lock #" + std::to_string(++i);
        if (!r.is_map(lk, lw)) continue;
        r.check_keys(lk, {"name", "priority", "timeout_s"}, lw);
        CoordinatorLockConfig c;
        c.name = r.text(lk, "name", true, lw).value_or("");
        c.priority = r.integer(lk, "priority", -1000000, 1000000, lw).value_or(0);
        c.timeout = from_seconds(r.number(lk, "timeout_s", false, Bound::non_negative, lw).value_or(0.0));
        l.coordinator.locks.push_back(std::move(c));
      }
    }
  }
  return l;
}

}  // namespace

namespace {

ReactiveConfig walk_reactive_config(std::string_view text, const std::string& file, const ControllerRegistry& registry) {
  Diagnostics diags;
  Reader r(file, diags);
  const YAML::Node root = yaml::parse(text, file);
  ReactiveConfig out;
  if (!root.IsMap()) {
    throw ConfigError(SourceLocation{file, 1, 1}, "expected a map with 'controllers' and 'loops'");
  }
  r.check_keys(root, {"controllers", "loops"}, "the reactive configuration");
  if (const YAML::Node cs = root["controllers"]) {
    if (!cs.IsSequence()) {
      r.error(cs, "'controllers' must be a list");
    } else {
      std::size_t i = 0;
      for (const auto& c : cs) {
        ControllerConfig cc = read_controller(r, c, i++, registry);
        if (!cc.name.empty() && out.find_controller(cc.name) != nullptr) r.error(c, "duplicate controller '" + cc.name + "'");
        out.controllers.push_back(std::move(cc));
      }
    }
  }
  if (const YAML::Node ls = root["loops"]) {
    if (!ls.IsSequence()) {
      r.error(ls, "'loops' must be a list");
    } else {
      std::size_t i = 0;
      for (const auto& l : ls) {
        LoopConfig lc = read_loop(r, l, i++);
        if (!lc.name.empty() && out.find_loop(lc.name) != nullptr) r.error(l, "duplicate loop '" + lc.name + "'");
        if (!lc.controller.empty() && out.find_controller(lc.controller) == nullptr) {
          r.error(l["controller"], "loop '" + lc.name + "': unknown controller '" + lc.controller + "'");
        }
        out.loops.push_back(std::move(lc));
      }
    }
  }
  if (diags.has_errors()) throw ConfigError(std::move(diags));
  return out;
}

}  // namespace

ReactiveConfig parse_reactive_config(std::string_view text, const std::string& file, const ControllerRegistry& registry) {
  return yaml::guarded(file, [&] { return walk_reactive_config(text, file, registry); });
}

ReactiveConfig load_reactive_config(const std::string& path, const ControllerRegistry& registry) {
  return parse_reactive_config(yaml::read_file(path), path, registry);
}

}  // namespace tripodal
