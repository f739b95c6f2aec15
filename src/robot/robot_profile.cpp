#include "tripodal/robot/robot_profile.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "../planner/yaml_util.hpp"

namespace tripodal {

namespace {

using detail::kind_name;
using detail::where;

struct Parser {
  std::string file;
  std::filesystem::path base;
  Diagnostics d;

  SourceLocation at(const YAML::Node& n) const { return where(file, n); }

  bool scalar(const YAML::Node& n, std::string& out, std::string_view what) {
    if (!n.IsScalar()) {
      d.error(at(n), std::string(what) + " must be a scalar, not " + kind_name(n));
      return false;
    }
    out = n.as<std::string>();
    return true;
  }

  std::optional<std::vector<std::string>> names(const YAML::Node& n, std::string_view what) {
    if (!n.IsSequence()) {
      d.error(at(n), std::string(what) + " must be a list of names, not " + kind_name(n));
      return std::nullopt;
    }
    std::vector<std::string> out;
    for (const auto& item : n) {
      std::string s;
      if (scalar(item, s, what)) out.push_back(s);
    }
    return out;
  }

  std::optional<double> positive_seconds(const YAML::Node& n, std::string_view what) {
    double v = 0.0;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v) || v <= 0.0) {
      d.error(at(n), std::string(what) + " must be a positive number of seconds, got '" +
                         (n.IsScalar() ? n.as<std::string>() : kind_name(n)) + "'");
      return std::nullopt;
    }
    return v;
  }

