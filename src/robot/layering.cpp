#include "tripodal/robot/layering.hpp"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace tripodal {

namespace {

bool many(const std::string& input) { return !input.empty() && input.back() == '*'; }
std::string base_name(const std::string& input) { return many(input) ? input.substr(0, input.size() - 1) : input; }

std::optional<Layer> layer_of_kind(ModuleKind k) {
  switch (k) {
    case ModuleKind::behavior:
    case ModuleKind::resource:
    case ModuleKind::controller: return Layer::reactive;
    case ModuleKind::navigation:
    case ModuleKind::process: return Layer::sequencing;
    case ModuleKind::planner:
    case ModuleKind::hri: return Layer::deliberate;
    case ModuleKind::other: return std::nullopt;
  }
  return std::nullopt;
}

std::string module_phrase(const DescribedModule& m) {
  std::string kind = m.core ? "core component" : std::string(to_string(m.kind));
  if (m.kind == ModuleKind::other && !m.core) kind = "module";
  return std::string(to_string(m.layer)) + " " + kind + " '" + m.name + "'";
}

std::string join(const std::vector<std::string>& v, std::string_view sep = ", ") {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : std::string(sep)) + s;
  return out;
}

std::string dot_id(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

}  // namespace

void check_layering(const std::vector<DescribedModule>& modules, Diagnostics& d) {
  // R1: a module's kind fixes its layer (the paper's Fig. 5 guideline).
  for (const DescribedModule& m : modules) {
    auto expected = layer_of_kind(m.kind);
    if (expected && *expected != m.layer) {
      d.error(m.where, "module '" + m.name + "' is a " + std::string(to_string(m.kind)) + " but sits in the " +
                           std::string(to_string(m.layer)) + " layer; " + std::string(to_string(m.kind)) +
                           " modules belong to the " + std::string(to_string(*expected)) + " layer (rule R1)");
    }
  }
  // R0: every input has exactly one provider (or any number, for a fused input "name*"); where
  // several provide it, the module's `from:` names the one it takes the input from.
  for (const DescribedModule& m : modules) {
    for (const auto& binding : m.from) {
      // Named, not a structured binding: the lambda below captures it (clang 14 cannot capture one).
      const std::string& info = binding.first;
      const std::string& provider = binding.second;
      const bool is_input =
          std::any_of(m.inputs.begin(), m.inputs.end(), [&](const std::string& in) { return base_name(in) == info; });
      if (!is_input) {
        std::string list;
        for (const std::string& in : m.inputs) list += (list.empty() ? "" : ", ") + base_name(in);
        d.error(m.where, "from: " + module_phrase(m) + " has no input '" + info + "' to bind to '" + provider +
                             "'; its inputs: " + (list.empty() ? std::string("none") : list));
      }
    }
    for (const std::string& in : m.inputs) {
      const std::string info = base_name(in);
      std::vector<const DescribedModule*> providers;
      for (const DescribedModule& p : modules) {
        if (&p != &m && std::find(p.outputs.begin(), p.outputs.end(), info) != p.outputs.end()) providers.push_back(&p);
      }
      if (const auto bound = m.from.find(info); bound != m.from.end()) {
        const auto named =
            std::find_if(providers.begin(), providers.end(), [&](const DescribedModule* p) { return p->name == bound->second; });
        if (named == providers.end()) {
          std::string list;
          for (const auto* p : providers) list += (list.empty() ? "" : ", ") + p->name;
          d.error(m.where, "from: " + module_phrase(m) + " takes '" + info + "' from '" + bound->second +
                               "', which does not provide it; " +
                               (list.empty() ? std::string("no module provides it") : "its providers: " + list));
          continue;
        }
        const DescribedModule* chosen = *named;
        providers.assign(1, chosen);
      }
      if (!many(in)) {
        if (providers.empty()) {
          d.error(m.where, "missing provider: " + module_phrase(m) + " needs '" + info + "', but no module provides it");
        } else if (providers.size() > 1) {
          std::string list;
          for (const auto* p : providers) {
            list += (list.empty() ? "" : ", ") + p->name + (p->where.line > 0 ? " (" + p->where.str() + ")" : std::string());
          }
          d.error(m.where, "duplicate providers: " + module_phrase(m) + " needs '" + info + "', which " +
                               std::to_string(providers.size()) + " modules provide: " + list + "; exactly one must");
        }
      }
      for (const DescribedModule* p : providers) {
        // R2: the reactive layer keeps running whatever the planner does, so it never depends on it.
        if (m.layer == Layer::reactive && p->layer == Layer::deliberate) {
          d.error(m.where, "layering: " + module_phrase(m) + " takes '" + info + "' from " + module_phrase(*p) +
                               "; reactive modules must not depend on the deliberate layer (rule R2)");
        }
        // R3: the sequencing layer extracts information from raw data for the deliberate layer.
        if (m.layer == Layer::deliberate && p->layer == Layer::reactive) {
          d.error(m.where, "layering: " + module_phrase(m) + " takes '" + info + "' from " + module_phrase(*p) +
                               "; raw data reaches the deliberate layer only through a sequencing module (rule R3)");
        }
        // R4: resource -> behavior -> coordinator -> controller; a behavior never drives the base itself.
        if (m.kind == ModuleKind::controller && p->kind == ModuleKind::behavior) {
          d.error(m.where, "layering: controller '" + m.name + "' takes '" + info + "' directly from behavior '" + p->name +
                               "'; motion commands reach controllers only through the behavior coordinator (rule R4)");
        }
        // R5: behaviors are independent primitives; only the coordinator combines them.
        if (m.kind == ModuleKind::behavior && p->kind == ModuleKind::behavior) {
          d.error(m.where, "layering: behavior '" + m.name + "' takes '" + info + "' from behavior '" + p->name +
                               "'; behaviors are independent and combined only by the behavior coordinator (rule R5)");
        }
      }
    }
  }
}

