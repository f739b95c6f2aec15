#include "tripodal/robot/robot_profile.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal {

bool is_ros_namespace(std::string_view ns) {
  if (!ns.empty() && ns.front() == '/') ns.remove_prefix(1);
  if (ns.empty()) return true;  // none: the topics are at the root ("rt/odom")
  std::size_t start = 0;
  while (start <= ns.size()) {
    const std::size_t end = std::min(ns.find('/', start), ns.size());
    const std::string_view token = ns.substr(start, end - start);
    if (token.empty() || std::isdigit(static_cast<unsigned char>(token.front())) != 0) return false;
    for (const char c : token) {
      if (std::isalnum(static_cast<unsigned char>(c)) == 0 && c != '_') return false;
    }
    start = end + 1;
  }
  return true;
}

namespace {

struct Parser {
  Parser(std::string file_name, std::filesystem::path base_dir)
      : file(std::move(file_name)), base(std::move(base_dir)), r(file, d) {}

  std::string file;
  std::filesystem::path base;
  Diagnostics d;
  yaml::Reader r;
  bool dds_namespace_given = false;  // an explicit "" puts the topics at the root

  SourceLocation at(const YAML::Node& n) const { return r.at(n); }

  bool scalar(const YAML::Node& n, std::string& out, std::string_view what) {
    auto text = r.text(n, what);
    if (text) out = std::move(*text);
    return text.has_value();
  }

  std::optional<std::vector<std::string>> names(const YAML::Node& n, std::string_view what) { return r.names(n, what); }

  std::optional<double> positive_seconds(const YAML::Node& n, std::string_view what) {
    return r.seconds(n, what);
  }

  // The thread keys of a loop (or of the sequencing loop), those present in `n`.
  void timing(const YAML::Node& n, LoopTimingOptions& t, const std::string& what) {
    if (const YAML::Node v = n["realtime_priority"]) {
      if (auto p = r.integer(v, what + " realtime_priority", 0, 99)) t.realtime_priority = static_cast<int>(*p);
    }
    if (const YAML::Node v = n["cpu"]) {
      if (auto c = r.integer(v, what + " cpu", -1, 1023)) t.cpu = static_cast<int>(*c);
    }
    if (const YAML::Node v = n["lock_memory"]) {
      if (auto b = r.boolean(v, what + " lock_memory")) t.lock_memory = *b;
    }
    if (const YAML::Node v = n["budget_s"]) {
      if (auto s = positive_seconds(v, what + " budget_s")) t.budget = from_seconds(*s);
    }
    if (const YAML::Node v = n["deadline_overruns"]) {
      if (auto k = r.integer(v, what + " deadline_overruns", 0, 1000000)) t.deadline_overruns = static_cast<std::uint32_t>(*k);
    }
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

  void module(const YAML::Node& n, ModuleKind kind, std::vector<ModuleEntry>& out, std::string default_name = {}) {
    ModuleEntry e;
    e.name = std::move(default_name);
    e.kind = kind;
    e.where = at(n);
    if (n.IsScalar()) {  // "- BhCleaning": a registered type under its own name
      e.name = e.type = n.Scalar();
      out.push_back(std::move(e));
      return;
    }
    const std::string entry = "a " + std::string(to_string(kind)) + " entry";
    const bool known =
        kind == ModuleKind::behavior
            ? r.expect_keys(
                  n, {"name", "type", "description", "layer", "inputs", "outputs", "from", "parameters", "watchdog", "safety"},
                  entry)
            : r.expect_keys(n, {"name", "type", "description", "layer", "inputs", "outputs", "from", "parameters", "watchdog"},
                            entry);
    if (!known) return;
    for (const auto& kv : n) {
      const std::string key = yaml::Reader::checked_key(kv.first);
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
      } else if (key == "from") {
        if (!r.expect_map(v, "from")) continue;
        for (const auto& p : v) {
          const auto info = r.key(p.first, "from");
          std::string provider;
          if (info && scalar(p.second, provider, "from '" + *info + "'")) e.from[*info] = provider;
        }
      } else if (key == "parameters") {
        if (!r.expect_map(v, "parameters")) continue;
        for (const auto& p : v) {
          const auto name = r.key(p.first, "parameters");
          std::string val;
          if (name && scalar(p.second, val, "parameter '" + *name + "'")) e.parameters[*name] = val;
        }
      } else if (key == "safety") {
        std::string flag;
        if (scalar(v, flag, "safety")) {
          if (flag == "true") e.safety = true;
          else if (flag != "false") d.error(at(v), "safety: expected true or false, got '" + flag + "'");
        }
      } else if (key == "watchdog") {
        if (!r.expect_keys(v, {"timeout_s", "event"}, "watchdog")) continue;
        if (const YAML::Node t = r.require(v, "timeout_s", "watchdog", "seconds")) {
          if (auto s = positive_seconds(t, "watchdog timeout_s")) e.watchdog_timeout = from_seconds(*s);
        }
        if (const YAML::Node ev = v["event"]) scalar(ev, e.watchdog_event, "watchdog event");
      }
    }
    if (e.name.empty()) {
      if (!n["name"]) r.require(n, "name", entry, "the module's name");
      return;
    }
    if (e.type.empty()) e.type = e.name;
    out.push_back(std::move(e));
  }

