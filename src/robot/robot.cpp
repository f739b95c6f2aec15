#include "tripodal/robot/robot.hpp"

#include <algorithm>
#include <optional>

#include "tripodal/core/net_loader.hpp"

namespace tripodal {

namespace {

// The planner's questions go to the module that lists the question among its outputs.
class RobotKnowledge final : public TaskKnowledge {
 public:
  std::vector<std::pair<std::string, RobotModule*>> providers;  // output name -> module
  [[nodiscard]] ListResult list(std::string_view function, std::string_view argument) const override {
    for (const auto& [info, m] : providers) {
      if (info != function) continue;
      try {
        if (auto r = m->answer(function, argument)) return *r;
      } catch (const std::exception& e) {
        return {false, {}, "the module providing '" + std::string(function) + "' failed: " + e.what()};
      }
    }
    return {false, {}, "no module of this robot answers '" + std::string(function) + "'"};
  }
};

}  // namespace

struct Robot::Impl {
  const Clock& clock;
  RobotOptions options;
  RobotDescription description;
  BehaviorSet behaviors;
  ProcessRegistry processes;
  TaskLibrary tasks;
  RecoveryPolicy recovery;
  std::vector<std::pair<std::string, std::unique_ptr<RobotModule>>> modules;
  RobotKnowledge knowledge;
  CBehaviorCoordinator coordinator;
  std::unique_ptr<CProcessSupervisor> supervisor;
  std::unique_ptr<CPlanner> planner;
  BehaviorContext activation_context;  // what behaviors see when the supervisor activates them