namespace {

// R6: the channels behaviors write by name against those the hardware's type exports. A hardware
// that exports channels of its world too (the simulator's joints) is checked at assembly.
void check_channels(const std::vector<DescribedModule>& modules, Diagnostics& d) {
  const auto hw = std::find_if(modules.begin(), modules.end(), [](const DescribedModule& m) { return m.hardware; });
  if (hw == modules.end()) return;
  std::string exported;
  for (const ChannelSpec& c : hw->channels)
    exported += (exported.empty() ? "" : ", ") + c.name + " (" + std::string(to_string(c.type)) + ")";
  for (const DescribedModule& m : modules) {
    for (const ChannelWrite& w : m.writes) {
      if (w.name.empty()) continue;
      const auto c =
          std::find_if(hw->channels.begin(), hw->channels.end(), [&](const ChannelSpec& s) { return s.name == w.name; });
      if (c == hw->channels.end()) {
        d.error(m.where, "behavior '" + m.name + "' writes the command channel '" + w.name + "' (" +
                             std::string(to_string(w.type)) + "), which hardware '" + hw->type +
                             "' does not export; it exports " + (exported.empty() ? std::string("none") : exported) +
                             " (rule R6)");
      } else if (c->type != w.type) {
        d.error(m.where, "behavior '" + m.name + "' writes the command channel '" + w.name + "' as " +
                             std::string(to_string(w.type)) + ", and hardware '" + hw->type + "' exports it as " +
                             std::string(to_string(c->type)) + " (rule R6)");
      }
    }
  }
}

// "uv_lamp (digital) <- BhUvLamp": a channel with the behaviors that write it.
std::string channel_phrase(const ChannelSpec& c, const std::vector<DescribedModule>& modules) {
  std::vector<std::string> writers;
  for (const DescribedModule& m : modules) {
    for (const ChannelWrite& w : m.writes) {
      if (w.name == c.name || (w.name.empty() && w.type == c.type)) writers.push_back(m.name);
    }
  }
  return c.name + " (" + std::string(to_string(c.type)) + ")" + (writers.empty() ? std::string() : " <- " + join(writers));
}

}  // namespace