  void modules(const YAML::Node& n, ModuleKind kind, std::vector<ModuleEntry>& out, std::string_view section) {
    if (!r.expect_list(n, section)) return;
    for (const auto& m : n) module(m, kind, out);
  }

  void process(const YAML::Node& n, std::vector<ProcessEntry>& out) {
    ProcessEntry p;
    p.where = at(n);
    if (!r.expect_keys(n, {"name", "type", "net", "module", "parameters", "recovery"}, "a process entry")) return;
    bool has_net = false;
    for (const auto& kv : n) {
      const std::string key = yaml::Reader::checked_key(kv.first);
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
        if (!r.expect_map(v, "parameters")) continue;
        for (const auto& q : v) {
          const auto name = r.key(q.first, "parameters");
          std::string val;
          if (name && scalar(q.second, val, "parameter '" + *name + "'")) p.parameters.push_back(BindingParam{*name, val, at(q.second)});
        }
      }
    }
    if (!n["name"]) r.require(n, "name", "a process entry", "the process's name");
    if (!has_net) d.error(p.where, "process '" + p.name + "' needs a net file (net: FILE)");
    if (!p.name.empty()) out.push_back(std::move(p));
  }

  // `dds:` — every value checked where it is written; a namespace must be one ROS 2 accepts, since
  // a ROS 2 node on the same domain would otherwise see none of the robot's topics.
  void dds_section(const YAML::Node& n, RobotProfile& prof) {
    DdsSection s;
    s.where = at(n);
    if (!r.expect_keys(
            n,
            {"domain_id", "namespace", "loopback", "participant_lease_s", "period_s", "publish", "tasks", "frames", "security"},
            "dds")) {
      return;
    }
    if (const YAML::Node v = n["security"]) {
      if (r.expect_keys(v, {"keys", "identity"}, "dds security")) {
        const auto keys = v["keys"] ? r.text(v["keys"], "dds security keys") : std::nullopt;
        const auto identity = v["identity"] ? r.text(v["identity"], "dds security identity") : std::nullopt;
        if (!keys || !identity) {
          d.error(at(v),
                  "dds security needs keys (the folder `tripodal fleet-keys` made) and identity (this robot's name in it)");
        } else {
          s.security_keys = std::filesystem::path(*keys).is_absolute() ? std::filesystem::path(*keys) : prof.dir / *keys;
          s.security_identity = *identity;
        }
      }
    }
    if (const YAML::Node v = n["domain_id"]) {
      if (auto id = r.integer(v, "dds domain_id", 0, 232)) s.domain_id = static_cast<std::uint32_t>(*id);
    }
    if (const YAML::Node v = n["namespace"]) {
      if (auto ns = r.text(v, "dds namespace")) {
        dds_namespace_given = true;
        s.ros_namespace = *ns;
        if (!is_ros_namespace(*ns)) {
          d.error(at(v), "dds namespace '" + *ns + "' is not a ROS 2 namespace: names of letters, digits and '_', "
                         "not starting with a digit, separated by '/'");
        }
      }
    }
    if (const YAML::Node v = n["loopback"]) {
      if (auto b = r.boolean(v, "dds loopback")) s.loopback = *b;
    }
    if (const YAML::Node v = n["participant_lease_s"]) {
      if (auto l = positive_seconds(v, "dds participant_lease_s")) s.participant_lease = from_seconds(*l);
    }
    if (const YAML::Node v = n["period_s"]) {
      if (auto p = positive_seconds(v, "dds period_s")) s.period = from_seconds(*p);
    }
    if (const YAML::Node v = n["tasks"]) {
      if (auto b = r.boolean(v, "dds tasks")) s.tasks = *b;
    }
    if (const YAML::Node v = n["frames"]) {
      if (r.expect_map(v, "dds frames")) {
        for (const auto& kv : v) {
          const auto frame = r.key(kv.first, "dds frames");
          if (!frame) continue;
          if (!is_ros_namespace(*frame) || frame->find('/') != std::string::npos || frame->empty()) {
            d.error(at(kv.first), "dds frames: '" + *frame + "' is not a frame name (letters, digits and '_')");
            continue;
          }
          const auto xyt = r.numbers(kv.second, "dds frames " + *frame, 3, 3, "[x_m, y_m, theta_rad]");
          if (xyt) s.frames.push_back({*frame, Pose2D{(*xyt)[0], (*xyt)[1], (*xyt)[2]}, at(kv.first)});
        }
      }
    }
    if (const YAML::Node v = n["publish"]) {
      if (r.expect_list(v, "dds publish")) {
        std::map<std::string, SourceLocation> seen;
        for (const auto& item : v) {
          auto topic = r.choice(item, "dds publish", {"odom", "pose", "map", "events", "markings", "tf", "clock"});
          if (!topic) continue;
          auto [it, fresh] = seen.emplace(*topic, at(item));
          if (!fresh) {
            d.error(at(item), "dds publish lists '" + *topic + "' twice (first at " + it->second.str() + ")");
            continue;
          }
          s.publish.push_back(*topic);
        }
      }
    } else {
      s.publish.assign(std::begin(kDdsTopics), std::end(kDdsTopics));
    }
    prof.dds = std::move(s);
  }

