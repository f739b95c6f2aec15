#include "guide_hri.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "run_outputs.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

namespace tripodal::app {

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