std::vector<std::string> knowledge_inputs(const TaskLibrary& tasks) {
  std::set<std::string> out;
  std::function<void(const std::vector<TemplateNode>&)> walk = [&](const std::vector<TemplateNode>& nodes) {
    for (const TemplateNode& n : nodes) {
      if (n.kind == TemplateNode::Kind::foreach) {
        const auto paren = n.list_expr.find('(');
        if (paren != std::string::npos && paren > 0) out.insert(n.list_expr.substr(0, paren));
      }
      walk(n.body);
    }
  };
  for (const TaskTemplate& t : tasks.templates()) walk(t.plan);
  return {out.begin(), out.end()};
}

namespace {

// Calls `fn` with the registry of the entry's family: hardware, behaviors, controllers, resources or
// (every other kind) modules.
template <class Fn>
auto with_registry(const RobotPlugins& plugins, const ModuleEntry& e, bool is_hardware, Fn&& fn) {
  if (is_hardware) return fn(plugins.hardware);
  if (e.kind == ModuleKind::behavior) return fn(plugins.behaviors);
  if (e.kind == ModuleKind::controller) return fn(plugins.controllers);
  if (e.kind == ModuleKind::resource) return fn(plugins.resources);
  return fn(plugins.modules);
}

// One entry of the profile as the diagram shows it: from its type's manifest, or from what the
// profile declares of a type not implemented yet; nullopt for an unknown type (reported).
std::optional<DescribedModule> describe_entry(const ModuleEntry& e, bool is_hardware, const RobotPlugins& plugins,
                                              Diagnostics& d) {
  DescribedModule dm;
  dm.name = e.name;
  dm.type = e.type;
  dm.kind = e.kind;
  dm.where = e.where;
  dm.description = e.description;
  dm.from = e.from;
  dm.hardware = is_hardware;
  const ModuleManifest* m = with_registry(plugins, e, is_hardware, [&](const auto& r) { return r.find(e.type); });
  if (m != nullptr) {
    dm.layer = m->layer;
    if (e.layer || e.inputs || e.outputs) {
      // One manifest per type: the diagram must show what the code does, not a second copy.
      d.error(e.where, "module '" + e.name + "' re-declares " +
                           (e.layer    ? "layer"
                            : e.inputs ? "inputs"
                                       : "outputs") +
                           " of its registered type '" + e.type + "' (a " + std::string(to_string(m->layer)) + "-layer " +
                           std::string(to_string(m->kind)) +
                           "); remove layer, inputs and outputs: the diagram comes from the type's own manifest");
    }
    if (!is_hardware && m->kind != ModuleKind::other && m->kind != e.kind) {
      d.error(e.where, "module '" + e.name + "': type '" + e.type + "' is a " + std::string(to_string(m->kind)) +
                           ", but it is listed as a " + std::string(to_string(e.kind)));
    }
    dm.inputs = m->inputs;
    dm.outputs = m->outputs;
    dm.writes = m->writes;
    dm.channels = m->command_channels;
    if (dm.description.empty()) dm.description = m->description;
    return dm;
  }
  if (e.layer) {
    dm.layer = *e.layer;  // declared in the profile: a module designed before it is implemented
    dm.inputs = e.inputs.value_or(std::vector<std::string>{});
    dm.outputs = e.outputs.value_or(std::vector<std::string>{});
    return dm;
  }
  const std::string kind = is_hardware ? std::string("hardware type") : std::string(to_string(e.kind)) + " type";
  const std::vector<std::string> known = with_registry(plugins, e, is_hardware, [](const auto& r) { return r.names(); });
  d.error(e.where,
          unknown_name_message(kind, e.type, known) + "; register it, or declare it here with layer, inputs and outputs");
  return std::nullopt;
}

// The robot's own modules, in every diagram: planner, process supervisor, behavior coordinator.
DescribedModule core_module(std::string name, std::string type, ModuleKind kind, Layer layer, std::string description,
                            std::vector<std::string> inputs, std::vector<std::string> outputs, const SourceLocation& where) {
  DescribedModule m;
  m.name = std::move(name);
  m.type = std::move(type);
  m.kind = kind;
  m.layer = layer;
  m.core = true;
  m.description = std::move(description);
  m.inputs = std::move(inputs);
  m.outputs = std::move(outputs);
  m.where = where;
  return m;
}

}  // namespace

