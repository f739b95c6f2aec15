#include "guide_hri.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "run_outputs.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

namespace tripodal::app {

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
          .description("the HRI of the guide robot: the RKMS knowledge, the LED buttons, the exhibit hall's nodes for the planner")
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
  if (knowledge_file_.empty()) throw ConfigError(where(), "module type 'Hri' needs knowledge: an RKMS file (configs/hri/rkms.xsd)");
}

void CHri::on_start(ModuleContext& context) {
  std::filesystem::path file = knowledge_file_;
  if (file.is_relative()) file = context.profile_dir / file;
  store_ = std::make_unique<KnowledgeStore>(file);
  maps_ = context.modules != nullptr ? context.modules->find<navi::CGridMaps>() : nullptr;
  if (maps_ == nullptr) throw ConfigError(where(), "module type 'Hri' needs a GridMaps module (the hall's nodes)");
  auto* hw = dynamic_cast<sim::SimHardware*>(context.hardware);
  sim_ = hw != nullptr ? &hw->simulator() : nullptr;
}

KnowledgeStore& CHri::knowledge_store() const {
  if (!store_) throw std::logic_error("CHri::knowledge_store: the module has not started");
  return *store_;
}

std::vector<std::string> CHri::take_presses() { return std::exchange(presses_, {}); }

void CHri::on_update(ModuleContext& context) {
  context.heartbeat = true;
  if (sim_ == nullptr) return;
  for (std::string& b : sim_->take_button_presses()) {
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
    const std::string name = argument.starts_with(kNodePrefix) ? std::string(argument) : std::string(kNodePrefix) + std::string(argument);
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

std::string command_text(const TaskLibrary& tasks, const Understanding& u) {
  for (const TaskTemplate& t : tasks.templates()) {
    if (t.name != u.task || t.commands.empty()) continue;
    std::string out;
    for (const PatternToken& tok : t.commands.front().tokens) {
      if (tok.kind == PatternToken::Kind::optional_word) continue;
      std::string word = tok.text;
      if (tok.kind != PatternToken::Kind::word) {
        const auto it = u.slots.find(tok.text);
        word = it != u.slots.end() ? it->second : std::string();
      }
      if (!word.empty()) out += (out.empty() ? "" : " ") + word;
    }
    return out;
  }
  return u.task;
}

// The HRI's knowledge of the hall: the planner's functions as the robot's Hri module answers them
// from where the robot stands now.
class GuideHri::Hall final : public TaskKnowledge {
 public:
  Hall(const CHri& hri, const Robot& robot) : hri_(hri), robot_(robot) {}
  [[nodiscard]] ListResult list(std::string_view function, std::string_view argument) const override {
    const auto a = hri_.answer(function, argument, robot_.navigation());
    if (!a) return {false, {}, "I know nothing of " + std::string(function) + "()"};
    return {a->ok, a->items, a->error};
  }

 private:
  const CHri& hri_;
  const Robot& robot_;
};

namespace {

std::string step_text(const ProcessStep& s) {
  std::string out = s.process + "(";
  for (std::size_t i = 0; i < s.params.size(); ++i) out += (i ? ", " : "") + s.params[i].name + "=" + s.params[i].value;
  return out + ")";
}

}  // namespace

GuideHri::GuideHri(Robot& robot, CHri& hri, const Clock& clock, const std::filesystem::path& tasks_file, Options options)
    : robot_(robot), tasks_(TaskLibrary::load(tasks_file)), hall_(std::make_unique<Hall>(hri, robot)) {
  // The hall's local sources: the clock's time of day (the run starts at 14:00), the battery, and
  // a fixed forecast, one description per day.
  providers_.add("time", std::make_unique<ClockTimeProvider>(clock, std::chrono::hours(14)));
  providers_.add("battery", std::make_unique<BatteryProvider>(options.battery_charge ? std::move(options.battery_charge)
                                                                                                 : std::function<double()>([] { return -1.0; })));
  providers_.add("weather", std::make_unique<WeatherTableProvider>(
                                clock, std::chrono::hours(14), std::vector<std::string>{"sunny and mild, 22 degrees", "cloudy, 18 degrees"}));
  const TaskStarter starter = [this](const Understanding& u) -> std::string {
    const CommandAnswer a = robot_.command(command_text(tasks_, u));
    if (a.accepted) started_task_ = u.task;
    return a.accepted ? std::string() : a.text;
  };
  HriOptions hri_options;
  hri_options.buttons = hri.buttons();
  service_ = std::make_unique<StoreBackedHri>(hri.knowledge_store(), tasks_, *hall_, providers_, starter, std::move(hri_options),
                                              std::move(options.voice));
  robot_.planner().add_observer(*this);
}

GuideHri::~GuideHri() { robot_.planner().remove_observer(*this); }

HriModule& GuideHri::module() {
  HriModule& m = service_->module();
  m.set_internal_state(state_);
  return m;
}

std::vector<HriReply> GuideHri::update() {
  std::vector<HriReply> out;
  HriModule& m = module();
  for (; !explain_.empty(); explain_.pop_front()) out.push_back(m.handle(explain_.front()));
  return out;
}

void GuideHri::on_task_started(const TaskReport& task, const Plan& /*plan*/, Time /*now*/) {
  state_ = {task.task, "running", "", ""};
  last_task_end_.clear();
}

void GuideHri::on_process_started(const ProcessRecord& p) {
  state_.process = step_text(p.step);
  if (p.step.process != "PrExplain") return;
  for (const BindingParam& b : p.step.params) {
    if (b.name == "topic") explain_.push_back(b.value);
  }
}

void GuideHri::on_process_succeeded(const ProcessRecord& p) { finished(p, "succeeded"); }

void GuideHri::on_process_failed(const ProcessRecord& p) {
  state_.fault = p.message;
  finished(p, "failed: " + p.message);
}

void GuideHri::on_task_succeeded(const TaskReport& /*task*/) { ended("succeeded"); }

void GuideHri::on_task_failed(const TaskReport& task) {
  if (!task.reason.empty()) state_.fault = task.reason;
  ended("failed");
}

void GuideHri::finished(const ProcessRecord& p, const std::string& how) {
  processes_.push_back(fixed(to_seconds(p.started), 3) + "-" + fixed(to_seconds(p.finished.value_or(p.started)), 3) + " " + p.run + " " +
                       step_text(p.step) + " " + how);
  state_.process.clear();
}

void GuideHri::ended(const std::string& how) {
  state_.task_state = how;
  state_.process.clear();
  last_task_end_ = how;
}

void register_guide_modules(ModuleRegistry& registry) {
  registry.add<CHri>();
}

}  // namespace tripodal::app