  RobotProfile parse(const std::string& text) {
    RobotProfile prof;
    prof.file = file;
    prof.dir = base;
    const YAML::Node root = yaml::parse(text, file);
    prof.where = SourceLocation{file, 1, 1};
    if (!r.expect_keys(root,
                       {"robot", "hardware", "controllers", "loops", "resources", "navigation", "hri", "modules", "behaviors",
                        "processes", "tasks", "recovery", "dds", "external_facts", "plugins"},
                       "the robot profile")) {
      throw ConfigError(d);
    }
    for (const auto& kv : root) {
      const std::string key = yaml::Reader::checked_key(kv.first);
      const YAML::Node v = kv.second;
      if (key == "robot") {
        if (!r.expect_keys(v, {"name", "description", "sequencing_period_s", "sequencing_loop"}, "robot")) continue;
        prof.where = at(v);
        if (const YAML::Node name = v["name"]) scalar(name, prof.name, "robot name");
        if (const YAML::Node description = v["description"]) scalar(description, prof.description, "description");
        if (const YAML::Node period = v["sequencing_period_s"]) {
          if (auto s = positive_seconds(period, "sequencing_period_s")) prof.sequencing_period = from_seconds(*s);
        }
        if (const YAML::Node sl = v["sequencing_loop"]) {
          if (r.expect_keys(sl, {"realtime_priority", "cpu", "lock_memory", "budget_s", "deadline_overruns"},
                            "robot sequencing_loop")) {
            timing(sl, prof.sequencing_timing, "sequencing_loop");
          }
        }
      } else if (key == "hardware") {
        std::vector<ModuleEntry> hw;
        module(v, ModuleKind::other, hw, "hardware");
        if (!hw.empty()) prof.hardware = std::move(hw.front());
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
        if (!r.expect_list(v, "loops")) continue;
        for (const auto& l : v) {
          LoopEntry loop;
          loop.where = at(l);
          if (!r.expect_keys(
                  l,
                  {"name", "period_s", "controller", "realtime_priority", "cpu", "lock_memory", "budget_s", "deadline_overruns"},
                  "a loop")) {
            continue;
          }
          if (const YAML::Node name = r.require(l, "name", "a loop", "the loop's name")) scalar(name, loop.name, "name");
          if (const YAML::Node c = l["controller"]) scalar(c, loop.controller, "controller");
          if (const YAML::Node p = r.require(l, "period_s", "a loop", "seconds")) {
            if (auto s = positive_seconds(p, "period_s")) loop.period = from_seconds(*s);
          }
          timing(l, loop.timing, "loop '" + loop.name + "'");
          prof.loops.push_back(std::move(loop));
        }
      } else if (key == "processes") {
        if (!r.expect_list(v, "processes")) continue;
        for (const auto& p : v) process(p, prof.processes);
      } else if (key == "tasks") {
        prof.tasks = path_of(v, "tasks file", prof.tasks_where);
      } else if (key == "recovery") {
        prof.recovery = path_of(v, "recovery file", prof.recovery_where);
      } else if (key == "dds") {
        dds_section(v, prof);
      } else if (key == "external_facts") {
        prof.external_facts_where = at(v);
        if (auto n = names(v, "external_facts")) prof.external_facts = std::move(*n);
      } else if (key == "plugins") {
        if (!r.expect_list(v, "plugins")) continue;
        for (const auto& item : v) {
          PluginEntry e;
          e.path = path_of(item, "plugin library", e.where);
          if (!e.path.empty()) prof.plugins.push_back(std::move(e));
        }
      }
    }
    if (prof.name.empty()) d.error(prof.where, "the profile needs robot: {name: ...}");
    if (prof.dds && !dds_namespace_given) {
      prof.dds->ros_namespace = prof.name;
      if (!is_ros_namespace(prof.name)) {
        d.error(prof.dds->where, "dds: the robot's name '" + prof.name + "' is not a ROS 2 namespace (letters, digits and '_'); "
                                 "give dds: {namespace: ...}");
      }
    }
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
  return load_robot_profile_from_string(yaml::read_file(file), file.string(), file.parent_path());
}

RobotProfile load_robot_profile_from_string(std::string_view yaml, std::string_view name, const std::filesystem::path& base_dir) {
  Parser p(std::string(name), base_dir);
  return yaml::guarded(p.file, [&] { return p.parse(std::string(yaml)); });
}

}  // namespace tripodal