RobotDescription describe_robot(const RobotProfile& profile, const RobotPlugins& plugins,
                                const std::vector<std::string>& planner_inputs, Diagnostics& d) {
  RobotDescription out;
  out.name = profile.name;
  out.description = profile.description;
  std::vector<std::string> pin = planner_inputs;
  pin.push_back("process_result");
  out.modules.push_back(core_module(CoreNames::kPlanner, "CPlanner", ModuleKind::planner, Layer::deliberate,
                                    "turns task commands into plans of process modules; recovers from faults", pin,
                                    {"process_plan"}, profile.where));
  out.modules.push_back(core_module(CoreNames::kSupervisor, "CProcessSupervisor", ModuleKind::other, Layer::sequencing,
                                    "runs the processes' nets, activates behaviors, posts faults", {"process_plan"},
                                    {"process_result"}, profile.where));
  out.modules.push_back(core_module(CoreNames::kCoordinator, "CBehaviorCoordinator", ModuleKind::other, Layer::reactive,
                                    "fuses the commands and the command channels of the active behaviors", {"behavior_command*"},
                                    {"cmd_vel"}, profile.where));
  if (profile.hardware) {
    if (auto dm = describe_entry(*profile.hardware, true, plugins, d)) out.modules.push_back(std::move(*dm));
  }
  for (const ModuleEntry* e : profile.all_modules()) {
    if (auto dm = describe_entry(*e, false, plugins, d)) out.modules.push_back(std::move(*dm));
  }
  for (const ProcessEntry& p : profile.processes) out.processes.push_back(p.name);
  check_layering(out.modules, d);
  check_channels(out.modules, d);
  return out;
}

std::string describe_text(const RobotDescription& r) {
  std::ostringstream o;
  o << "robot " << r.name;
  if (!r.description.empty()) o << ": " << r.description;
  o << '\n';
  for (Layer layer : {Layer::deliberate, Layer::sequencing, Layer::reactive}) {
    o << '\n' << to_string(layer) << " layer\n";
    for (const DescribedModule& m : r.modules) {
      if (m.layer != layer) continue;
      if (m.core) {
        o << "  " << m.name << " (core, " << m.type << ")\n";
      } else {
        o << "  " << m.name << " (" << to_string(m.kind) << (m.type != m.name ? ", " + m.type : std::string()) << ")\n";
      }
      o << "      in:  " << (m.inputs.empty() ? "-" : join(m.inputs)) << '\n';
      o << "      out: " << (m.outputs.empty() ? "-" : join(m.outputs)) << '\n';
      if (!m.writes.empty()) {
        std::vector<std::string> w;
        for (const ChannelWrite& c : m.writes) w.push_back(c.label() + " (" + std::string(to_string(c.type)) + ")");
        o << "      writes: " << join(w) << '\n';
      }
      for (const ChannelSpec& c : m.channels) o << "      channel: " << channel_phrase(c, r.modules) << '\n';
    }
    if (layer == Layer::sequencing) {
      o << "  configurations (core): " << (r.processes.empty() ? "-" : join(r.processes)) << '\n';
    }
  }
  return o.str();
}