  std::filesystem::path path_of(const YAML::Node& n, std::string_view what, SourceLocation& loc) {
    std::string s;
    loc = at(n);
    if (!scalar(n, s, what)) return {};
    std::filesystem::path p(s);
    if (p.is_relative()) p = base / p;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(p, ec)) d.error(loc, std::string(what) + " '" + s + "' not found (looked for " + p.string() + ")");
    return p;
  }

  void module(const YAML::Node& n, ModuleKind kind, std::vector<ModuleEntry>& out) {
    ModuleEntry e;
    e.kind = kind;
    e.where = at(n);
    if (n.IsScalar()) {  // "- BhCleaning": a registered type under its own name
      e.name = e.type = n.as<std::string>();
      out.push_back(std::move(e));
      return;
    }
    if (!n.IsMap()) {
      d.error(e.where, "a " + std::string(to_string(kind)) + " entry must be a name or a map with name, type, ...; not " + kind_name(n));
      return;
    }
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      const YAML::Node v = kv.second;
      if (key == "name") {
        scalar(v, e.name, "name");
      } else if (key == "type") {
        scalar(v, e.type, "type");
      } else if (key == "description") {
        scalar(v, e.description, "description");
      } else if (key == "layer") {
        std::string s;
        if (scalar(v, s, "layer")) {
          e.layer = parse_layer(s);
          if (!e.layer) d.error(at(v), "unknown layer '" + s + "'; expected one of: deliberate, sequencing, reactive");
        }
      } else if (key == "inputs") {
        e.inputs = names(v, "inputs");
      } else if (key == "outputs") {
        e.outputs = names(v, "outputs");
      } else if (key == "parameters") {
        if (!v.IsMap()) {
          d.error(at(v), "parameters must be a map of name: value, not " + kind_name(v));
          continue;
        }
        for (const auto& p : v) {
          std::string val;
          if (scalar(p.second, val, "parameter '" + p.first.as<std::string>() + "'")) e.parameters[p.first.as<std::string>()] = val;
        }
      } else if (key == "watchdog") {
        if (!v.IsMap()) {
          d.error(at(v), "watchdog must be a map with timeout_s and optionally event, not " + kind_name(v));
          continue;
        }
        for (const auto& w : v) {
          const std::string wk = w.first.as<std::string>();
          if (wk == "timeout_s") {
            if (auto s = positive_seconds(w.second, "watchdog timeout_s")) e.watchdog_timeout = from_seconds(*s);
          } else if (wk == "event") {
            scalar(w.second, e.watchdog_event, "watchdog event");
          } else {
            d.error(at(w.first), "unknown key '" + wk + "' in watchdog; expected: timeout_s, event");
          }
        }
        if (!e.watchdog_timeout) d.error(at(v), "watchdog needs timeout_s");
      } else {
        d.error(at(kv.first), "unknown key '" + key + "' in a " + std::string(to_string(kind)) +
                                  " entry; expected: name, type, description, layer, inputs, outputs, parameters, watchdog");
      }
    }
    if (e.name.empty()) {
      d.error(e.where, "a " + std::string(to_string(kind)) + " entry needs a name");
      return;
    }
    if (e.type.empty()) e.type = e.name;
    out.push_back(std::move(e));
  }

  void modules(const YAML::Node& n, ModuleKind kind, std::vector<ModuleEntry>& out, std::string_view section) {
    if (!n.IsSequence()) {
      d.error(at(n), std::string(section) + " must be a list, not " + kind_name(n));
      return;
    }
    for (const auto& m : n) module(m, kind, out);
  }

  void process(const YAML::Node& n, std::vector<ProcessEntry>& out) {
    ProcessEntry p;
    p.where = at(n);
    if (!n.IsMap()) {
      d.error(p.where, "a process entry must be a map with name, net, parameters; not " + kind_name(n));
      return;
    }
    bool has_net = false;
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      const YAML::Node v = kv.second;
      if (key == "name") {
        scalar(v, p.name, "name");
      } else if (key == "type") {
        scalar(v, p.type, "type");
      } else if (key == "net") {
        has_net = true;
        p.net = path_of(v, "net file", p.net_where);
      } else if (key == "module") {
        p.module = path_of(v, "module net file", p.module_where);
      } else if (key == "recovery") {
        SourceLocation loc;
        p.recovery = path_of(v, "recovery file", loc);
      } else if (key == "parameters") {
        if (!v.IsMap()) {
          d.error(at(v), "parameters must be a map of name: value, not " + kind_name(v));
          continue;
        }
        for (const auto& q : v) {
          std::string val;
          if (scalar(q.second, val, "parameter")) p.parameters.push_back(BindingParam{q.first.as<std::string>(), val, at(q.second)});
        }
      } else {
        d.error(at(kv.first), "unknown key '" + key + "' in a process entry; expected: name, type, net, module, parameters, recovery");
      }
    }
    if (p.name.empty()) d.error(p.where, "a process entry needs a name");
    if (!has_net) d.error(p.where, "process '" + p.name + "' needs a net file (net: FILE)");
    if (!p.name.empty()) out.push_back(std::move(p));
  }

  RobotProfile parse(const std::string& text) {
    RobotProfile prof;
    prof.file = file;
    YAML::Node root;
    try {
      root = YAML::Load(text);
    } catch (const YAML::ParserException& e) {
      throw ConfigError(SourceLocation{file, e.mark.line + 1, e.mark.column + 1}, e.msg);
    }
    prof.where = SourceLocation{file, 1, 1};
    if (!root.IsMap()) {
      d.error(at(root), "a robot profile must be a map with robot, behaviors, processes, ...; not " + kind_name(root));
      throw ConfigError(d);
    }
    for (const auto& kv : root) {
      const std::string key = kv.first.as<std::string>();
      const YAML::Node v = kv.second;
      if (key == "robot") {
        if (!v.IsMap()) {
          d.error(at(v), "robot must be a map with name and description");
          continue;
        }
        prof.where = at(v);
        for (const auto& r : v) {
          const std::string rk = r.first.as<std::string>();
          if (rk == "name") scalar(r.second, prof.name, "robot name");
          else if (rk == "description") scalar(r.second, prof.description, "description");
          else d.error(at(r.first), "unknown key '" + rk + "' in robot; expected: name, description");
        }
      } else if (key == "controllers") {
        modules(v, ModuleKind::controller, prof.controllers, key);
      } else if (key == "resources") {
        modules(v, ModuleKind::resource, prof.resources, key);
      } else if (key == "navigation") {
        modules(v, ModuleKind::navigation, prof.navigation, key);
      } else if (key == "hri") {
        modules(v, ModuleKind::hri, prof.hri, key);
      } else if (key == "modules") {
        modules(v, ModuleKind::other, prof.modules, key);
      } else if (key == "behaviors") {
        modules(v, ModuleKind::behavior, prof.behaviors, key);
      } else if (key == "loops") {
        if (!v.IsSequence()) {
          d.error(at(v), "loops must be a list, not " + kind_name(v));
          continue;
        }
        for (const auto& l : v) {
          LoopEntry loop;
          loop.where = at(l);
          if (!l.IsMap()) {
            d.error(loop.where, "a loop must be a map with name, period_s, controller");
            continue;
          }
          for (const auto& lk : l) {
            const std::string k = lk.first.as<std::string>();
            if (k == "name") scalar(lk.second, loop.name, "name");
            else if (k == "controller") scalar(lk.second, loop.controller, "controller");
            else if (k == "period_s") {
              if (auto s = positive_seconds(lk.second, "period_s")) loop.period = from_seconds(*s);
            } else d.error(at(lk.first), "unknown key '" + k + "' in a loop; expected: name, period_s, controller");
          }
          if (loop.name.empty()) d.error(loop.where, "a loop needs a name");
          if (loop.period <= Duration{0} && !l["period_s"]) d.error(loop.where, "loop '" + loop.name + "' needs period_s");
          prof.loops.push_back(std::move(loop));
        }
      } else if (key == "processes") {
        if (!v.IsSequence()) {
          d.error(at(v), "processes must be a list, not " + kind_name(v));
          continue;
        }
        for (const auto& p : v) process(p, prof.processes);
      } else if (key == "tasks") {
        prof.tasks = path_of(v, "tasks file", prof.tasks_where);
      } else if (key == "recovery") {
        prof.recovery = path_of(v, "recovery file", prof.recovery_where);
      } else {
        d.error(at(kv.first), "unknown key '" + key +
                                  "'; expected: robot, controllers, loops, resources, navigation, hri, modules, behaviors, processes, tasks, recovery");
      }
    }
    if (prof.name.empty()) d.error(prof.where, "the profile needs robot: {name: ...}");
    // Names are unique across every kind of module: they identify providers in the checks.
    std::map<std::string, SourceLocation> seen;
    for (const ModuleEntry* m : prof.all_modules()) {
      auto [it, fresh] = seen.emplace(m->name, m->where);
      if (!fresh) d.error(m->where, "module name '" + m->name + "' is used twice (first at " + it->second.str() + ")");
    }
    std::set<std::string> procs;
    for (const ProcessEntry& p : prof.processes) {
      if (!procs.insert(p.name).second) d.error(p.where, "process '" + p.name + "' is listed twice");
    }
    for (const LoopEntry& l : prof.loops) {
      if (l.controller.empty()) continue;
      const bool known = std::any_of(prof.controllers.begin(), prof.controllers.end(),
                                     [&](const ModuleEntry& c) { return c.name == l.controller; });
      if (!known) d.error(l.where, "loop '" + l.name + "' drives controller '" + l.controller + "', which the profile does not list");
    }
    if (d.has_errors()) throw ConfigError(d);
    return prof;
  }
};

}  // namespace

std::vector<const ModuleEntry*> RobotProfile::all_modules() const {
  std::vector<const ModuleEntry*> out;
  for (const auto* list : {&controllers, &resources, &navigation, &hri, &modules, &behaviors}) {
    for (const ModuleEntry& m : *list) out.push_back(&m);
  }
  return out;
}

RobotProfile load_robot_profile(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ConfigError(SourceLocation{file.string(), 0, 0}, "cannot read the robot profile");
  std::stringstream s;
  s << in.rdbuf();
  return load_robot_profile_from_string(s.str(), file.string(), file.parent_path());
}

RobotProfile load_robot_profile_from_string(std::string_view yaml, std::string_view name, const std::filesystem::path& base_dir) {
  Parser p{std::string(name), base_dir, {}};
  return p.parse(std::string(yaml));
}

}  // namespace tripodal