  Impl(const Clock& c, RobotOptions o) : clock(c), options(std::move(o)), behaviors(c) {}
};

Robot::Robot(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Robot::~Robot() = default;

std::unique_ptr<Robot> Robot::assemble(const RobotProfile& profile, const RobotCatalog& catalog, const Clock& clock,
                                       RobotOptions options) {
  auto m = std::make_unique<Impl>(clock, std::move(options));
  Diagnostics d;
  auto collect = [&](const auto& fn) {
    try {
      fn();
    } catch (const ConfigError& e) {
      d.append(e.diagnostics());
    }
  };

  std::vector<std::string> process_names;
  for (const ProcessEntry& p : profile.processes) process_names.push_back(p.name);
  auto is_process = [&](std::string_view n) { return std::find(process_names.begin(), process_names.end(), n) != process_names.end(); };
  std::vector<std::string> behavior_names;
  for (const ModuleEntry& b : profile.behaviors) behavior_names.push_back(b.name);
  auto is_behavior = [&](std::string_view n) { return std::find(behavior_names.begin(), behavior_names.end(), n) != behavior_names.end(); };

  if (!profile.tasks.empty()) {
    collect([&] { m->tasks = TaskLibrary::load(profile.tasks, TaskLoadOptions{is_process}); });
  }
  if (!profile.recovery.empty()) collect([&] { m->recovery = RecoveryPolicy::load(profile.recovery, is_process); });

  m->description = describe_robot(profile, catalog, knowledge_inputs(m->tasks), d);

  // Processes: nets, parameters and their own recovery rules.
  if (m->options.register_process_types) m->options.register_process_types(m->processes);
  auto load = m->options.load_net;
  if (!load) {
    load = [&](const std::filesystem::path& f) {
      LoadOptions lo;
      lo.is_known_behavior = is_behavior;
      lo.structural_warnings = false;
      return load_net_or_throw(f, lo);
    };
  }
  for (const ProcessEntry& p : profile.processes) {
    collect([&] {
      ProcessDefinition def;
      def.name = p.name;
      def.type = p.type;
      def.parameters = p.parameters;
      def.where = p.where;
      def.net = load(p.net);
      if (!p.module.empty()) def.module = load(p.module);
      if (!p.recovery.empty()) def.recovery = RecoveryPolicy::load(p.recovery, is_process).rules();
      for (const Place& place : def.net.places()) {
        if (place.behavior && !is_behavior(place.behavior->behavior)) {
          d.error(p.net_where.line > 0 ? p.net_where : p.where,
                  "process '" + p.name + "': place '" + place.id + "' of " + p.net.filename().string() + " binds behavior '" +
                      place.behavior->behavior + "', which the robot does not list under behaviors");
        }
      }
      m->processes.add(std::move(def));
    });
  }

  // Behaviors and modules.
  for (const ModuleEntry& b : profile.behaviors) {
    if (catalog.behaviors == nullptr || !catalog.behaviors->contains(b.type)) {
      d.error(b.where, "behavior '" + b.name + "' cannot be started: no behavior type '" + b.type + "' is registered");
      continue;
    }
    collect([&] {
      auto inst = catalog.behaviors->create(b.type);
      if (inst->name() != b.name) {
        throw ConfigError(b.where, "behavior '" + b.name + "': type '" + b.type + "' creates '" + std::string(inst->name()) +
                                       "'; behaviors are known to the nets by their type name");
      }
      m->behaviors.add(std::move(inst));
    });
  }
  for (const auto* list : {&profile.resources, &profile.navigation, &profile.hri, &profile.modules}) {
    for (const ModuleEntry& e : *list) {
      if (catalog.modules == nullptr || !catalog.modules->can_create(e.type)) {
        d.error(e.where, "module '" + e.name + "' cannot be started: no factory is registered for type '" + e.type + "'");
        continue;
      }
      collect([&] { m->modules.emplace_back(e.name, catalog.modules->create(ModuleConfig{e.name, e.type, e.parameters, e.where})); });
    }
  }
  if (d.has_errors()) throw ConfigError(d);

  // Wiring: the coordinator's inputs in profile order (earlier behaviors win ties by priority).
  int priority = static_cast<int>(profile.behaviors.size());
  for (const ModuleEntry& b : profile.behaviors) m->coordinator.add_input(CoordinatorInputConfig{b.name, priority--});
  m->activation_context.period = m->options.period;
  m->activation_context.resources = m->options.resources;
  m->activation_context.navi = m->options.navigation;
  m->activation_context.base = m->options.base;
  m->behaviors.set_context(&m->activation_context);
  m->supervisor = std::make_unique<CProcessSupervisor>(m->behaviors, clock, m->options.supervisor);
  for (auto& [name, mod] : m->modules) {
    mod->attach(ModulePort(*m->supervisor, name));
    for (const DescribedModule& dm : m->description.modules) {
      if (dm.name != name) continue;
      for (const std::string& out : dm.outputs) m->knowledge.providers.emplace_back(out, mod.get());
    }
  }
  for (const auto* list : {&profile.resources, &profile.navigation, &profile.hri, &profile.modules}) {
    for (const ModuleEntry& e : *list) {
      if (e.watchdog_timeout) m->supervisor->watch_module(e.name, *e.watchdog_timeout, e.watchdog_event);
    }
  }
  m->planner = std::make_unique<CPlanner>(m->tasks, m->recovery, m->knowledge, m->processes, *m->supervisor, clock,
                                          m->options.planner);
  return std::unique_ptr<Robot>(new Robot(std::move(m)));
}

CommandAnswer Robot::command(std::string_view text) { return impl_->planner->command(text); }

void Robot::step() {
  Impl& m = *impl_;
  const Time now = m.clock.now();
  for (auto& [name, mod] : m.modules) {
    try {
      mod->update(now);
    } catch (const std::exception& e) {
      m.supervisor->report_module_fault(name, e.what());
    } catch (...) {
      m.supervisor->report_module_fault(name, "unknown exception");
    }
  }
  BehaviorContext ctx;
  ctx.now = now;
  ctx.period = m.options.period;
  ctx.resources = m.options.resources;
  ctx.navi = m.options.navigation;
  ctx.base = m.options.base;
  m.activation_context = ctx;
  m.behaviors.step_active(ctx, [&](std::string_view name, const std::optional<Twist2D>& cmd) {
    auto id = m.coordinator.find_input(name);
    if (!id) return;
    if (cmd) m.coordinator.submit(*id, *cmd, now);
    else m.coordinator.withdraw(*id);
  });
  m.coordinator.update(now);
  if (m.planner->busy()) {
    m.planner->step();
  } else {
    m.supervisor->step();  // module events and watchdogs keep flowing between tasks
  }
}

const RobotDescription& Robot::description() const noexcept { return impl_->description; }
CPlanner& Robot::planner() noexcept { return *impl_->planner; }
CProcessSupervisor& Robot::supervisor() noexcept { return *impl_->supervisor; }
BehaviorSet& Robot::behaviors() noexcept { return impl_->behaviors; }
const ProcessRegistry& Robot::processes() const noexcept { return impl_->processes; }
const CBehaviorCoordinator& Robot::coordinator() const noexcept { return impl_->coordinator; }

RobotModule* Robot::module(std::string_view name) noexcept {
  for (auto& [n, mod] : impl_->modules) {
    if (n == name) return mod.get();
  }
  return nullptr;
}

}  // namespace tripodal