std::string describe_dot(const RobotDescription& r) {
  std::ostringstream o;
  o << "digraph " << dot_id(r.name.empty() ? "robot" : r.name) << " {\n"
    << "  label=" << dot_id("Layered functionality diagram of " + r.name) << ";\n  labelloc=t;\n  rankdir=TB;\n  newrank=true;\n"
    << "  node [shape=box, style=\"rounded,filled\", fillcolor=white, fontname=\"Helvetica\", fontsize=11];\n"
    << "  edge [fontname=\"Helvetica\", fontsize=9];\n";
  const std::map<Layer, const char*> colour{{Layer::deliberate, "#e8eef9"}, {Layer::sequencing, "#eaf5e6"}, {Layer::reactive, "#fbf0e2"}};
  for (Layer layer : {Layer::deliberate, Layer::sequencing, Layer::reactive}) {
    const std::string l(to_string(layer));
    o << "  subgraph cluster_" << l << " {\n    label=" << dot_id(std::string(1, static_cast<char>(l[0] - 32)) + l.substr(1) + " layer")
      << ";\n    style=filled; color=\"#999999\"; fillcolor=\"" << colour.at(layer) << "\";\n";
    for (const DescribedModule& m : r.modules) {
      if (m.layer != layer) continue;
      std::string label = m.name + "\\n<" + std::string(to_string(m.kind)) + ">";
      if (m.core) label = m.name + "\\n<core>";
      o << "    " << dot_id(m.name) << " [label=\"" << label << "\"" << (m.core ? ", penwidth=2" : "")
        << (m.kind == ModuleKind::behavior ? ", shape=ellipse" : "") << "];\n";
    }
    o << "    \"_" << l << "\" [shape=point, style=invis, width=0, height=0, label=\"\"];\n";
    if (layer == Layer::sequencing) {
      std::string label = "configurations\\n<core>";
      for (const auto& p : r.processes) label += "\\n" + p;
      o << "    \"configurations\" [shape=note, penwidth=2, label=\"" << label << "\"];\n";
    }
    o << "  }\n";
  }
  // Edges: provider -> consumer, one per pair with every information they exchange.
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> edges;
  for (const DescribedModule& c : r.modules) {
    for (const std::string& in : c.inputs) {
      const std::string info = base_name(in);
      const auto bound = c.from.find(info);  // only the provider `from:` names, where it names one
      for (const DescribedModule& p : r.modules) {
        if (bound != c.from.end() && p.name != bound->second) continue;
        if (&p != &c && std::find(p.outputs.begin(), p.outputs.end(), info) != p.outputs.end()) edges[{p.name, c.name}].push_back(info);
      }
    }
  }
  // Stack the layers as in the paper: deliberate on top, reactive at the bottom. Information
  // flowing up (sensor data to the localizer) must not pull a lower layer above a higher one.
  std::map<std::string, int> rank;
  for (const DescribedModule& m : r.modules) rank[m.name] = static_cast<int>(m.layer);
  // Every node of a layer above the anchor of the next layer, every node below its own anchor.
  auto below = [&](const std::string& node, Layer layer) {
    if (layer != Layer::deliberate) o << "  \"_" << to_string(layer) << "\" -> " << dot_id(node) << " [style=invis];\n";
    if (layer != Layer::reactive) {
      o << "  " << dot_id(node) << " -> \"_" << to_string(static_cast<Layer>(static_cast<int>(layer) + 1)) << "\" [style=invis];\n";
    }
  };
  for (const DescribedModule& m : r.modules) below(m.name, m.layer);
  below("configurations", Layer::sequencing);
  for (const auto& [pc, infos] : edges) {
    o << "  " << dot_id(pc.first) << " -> " << dot_id(pc.second) << " [label=" << dot_id(join(infos, ", "))
      << (rank[pc.first] > rank[pc.second] ? ", constraint=false" : "") << "];\n";
  }
  // Command channels: behavior -> coordinator -> hardware, bold.
  std::vector<std::string> fused;
  for (const DescribedModule& m : r.modules) {
    if (m.writes.empty()) continue;
    std::vector<std::string> labels;
    for (const ChannelWrite& w : m.writes) labels.push_back(w.label());
    fused.insert(fused.end(), labels.begin(), labels.end());
    o << "  " << dot_id(m.name) << " -> " << dot_id(CoreNames::kCoordinator) << " [label=" << dot_id(join(labels))
      << ", style=bold, color=\"#8a4b08\", constraint=false];\n";
  }
  for (const DescribedModule& m : r.modules) {
    if (!m.hardware || m.channels.empty() || fused.empty()) continue;
    std::vector<std::string> names;
    for (const ChannelSpec& c : m.channels) names.push_back(c.name);
    o << "  " << dot_id(CoreNames::kCoordinator) << " -> " << dot_id(m.name) << " [label=" << dot_id(join(names))
      << ", style=bold, color=\"#8a4b08\"];\n";
  }
  o << "  " << dot_id(CoreNames::kSupervisor) << " -> \"configurations\" [style=dashed, arrowhead=none, label=\"runs\"];\n";
  for (const DescribedModule& m : r.modules) {
    if (m.kind == ModuleKind::behavior) {
      o << "  " << dot_id(CoreNames::kSupervisor) << " -> " << dot_id(m.name) << " [style=dashed, color=\"#777777\", label=\"activates\"];\n";
    }
  }
  o << "}\n";
  return o.str();
}

}  // namespace tripodal
