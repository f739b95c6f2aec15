#include "tripodal/hri/hri_robot_module.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "tripodal/hardware/buttons.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/navi/grid_maps.hpp"

namespace tripodal {

namespace {

// Nodes of a command are "node{n}" in the regions file: "node 1" in words is node1.
constexpr std::string_view kNodePrefix = "node";

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\n");
  return std::string(s.substr(b, e - b + 1));
}

}  // namespace

std::map<std::string, std::string, std::less<>> parse_button_bindings(std::string_view text, const SourceLocation& where) {
  std::map<std::string, std::string, std::less<>> out;
  Diagnostics d;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(';', start), text.size());
    const std::string item = trim(text.substr(start, end - start));
    start = end + 1;
    if (item.empty()) continue;
    const auto eq = item.find('=');
    const std::string name = eq == std::string::npos ? std::string() : trim(std::string_view(item).substr(0, eq));
    const std::string request = eq == std::string::npos ? std::string() : trim(std::string_view(item).substr(eq + 1));
    if (name.empty() || request.empty()) {
      d.error(where, "buttons: '" + item + "' is not NAME=REQUEST (e.g. hello=Introduce yourself.)");
    } else if (!out.emplace(name, request).second) {
      d.error(where, "buttons: button '" + name + "' is bound twice");
    }
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
  return out;
}

const ModuleManifest& CHri::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("Hri", ModuleKind::hri, Layer::deliberate)
          .description(
              "the HRI of the guide robot: the RKMS knowledge, the LED buttons, the exhibit hall's nodes for "
              "the planner")
          .outputs({"node", "exhibit_here"})
          .text("knowledge", std::string(), "the RKMS knowledge file (XML, configs/hri/rkms.xsd), relative to the profile")
          .text("buttons", std::string(), "LED buttons and the requests they stand for: \"hello=Introduce yourself.; ...\"")
          .number("exhibit_radius_m", 1.0, "m", "how near a node the robot must be for exhibit_here()", 0.1, 10.0)
          .build();
  return m;
}

void CHri::on_configure(const ParameterSet& params) {
  knowledge_file_ = params.string("knowledge");
  exhibit_radius_m_ = params.number("exhibit_radius_m");
  buttons_ = parse_button_bindings(params.string("buttons"), where());
  if (knowledge_file_.empty())
    throw ConfigError(where(), "module type 'Hri' needs knowledge: an RKMS file (configs/hri/rkms.xsd)");
}

void CHri::on_start(ModuleContext& context) {
  std::filesystem::path file = knowledge_file_;
  if (file.is_relative()) file = context.profile_dir / file;
  store_ = std::make_unique<KnowledgeStore>(file);
  maps_ = context.modules != nullptr ? context.modules->find<navi::CGridMaps>() : nullptr;
  if (maps_ == nullptr) throw ConfigError(where(), "module type 'Hri' needs a GridMaps module (the hall's nodes)");
  panel_ = dynamic_cast<ButtonPanel*>(context.hardware);
}

KnowledgeStore& CHri::knowledge_store() const {
  if (!store_) throw std::logic_error("CHri::knowledge_store: the module has not started");
  return *store_;
}

std::vector<std::string> CHri::take_presses() {
  return std::exchange(presses_, {});
}

void CHri::on_update(ModuleContext& context) {
  context.heartbeat = true;
  if (panel_ == nullptr) return;
  for (std::string& b : panel_->take_button_presses()) {
    context.post("button." + b, "LED button " + b + " pressed");
    presses_.push_back(std::move(b));
  }
}

std::optional<KnowledgeAnswer> CHri::on_answer(std::string_view function, std::string_view argument,
                                               const NavigationData& navigation) const {
  const navi::RegionMap& regions = maps_->regions();
  std::string known;
  for (const navi::MapNode& n : regions.nodes) {
    if (n.name.starts_with(kNodePrefix)) known += (known.empty() ? "" : ", ") + n.name.substr(kNodePrefix.size());
  }
  KnowledgeAnswer a;
  if (function == "node") {
    const std::string name =
        argument.starts_with(kNodePrefix) ? std::string(argument) : std::string(kNodePrefix) + std::string(argument);
    if (regions.node(name) == nullptr) {
      a.error = "unknown node '" + std::string(argument) + "' (known: " + known + ")";
      return a;
    }
    a.ok = true;
    a.items = {name};
    return a;
  }
  if (function == "exhibit_here") {
    const navi::MapNode* nearest = nullptr;
    double best = std::numeric_limits<double>::infinity();
    for (const navi::MapNode& n : regions.nodes) {
      if (!n.name.starts_with(kNodePrefix)) continue;
      const double d = std::hypot(n.pose.x_m - navigation.map_from_base.x_m, n.pose.y_m - navigation.map_from_base.y_m);
      if (d < best) {
        best = d;
        nearest = &n;
      }
    }
    if (nearest == nullptr || best > exhibit_radius_m_) {
      a.error = nearest == nullptr ? "the map has no node"
                                   : "I am not at an exhibit: the nearest is " + nearest->name + ", " +
                                         std::to_string(static_cast<int>(std::lround(best))) + " m away";
      return a;
    }
    a.ok = true;
    a.items = {nearest->name.substr(kNodePrefix.size())};
    return a;
  }
  return std::nullopt;
}

void register_hri_modules(ModuleRegistry& registry) {
  registry.add<CHri>();
}

}  // namespace tripodal
