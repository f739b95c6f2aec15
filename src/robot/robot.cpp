#include "tripodal/robot/robot.hpp"

#include <algorithm>
#include <atomic>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>

#include "tripodal/behaviors/navigation_behaviors.hpp"
#include "tripodal/behaviors/safety_behaviors.hpp"
#include "tripodal/behaviors/teleop.hpp"
#include "tripodal/core/net_loader.hpp"
#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/reactive/reactive_config.hpp"
#include "tripodal/resources/resource_faults.hpp"
#include "tripodal/robot/battery_monitor.hpp"
#include "tripodal_reactive_internal/sim_loop_driver.hpp"

namespace tripodal {

namespace {

// The planner's questions go to the module that lists the question among its outputs.
class RobotKnowledge final : public TaskKnowledge {
 public:
  std::vector<std::pair<std::string, const CModule*>> providers;  // output name -> module
  const NavigationData* navigation = nullptr;
  [[nodiscard]] ListResult list(std::string_view function, std::string_view argument) const override {
    for (const auto& [info, m] : providers) {
      if (info != function) continue;
      try {
        if (auto r = m->answer(function, argument, *navigation)) return {r->ok, std::move(r->items), std::move(r->error)};
      } catch (const std::exception& e) {
        return {false, {}, "the module providing '" + std::string(function) + "' failed: " + e.what()};
      }
    }
    return {false, {}, "no module of this robot answers '" + std::string(function) + "'"};
  }
};

// The profile's text parameters of one entry, with the run's overrides applied.
ParameterValues parameters_of(const ModuleEntry& e, const std::vector<ParameterOverride>& overrides) {
  ParameterValues out;
  for (const auto& [k, v] : e.parameters) out.emplace(k, Value{v});
  for (const ParameterOverride& o : overrides) {
    if (o.module == e.name) out.insert_or_assign(o.parameter, Value{o.value});
  }
  return out;
}

// A controller's full configuration (limits, wheel geometry): the reactive configuration file its
// profile entry names in the parameter `config`, its types checked against `registry` (the
// application's, so that its own controller types are known).
ControllerConfig controller_config(const RobotProfile& p, const ModuleEntry& e, const ControllerRegistry& registry) {
  const auto it = e.parameters.find("config");
  if (it == e.parameters.end()) {
    throw ConfigError(e.where, "controller '" + e.name +
                                   "' needs parameters: {config: FILE}, the reactive configuration with its limits and wheels");
  }
  const std::filesystem::path file = p.dir / it->second;
  const ReactiveConfig rc = load_reactive_config(file.string(), registry);
  const ControllerConfig* c = rc.find_controller(e.name);
  if (c == nullptr) throw ConfigError(e.where, file.string() + " configures no controller named '" + e.name + "'");
  if (c->type != e.type) {
    throw ConfigError(e.where, "controller '" + e.name + "' is of type '" + e.type + "' here but '" + c->type + "' in " + file.string());
  }
  return *c;
}

// Whether the type of entry `e` of `profile` is registered in its family's registry.
bool registered(const RobotProfile& profile, const RobotPlugins& plugins, const ModuleEntry& e) {
  if (profile.hardware && &e == &*profile.hardware) return plugins.hardware.contains(e.type);
  switch (e.kind) {
    case ModuleKind::behavior: return plugins.behaviors.contains(e.type);
    case ModuleKind::controller: return plugins.controllers.contains(e.type);
    case ModuleKind::resource: return plugins.resources.contains(e.type);
    default: return plugins.modules.contains(e.type);
  }
}

// What the checks of a profile load on the way, for Robot::assemble to keep.
struct CheckedProfile {
  RobotDescription description;
  TaskLibrary tasks;
  RecoveryPolicy recovery;
  std::vector<ProcessDefinition> processes;
  std::vector<ControllerConfig> controllers;  // of the loops that drive one, in loop order
  std::map<std::string, std::string, std::less<>> behavior_types;  // profile name -> type; not the safety ones
};

// Facts: a guard reading a fact no module sets waits on the net's default for ever (the robot
// docks, the net waits for `charging`). Every fact the nets read must be among the outputs of a
// module of the profile (a type that calls ModuleContext::set_fact lists its facts there); one the
// profile lists under external_facts comes from the application, and is only noted. Reported at
// the first guard of each net that reads it, with the process entry of the profile.
void check_facts(const RobotProfile& profile, const CheckedProfile& checked, Diagnostics& d) {
  std::set<std::string, std::less<>> provided;
  for (const DescribedModule& m : checked.description.modules) provided.insert(m.outputs.begin(), m.outputs.end());
  const std::vector<std::string> provided_names(provided.begin(), provided.end());
  auto is_external = [&](std::string_view f) {
    return std::find(profile.external_facts.begin(), profile.external_facts.end(), f) != profile.external_facts.end();
  };
  for (const ProcessDefinition& def : checked.processes) {
    const auto entry = std::find_if(profile.processes.begin(), profile.processes.end(),
                                    [&](const ProcessEntry& p) { return p.name == def.name; });
    for (const PetriNet* net : {&def.net, def.module ? &*def.module : nullptr}) {
      if (net == nullptr) continue;
      std::set<std::string, std::less<>> reported;
      for (const Transition& t : net->transitions()) {
        if (!t.guard) continue;
        for (const std::string& name : t.guard->identifiers()) {
          if (net->find_fact(name) == nullptr || provided.count(name) != 0 || !reported.insert(name).second) continue;
          const std::string what = "process '" + def.name + "': the guard of transition '" + t.id + "' reads fact '" + name +
                                   "', which no module of robot '" + profile.name + "' provides (lists among its outputs)";
          if (is_external(name)) {
            d.warning(t.where, what + "; the profile lists it under external_facts (" + profile.external_facts_where.str() +
                                   "), so the application must set it (CProcessSupervisor::set_fact)");
            continue;
          }
          const auto close = closest_name(name, provided_names);
          d.error(t.where, what + (close ? "; did you mean '" + *close + "'?" : std::string()) +
                               "; add a module that sets it (BatteryMonitor sets charging and "
                               "battery_percent), or list it under external_facts: when the application sets it");
          if (entry != profile.processes.end()) d.note(entry->where, "process '" + def.name + "' is listed here");
        }
      }
    }
  }
}

// Whether a type declared in the profile but not registered refuses the robot (assembly) or is
// noted (the diagram of a design, whose modules may not be implemented yet).
enum class DeclaredTypes { must_be_registered, may_be_designs };

// The names the checks of a profile look up: its processes and its behaviors, the safety ones
// apart (the loop's own, active from the start: the nets do not activate them).
class ProfileNames {
 public:
  explicit ProfileNames(const RobotProfile& profile) : profile_(profile) {
    for (const ModuleEntry& b : profile.behaviors) {
      if (!b.safety) behavior_types_.emplace(b.name, b.type);
    }
  }
  [[nodiscard]] bool is_process(std::string_view n) const {
    return std::any_of(profile_.processes.begin(), profile_.processes.end(), [&](const ProcessEntry& p) { return p.name == n; });
  }
  [[nodiscard]] bool is_behavior(std::string_view n) const { return behavior_types_.count(n) != 0; }
  [[nodiscard]] bool is_safety(std::string_view n) const {
    return std::any_of(profile_.behaviors.begin(), profile_.behaviors.end(),
                       [&](const ModuleEntry& b) { return b.safety && b.name == n; });
  }
  [[nodiscard]] const std::map<std::string, std::string, std::less<>>& behavior_types() const noexcept { return behavior_types_; }

 private:
  const RobotProfile& profile_;
  std::map<std::string, std::string, std::less<>> behavior_types_;  // profile name -> type
};

// A type declared in the profile (layer, inputs, outputs) draws the diagram of a module designed
// before it is implemented; running needs the type itself. (describe_robot reported the undeclared
// unknown ones.)
void check_declared_types(const RobotProfile& profile, const RobotPlugins& plugins, DeclaredTypes declared, Diagnostics& d) {
  std::vector<const ModuleEntry*> entries;
  if (profile.hardware) entries.push_back(&*profile.hardware);
  for (const ModuleEntry* e : profile.all_modules()) entries.push_back(e);
  for (const ModuleEntry* e : entries) {
    if (!(e->layer || e->inputs || e->outputs) || registered(profile, plugins, *e)) continue;
    const bool is_hardware = profile.hardware && e == &*profile.hardware;
    const std::string kind = is_hardware ? "hardware" : std::string(to_string(e->kind));
    const bool own_family = is_hardware || e->kind == ModuleKind::behavior || e->kind == ModuleKind::controller ||
                            e->kind == ModuleKind::resource;
    std::string why = kind + " '" + e->name + "' cannot be started: its type '" + e->type +
                      "' is declared here (layer, inputs, outputs), which draws the diagram, but no " +
                      (own_family ? kind : std::string("module")) + " type of that name is registered";
    if (declared == DeclaredTypes::must_be_registered) {
      d.error(e->where, std::move(why));
    } else {
      d.warning(e->where, std::move(why) + " (a design: `tripodal run` refuses it)");
    }
  }
}

// One process of the profile: its nets, parameters and own recovery rules; a place binding a
// behavior the robot does not list, or runs as a safety behavior, is an error. Throws ConfigError
// for a net that does not load.
ProcessDefinition check_process(const ProcessEntry& p, const ProfileNames& names,
                                const std::function<PetriNet(const std::filesystem::path&)>& load, Diagnostics& d) {
  ProcessDefinition def;
  def.name = p.name;
  def.type = p.type;
  def.parameters = p.parameters;
  def.where = p.where;
  def.net = load(p.net);
  if (!p.module.empty()) {
    def.module = load(p.module);
    check_module_net(*def.module, p.name, d);
  }
  if (!p.recovery.empty()) {
    def.recovery = RecoveryPolicy::load(p.recovery, [&](std::string_view n) { return names.is_process(n); }).rules();
  }
  for (const Place& place : def.net.places()) {
    if (!place.behavior) continue;
    const std::string& behavior = place.behavior->behavior;
    const char* why = names.is_safety(behavior)
                          ? "which the robot runs as a safety behavior (safety: true: always active, never a net's)"
                      : !names.is_behavior(behavior) ? "which the robot does not list under behaviors"
                                                     : nullptr;
    if (why == nullptr) continue;
    d.error(p.net_where.line > 0 ? p.net_where : p.where, "process '" + p.name + "': place '" + place.id + "' of " +
                                                              p.net.filename().string() + " binds behavior '" + behavior + "', " +
                                                              why);
  }
  return def;
}

// Every check of a profile that builds no instance — the tasks and recovery rules, the diagram's
// providers and layering, every type registered, the process nets against the behaviors the profile
// lists, the controllers' reactive configurations — so that `tripodal describe` (check_robot) says
// what Robot::assemble would refuse. Problems go to `d`, located.
CheckedProfile check_profile(const RobotProfile& profile, const RobotPlugins& plugins,
                             std::function<PetriNet(const std::filesystem::path&)> load, DeclaredTypes declared, Diagnostics& d) {
  CheckedProfile out;
  auto collect = [&](const auto& fn) {
    try {
      fn();
    } catch (const ConfigError& e) {
      d.append(e.diagnostics());
    }
  };
  const ProfileNames names(profile);
  out.behavior_types = names.behavior_types();
  auto is_process = [&](std::string_view n) { return names.is_process(n); };
  if (!profile.tasks.empty()) {
    collect([&] { out.tasks = TaskLibrary::load(profile.tasks, TaskLoadOptions{is_process}); });
  }
  if (!profile.recovery.empty()) collect([&] { out.recovery = RecoveryPolicy::load(profile.recovery, is_process); });

  out.description = describe_robot(profile, plugins, knowledge_inputs(out.tasks), d);
  check_declared_types(profile, plugins, declared, d);

  if (!load) {
    load = [&](const std::filesystem::path& f) {
      LoadOptions lo;
      // A safety behavior is known, so that a net binding it is refused by check_process, with the reason.
      lo.is_known_behavior = [&](std::string_view n) { return names.is_behavior(n) || names.is_safety(n); };
      for (const ModuleEntry& b : profile.behaviors) lo.behavior_names.push_back(b.name);
      lo.structural_warnings = false;
      return load_net_or_throw(f, lo);
    };
  }
  for (const ProcessEntry& p : profile.processes) collect([&] { out.processes.push_back(check_process(p, names, load, d)); });
  check_facts(profile, out, d);

  // Behaviors are created anew at each activation; here their types are checked.
  for (const ModuleEntry& b : profile.behaviors) {
    if (plugins.behaviors.contains(b.type) && b.name != b.type) {  // (an unknown type is reported above)
      d.error(b.where, "behavior '" + b.name + "' is of type '" + b.type + "'; behaviors are known to the nets by their type name");
    }
  }
  // The base controllers' configurations, read through the application's controller types.
  for (const LoopEntry& l : profile.loops) {
    for (const ModuleEntry& c : profile.controllers) {
      if (!l.controller.empty() && c.name == l.controller) {
        collect([&] { out.controllers.push_back(controller_config(profile, c, plugins.controllers)); });
      }
    }
  }
  return out;
}

}  // namespace

std::optional<ControllerConfig> base_controller_config(const RobotProfile& profile, const ControllerRegistry& controllers) {
  for (const LoopEntry& l : profile.loops) {
    if (l.controller.empty()) continue;
    for (const ModuleEntry& c : profile.controllers) {
      if (c.name == l.controller) return controller_config(profile, c, controllers);
    }
  }
  return std::nullopt;
}

RobotDescription check_robot(const RobotProfile& profile, const RobotPlugins& plugins, Diagnostics& d) {
  return check_profile(profile, plugins, nullptr, DeclaredTypes::may_be_designs, d).description;
}

namespace {

// What the layering check (rule R6) cannot see from the hardware type's manifest: a channel named by
// a behavior's parameter needs the hardware instance to export channels of its type (the
// simulator's joints come from its world). Named channels R6 has checked.
void check_channel_writes(const RobotProfile& profile, const RobotPlugins& plugins, CHardware* hardware, Diagnostics& d) {
  const CommandChannels* exported = hardware != nullptr ? &hardware->command_channels() : nullptr;
  for (const ModuleEntry& b : profile.behaviors) {
    if (!plugins.behaviors.contains(b.type)) continue;
    for (const ChannelWrite& w : plugins.behaviors.manifest(b.type).writes) {
      if (!w.name.empty()) continue;
      bool any = false;
      for (std::size_t i = 0; exported != nullptr && i < exported->size(); ++i) any = any || exported->spec(i).type == w.type;
      if (!any) {
        d.error(b.where, "behavior '" + b.name + "' writes " + std::string(to_string(w.type)) +
                             " channels (the one its parameter '" + w.parameter + "' names), and " +
                             (hardware != nullptr ? "hardware '" + std::string(hardware->manifest().name) + "'"
                                                  : std::string("the robot (no hardware)")) +
                             " exports none of that type");
      }
    }
  }
}

}  // namespace

struct Robot::Impl final : public BehaviorHost, public ModuleDirectory {
  Clock& clock;
  const RobotPlugins& plugins;
  RobotOptions options;
  RobotDescription description;
  ProcessRegistry processes;
  TaskLibrary tasks;
  RecoveryPolicy recovery;
  Duration sequencing_period{0};
  std::filesystem::path profile_dir;

  // Below the reactive layer, and the reactive layer.
  std::unique_ptr<CHardware> hardware;
  std::vector<ControllerConfig> controller_configs;
  std::vector<std::unique_ptr<CResource>> own_resources;
  // The resources that detect faults of their own (ResourceFaultSource), by instance name.
  std::vector<std::pair<std::string, ResourceFaultSource*>> fault_sources;
  OdometryResource odometry{"odometry"};
  TeleopResource teleop;  // what an operator console drives by hand
  ResourceTable resources;
  // What the modules read: the resources as the behavior loop last handed them over.
  std::unique_ptr<ResourceSnapshot> snapshot;
  std::vector<std::unique_ptr<ControlLoop>> loops;
  std::vector<LoopTimingOptions> loop_timing;  // per loop, from the profile
  LoopTimingOptions sequencing_timing;
  std::map<std::string, std::string, std::less<>> behavior_types;  // profile name -> type
  // A net-bound behavior's parameters in the profile: defaults under the net's (e.g. the cleaning
  // behavior's max_replans on a robot whose safety reflexes make it plan many detours).
  std::map<std::string, ParameterValues, std::less<>> behavior_defaults;

  // The sequencing layer.
  std::vector<std::pair<std::string, std::unique_ptr<CModule>>> modules;
  NavigationData navigation;
  std::uint32_t path_ids = 0;
  RobotKnowledge knowledge;
  std::unique_ptr<CProcessSupervisor> supervisor;
  std::unique_ptr<CPlanner> planner;
  std::vector<std::string> requested_commands;  // by the modules this period (ModuleContext::commands)

  // The behaviors the supervisor activated, as the reactive loop reports them.
  struct ActiveBehavior {
    BehaviorHandle handle;
    BehaviorStatus state = BehaviorStatus::running;
    std::string reason;
  };
  std::map<std::string, ActiveBehavior, std::less<>> active;
  std::vector<LoopEvent> loop_events;

  // Drivers.
  std::recursive_mutex sequencing_mutex;  // the sequencing loop vs. command() from another thread
  std::unique_ptr<SimLoopDriver> schedule;  // simulated time: made at the first run_until
  // The wall-clock runtime: one periodic thread per reactive loop, then the sequencing one.
  std::vector<std::unique_ptr<PeriodicRunner>> runners;
  std::vector<std::uint64_t> deadline_faults_seen;  // per runner, as reported to the supervisor
  RealtimeOptions realtime;
  bool started = false;

  Impl(Clock& c, const RobotPlugins& p, RobotOptions o) : clock(c), plugins(p), options(std::move(o)) {}
  // The supervisor deactivates the running behaviors as it goes, through this host: it must go
  // while the loops, the modules and the record of active behaviors are still here.
  ~Impl() override {
    planner.reset();
    supervisor.reset();
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  // Robot::assemble, a step per section of the profile; each adds its problems to `d`.
  void adopt(CheckedProfile&& checked, const RobotProfile& profile, Diagnostics& d);
  void build_hardware(const RobotProfile& profile, Diagnostics& d);
  void build_resources(const RobotProfile& profile, Diagnostics& d);
  void build_loops(const RobotProfile& profile, Diagnostics& d);
  void start_behaviors(const RobotProfile& profile, Diagnostics& d);
  void build_modules(const RobotProfile& profile, Diagnostics& d);
  void start_modules(Diagnostics& d);
  void build_sequencing(const RobotProfile& profile);

  [[nodiscard]] ControlLoop& behavior_loop() const { return *loops.front(); }

  ModuleContext context(Time now) {
    ModuleContext ctx;
    ctx.now = now;
    ctx.resources = snapshot ? &snapshot->table() : &resources;
    ctx.navigation = &navigation;
    ctx.hardware = hardware.get();
    ctx.modules = this;
    ctx.path_ids = &path_ids;
    ctx.profile_dir = profile_dir;
    if (!loops.empty()) ctx.feedback = behavior_loop().navigation_feedback();
    ctx.task_running = planner && planner->busy();
    return ctx;
  }

  // What a module posted goes to the supervisor under the module's name.
  void deliver(std::string_view module, ModuleContext& ctx) {
    for (ModuleEvent& e : ctx.events) supervisor->post_event(std::move(e.name));
    ctx.events.clear();
    for (auto& [fact, value] : ctx.facts) supervisor->set_fact(std::move(fact), std::move(value));
    ctx.facts.clear();
    if (ctx.heartbeat) supervisor->heartbeat(module);
    ctx.heartbeat = false;
    for (std::string& c : ctx.commands) requested_commands.push_back(std::move(c));
    ctx.commands.clear();
  }

  template <class Fn>
  void for_each_module(ModuleContext& ctx, const Fn& fn) {
    for (auto& [name, m] : modules) {
      try {
        fn(*m);
      } catch (const std::exception& e) {
        supervisor->report_module_fault(name, e.what());
      } catch (...) {
        supervisor->report_module_fault(name, "unknown exception");
      }
      deliver(name, ctx);
    }
  }

  // ModuleDirectory
  [[nodiscard]] std::vector<CModule*> all() const override {
    std::vector<CModule*> out;
    for (const auto& [name, m] : modules) out.push_back(m.get());
    return out;
  }

  // BehaviorHost: the supervisor's behaviors run in the behavior loop.
  [[nodiscard]] bool has(std::string_view behavior) const override { return behavior_types.count(behavior) != 0; }

  void activate(std::string_view behavior, const ParameterValues& params, Time now) override {
    const auto type = behavior_types.find(behavior);
    if (type == behavior_types.end()) throw std::out_of_range("no behavior '" + std::string(behavior) + "'");
    ParameterValues merged;
    if (const auto d = behavior_defaults.find(behavior); d != behavior_defaults.end()) merged = d->second;
    for (const auto& [key, value] : params) merged.insert_or_assign(key, value);
    // Throws ConfigError for bad parameters: the supervisor makes it the behavior's failure.
    const BehaviorHandle h = behavior_loop().activate(plugins.behaviors.create(type->second), merged, behavior);
    active.insert_or_assign(std::string(behavior), ActiveBehavior{h, BehaviorStatus::running, {}});
    const BehaviorActivation a{behavior, merged, now, plugins.behaviors.find(type->second)};
    ModuleContext ctx = context(now);
    for_each_module(ctx, [&](CModule& m) { m.behavior_activated(a, ctx); });
  }

  void deactivate(std::string_view behavior, Time now) override {
    const auto it = active.find(behavior);
    if (it == active.end()) return;
    behavior_loop().deactivate(it->second.handle);
    active.erase(it);
    ModuleContext ctx = context(now);
    for_each_module(ctx, [&](CModule& m) { m.behavior_deactivated(behavior, ctx); });
  }

  [[nodiscard]] BehaviorReport report(std::string_view behavior) const override {
    const auto it = active.find(behavior);
    if (it == active.end()) return {};
    return BehaviorReport{it->second.state, it->second.reason, std::nullopt};
  }

  void collect_loop_reports() {
    loop_events.clear();
    for (auto& loop : loops) loop->collect_events(loop_events);
    for (const LoopEvent& e : loop_events) {
      switch (e.kind) {
        case LoopEvent::Kind::behavior_succeeded:
        case LoopEvent::Kind::behavior_failed: {
          // The supervisor's behaviors run in the behavior loop, each on the input of its name.
          const auto it = active.find(e.input);
          if (e.loop != behavior_loop().name() || it == active.end() || it->second.handle != e.handle) break;
          it->second.state = e.kind == LoopEvent::Kind::behavior_succeeded ? BehaviorStatus::succeeded : BehaviorStatus::failed;
          it->second.reason = std::string(e.reason);
          break;
        }
        case LoopEvent::Kind::controller_fault:
        case LoopEvent::Kind::controller_recovered:
        case LoopEvent::Kind::behavior_signal:
          supervisor->post_event(e.event_name());
          break;
      }
    }
  }

  // A run of overruns of a periodic thread is that loop's fault, once per run.
  void report_deadline_faults() {
    for (std::size_t i = 0; i < runners.size(); ++i) {
      const std::uint64_t faults = runners[i]->deadline_faults();
      if (faults == deadline_faults_seen[i]) continue;
      deadline_faults_seen[i] = faults;
      const PeriodicRunner& r = *runners[i];
      supervisor->report_fault(r.name(), r.name() + ".deadline",
                               "missed its deadline " + std::to_string(r.options().deadline_overruns) +
                                   " times in a row (period " + format_seconds(r.period()) + " s, budget " +
                                   format_seconds(r.budget()) + " s)");
    }
  }

  void step_sequencing() {
    std::lock_guard lock(sequencing_mutex);
    const Time now = clock.now();
    // On simulated time this thread is also the loops': it hands the resources over itself.
    if (!started) snapshot->publish();
    snapshot->refresh();
    report_deadline_faults();
    // The changes of this period (activations, the paths planned for them) reach the loops together.
    std::vector<std::unique_ptr<ControlLoop::ChangeBatch>> batches;
    for (auto& loop : loops) batches.push_back(std::make_unique<ControlLoop::ChangeBatch>(*loop));
    collect_loop_reports();
    // A resource's own faults (a silent peer) go the way of a module's: "<resource>.fault".
    for (auto& [name, source] : fault_sources) {
      for (std::string& why : source->take_faults()) supervisor->report_module_fault(name, std::move(why));
    }
    ModuleContext ctx = context(now);
    for_each_module(ctx, [&](CModule& m) { m.update(ctx); });
    // What the modules asked for at rest (the panel's start button): the planner's answer, a
    // started task or a refusal, reaches its observers as a command's would.
    for (const std::string& c : std::exchange(requested_commands, {})) (void)planner->command(c);
    if (planner->busy()) {
      planner->step();
    } else {
      supervisor->step();  // module events and watchdogs keep flowing between tasks
    }
    if (!loops.empty()) behavior_loop().set_navigation(navigation);
  }
};

namespace {

// Runs one step of assembly, adding the ConfigError it throws to `d`: a profile's problems are
// reported together, not one per run.
template <class Fn>
void collect(Diagnostics& d, const Fn& fn) {
  try {
    fn();
  } catch (const ConfigError& e) {
    d.append(e.diagnostics());
  }
}

// The first loop's coordinator: the hardware's command channels, then its inputs, the profile's
// behaviors in order (earlier ones win ties by priority) under the operator's hand and the safety
// reflexes.
CoordinatorConfig behavior_coordinator_config(const RobotProfile& profile, CHardware* hardware) {
  CoordinatorConfig cc;
  if (hardware != nullptr) {
    // The hardware's command channels, fused by this coordinator and written back each cycle.
    const auto specs = hardware->command_channels().specs();
    cc.channels.assign(specs.begin(), specs.end());
  }
  int priority = static_cast<int>(profile.behaviors.size());
  // Safety inputs rank above every other input (the monitor's operator too), so no lock
  // below the emergency stop masks them.
  const int safety_priority = priority + 1000;
  // Driving by hand (BhTeleop, set by an operator console) ranks just above every other
  // normal input, and its lock masks exactly those: the task stops, safety stays.
  const int top = priority;
  cc.inputs.push_back(
      CoordinatorInputConfig{.name = std::string(kTeleopInput), .priority = top + 1, .timeout = std::chrono::milliseconds(200)});
  cc.locks.push_back(CoordinatorLockConfig{.name = std::string(kTeleopInput), .priority = top});
  for (const ModuleEntry& b : profile.behaviors) {
    if (b.safety) {
      cc.inputs.push_back(CoordinatorInputConfig{.name = b.name, .priority = safety_priority, .role = InputRole::safety});
    } else {
      cc.inputs.push_back(CoordinatorInputConfig{b.name, priority--});
    }
  }
  return cc;
}

}  // namespace

void Robot::Impl::adopt(CheckedProfile&& checked, const RobotProfile& profile, Diagnostics& d) {
  sequencing_period = profile.sequencing_period;
  sequencing_timing = profile.sequencing_timing;
  profile_dir = profile.dir;
  description = std::move(checked.description);
  tasks = std::move(checked.tasks);
  recovery = std::move(checked.recovery);
  behavior_types = std::move(checked.behavior_types);
  for (const ModuleEntry& b : profile.behaviors) {
    if (!b.safety) behavior_defaults.emplace(b.name, parameters_of(b, options.parameters));
  }
  controller_configs = std::move(checked.controllers);
  processes = ProcessRegistry(plugins.processes);
  for (ProcessDefinition& def : checked.processes) collect(d, [&] { processes.add(std::move(def)); });
}

// The hardware (the profile's `hardware:`), and the resources it adds.
void Robot::Impl::build_hardware(const RobotProfile& profile, Diagnostics& d) {
  if (!profile.hardware || !plugins.hardware.contains(profile.hardware->type)) return;
  const ModuleEntry& h = *profile.hardware;
  collect(d, [&] {
    HardwareConfig hc;
    hc.name = h.name;
    hc.type = h.type;
    hc.where = h.where;
    hc.parameters = ParameterSet::resolve(plugins.hardware.manifest(h.type), parameters_of(h, options.parameters), h.where);
    hc.base = controller_configs.empty() ? nullptr : &controller_configs.front();
    hc.profile_dir = profile.dir;
    hardware = plugins.hardware.create_at(h.where, h.type, hc);
    hardware->add_resources(resources);
    // Hardware whose link detects faults of its own (a base on DDS) reports them like a resource.
    if (auto* faults = dynamic_cast<ResourceFaultSource*>(hardware.get())) fault_sources.emplace_back(h.name, faults);
    // So do the hardware's own resources that detect faults (the board's lidar): "<resource>.fault".
    for (std::size_t i = 0; i < resources.size(); ++i) {
      if (auto* faults = dynamic_cast<ResourceFaultSource*>(&resources.at(i)))
        fault_sources.emplace_back(resources.at(i).name(), faults);
    }
  });
}

// The profile's `resources:`.
void Robot::Impl::build_resources(const RobotProfile& profile, Diagnostics& d) {
  for (const ModuleEntry& e : profile.resources) {
    if (!plugins.resources.contains(e.type)) continue;  // check_profile reported it
    collect(d, [&] {
      ResourceConfig rc{e.name,
                        ParameterSet::resolve(plugins.resources.manifest(e.type), parameters_of(e, options.parameters), e.where),
                        e.where, hardware.get()};
      own_resources.push_back(plugins.resources.create_at(e.where, e.type, rc));
      resources.add(*own_resources.back());
      if (auto* faults = dynamic_cast<ResourceFaultSource*>(own_resources.back().get()))
        fault_sources.emplace_back(e.name, faults);
    });
  }
}

// The reactive loops (`loops:`). The first runs the behaviors.
void Robot::Impl::build_loops(const RobotProfile& profile, Diagnostics& d) {
  resources.add(odometry);
  resources.add(teleop);
  bool first = true;
  std::size_t controller_index = 0;
  for (const LoopEntry& l : profile.loops) {
    collect(d, [&] {
      std::unique_ptr<CController> controller;
      if (!l.controller.empty()) {
        if (!hardware)
          throw ConfigError(l.where,
                            "loop '" + l.name + "' drives controller '" + l.controller + "', and the robot has no hardware");
        controller = plugins.controllers.create(controller_configs.at(controller_index++), hardware->wheels());
      }
      const CoordinatorConfig cc = first ? behavior_coordinator_config(profile, hardware.get()) : CoordinatorConfig{};
      ControlLoopOptions lo;
      lo.name = l.name;
      lo.period = l.period;
      lo.max_path_points = CPathFollowingBehavior::kMaxPathPoints;
      auto loop = std::make_unique<ControlLoop>(lo, resources, CBehaviorCoordinator(cc), std::move(controller));
      if (first && loop->controller() != nullptr) loop->set_odometry_output(&odometry);
      if (first && hardware) loop->set_command_output(&hardware->command_channels());
      loops.push_back(std::move(loop));
      loop_timing.push_back(l.timing);
      first = false;
    });
  }
  if (loops.empty() && !profile.behaviors.empty()) {
    d.error(profile.where, "the robot lists behaviors but no loop to run them: add loops: [{name, period_s, controller}]");
  }
}

// The behaviors that run from the start: the operator's hand and the safety behaviors, with the
// parameters the profile gives them.
void Robot::Impl::start_behaviors(const RobotProfile& profile, Diagnostics& d) {
  if (!loops.empty()) collect(d, [&] { loops.front()->activate(std::make_unique<BhTeleop>(), {}, kTeleopInput); });
  for (const ModuleEntry& b : profile.behaviors) {
    if (!b.safety || loops.empty() || !plugins.behaviors.contains(b.type)) continue;
    collect(d, [&] {
      loops.front()->activate(plugins.behaviors.create(b.type), parameters_of(b, options.parameters), b.name, b.where);
    });
  }
}

// The modules of the sequencing loop (`navigation:`, `hri:`, `modules:`), configured.
void Robot::Impl::build_modules(const RobotProfile& profile, Diagnostics& d) {
  for (const auto* list : {&profile.navigation, &profile.hri, &profile.modules}) {
    for (const ModuleEntry& e : *list) {
      if (!plugins.modules.contains(e.type)) continue;  // check_profile reported it
      collect(d, [&] {
        auto mod = plugins.modules.create_at(e.where, e.type);
        mod->configure(parameters_of(e, options.parameters), e.where);
        modules.emplace_back(e.name, std::move(mod));
      });
    }
  }
}

// Every resource is in the table now (the hardware's, the profile's, the odometry): the modules
// start on its first snapshot.
void Robot::Impl::start_modules(Diagnostics& d) {
  snapshot = std::make_unique<ResourceSnapshot>(resources);
  snapshot->publish();
  snapshot->refresh();
  ModuleContext ctx = context(clock.now());
  // Not a structured binding: clang 14 (the fuzzing compiler) cannot capture one in a lambda.
  for (auto& named : modules) collect(d, [&] { named.second->start(ctx); });
}

// The supervisor, what the planner knows (the modules' outputs, the navigation), the modules'
// watchdogs, and the planner.
void Robot::Impl::build_sequencing(const RobotProfile& profile) {
  supervisor = std::make_unique<CProcessSupervisor>(*this, clock, options.supervisor);
  knowledge.navigation = &navigation;
  for (auto& [name, mod] : modules) {
    for (const DescribedModule& dm : description.modules) {
      if (dm.name != name) continue;
      for (const std::string& out : dm.outputs) knowledge.providers.emplace_back(out, mod.get());
    }
  }
  for (const auto* list : {&profile.navigation, &profile.hri, &profile.modules}) {
    for (const ModuleEntry& e : *list) {
      if (e.watchdog_timeout) supervisor->watch_module(e.name, *e.watchdog_timeout, e.watchdog_event);
    }
  }
  planner = std::make_unique<CPlanner>(tasks, recovery, knowledge, processes, *supervisor, clock, options.planner);
  if (!loops.empty()) behavior_loop().set_navigation(navigation);
}

Robot::Robot(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Robot::~Robot() {
  stop();
}

std::unique_ptr<Robot> Robot::assemble(const RobotProfile& profile, const RobotPlugins& plugins, Clock& clock,
                                       RobotOptions options) {
  auto m = std::make_unique<Impl>(clock, plugins, std::move(options));
  Diagnostics d;
  m->adopt(check_profile(profile, plugins, m->options.load_net, DeclaredTypes::must_be_registered, d), profile, d);
  m->build_hardware(profile, d);
  m->build_resources(profile, d);
  if (d.has_errors()) throw ConfigError(d);
  m->build_loops(profile, d);
  check_channel_writes(profile, plugins, m->hardware.get(), d);
  m->start_behaviors(profile, d);
  m->build_modules(profile, d);
  if (d.has_errors()) throw ConfigError(d);
  m->start_modules(d);
  if (d.has_errors()) throw ConfigError(d);
  m->build_sequencing(profile);
  return std::unique_ptr<Robot>(new Robot(std::move(m)));
}

CommandAnswer Robot::command(std::string_view text) {
  std::lock_guard lock(impl_->sequencing_mutex);
  return impl_->planner->command(text);
}

void Robot::step_sequencing() { impl_->step_sequencing(); }

void Robot::run_until(Time until) {
  Impl& m = *impl_;
  auto* clock = dynamic_cast<SimClock*>(&m.clock);
  if (clock == nullptr) throw std::logic_error("Robot::run_until needs a SimClock; on real time use start()");
  if (m.started) throw std::logic_error("Robot::run_until: the robot's threads are running");
  if (!m.schedule) {
    // The simulated-time scheduler: at each instant the hardware first, then the sequencing loop
    // when due, then each reactive loop when due (ties in the order added).
    m.schedule = std::make_unique<SimLoopDriver>(*clock);
    if (m.hardware) m.schedule->set_before_instant([&m](Time t) { m.hardware->advance_to(t); });
    m.schedule->add(m.sequencing_period, [&m](Time) { m.step_sequencing(); });
    for (auto& loop : m.loops) m.schedule->add(*loop);
  }
  m.schedule->run_until(until);
}

void Robot::run_for(Duration d) { run_until(impl_->clock.now() + d); }

void Robot::start(RealtimeOptions options) {
  Impl& m = *impl_;
  if (m.started) throw std::logic_error("Robot::start: already started");
  if (m.hardware) m.hardware->start();
  m.realtime = std::move(options);
  m.runners.clear();
  // The behavior loop's thread owns the hardware's motion and the resources: it advances the
  // hardware to the cycle's time, runs the cycle, and hands the resources to the sequencing layer.
  for (std::size_t i = 0; i < m.loops.size(); ++i) {
    ControlLoop& loop = *m.loops[i];
    PeriodicRunner::Cycle cycle;
    if (i == 0) {
      cycle = [&m, &loop](Time now) {
        if (m.hardware) m.hardware->advance_to(now);
        (void)loop.step(now);
        m.snapshot->publish();
      };
    } else {
      cycle = [&loop](Time now) { (void)loop.step(now); };
    }
    m.runners.push_back(
        std::make_unique<PeriodicRunner>(loop.name(), loop.period(), m.clock, std::move(cycle), m.loop_timing[i]));
  }
  m.runners.push_back(std::make_unique<PeriodicRunner>(
      "sequencing", m.sequencing_period, m.clock,
      [&m](Time now) {
        m.step_sequencing();
        if (m.realtime.after_sequencing) {
          std::lock_guard lock(m.sequencing_mutex);
          m.realtime.after_sequencing(now);
        }
      },
      m.sequencing_timing));
  m.deadline_faults_seen.assign(m.runners.size(), 0);
  m.started = true;
  // The loops first: the sequencing layer's first period sees their first hand-over.
  for (auto& r : m.runners) r->start();
}

void Robot::stop() noexcept {
  Impl& m = *impl_;
  if (!m.started) return;
  // The sequencing thread first: it activates behaviors in the loops still running.
  for (auto it = m.runners.rbegin(); it != m.runners.rend(); ++it) (*it)->stop();
  if (m.hardware) m.hardware->stop();
  m.started = false;
}

std::vector<std::string> Robot::realtime_warnings() const {
  std::vector<std::string> out;
  for (const auto& r : impl_->runners) {
    if (!r->setup().warning.empty()) out.push_back(r->setup().warning);
  }
  return out;
}

std::vector<LoopTimingReport> Robot::timing() const {
  std::vector<LoopTimingReport> out;
  for (const auto& r : impl_->runners) {
    const LoopStatistics& s = r->statistics();
    LoopTimingReport t;
    t.name = r->name();
    t.period = r->period();
    t.budget = r->budget();
    t.cycles = s.cycles();
    t.overruns = r->overruns();
    t.skipped_ticks = s.skipped_ticks();
    t.deadline_faults = r->deadline_faults();
    t.period_error_max = s.max_jitter();
    t.execution_max = s.max_execution();
    // The quantiles come from histogram buckets: one may read a bucket's edge above the largest
    // sample; no quantile is above the maximum.
    t.period_error_p50 = std::min(s.jitter_quantile(0.5), t.period_error_max);
    t.period_error_p99 = std::min(s.jitter_quantile(0.99), t.period_error_max);
    t.execution_p99 = std::min(s.execution_quantile(0.99), t.execution_max);
    t.realtime = r->setup().realtime;
    t.warning = r->setup().warning;
    out.push_back(std::move(t));
  }
  return out;
}

bool Robot::started() const noexcept { return impl_->started; }
const RobotDescription& Robot::description() const noexcept { return impl_->description; }
CPlanner& Robot::planner() noexcept { return *impl_->planner; }
CProcessSupervisor& Robot::supervisor() noexcept { return *impl_->supervisor; }
const ProcessRegistry& Robot::processes() const noexcept { return impl_->processes; }
ControlLoop& Robot::behavior_loop() noexcept { return impl_->behavior_loop(); }
CHardware* Robot::hardware() noexcept { return impl_->hardware.get(); }
const ResourceTable& Robot::resources() const noexcept { return impl_->resources; }
const ResourceTable& Robot::sequencing_resources() const noexcept {
  return impl_->snapshot->table();
}
const NavigationData& Robot::navigation() const noexcept { return impl_->navigation; }

bool Robot::behavior_active(std::string_view name) const noexcept {
  const auto it = impl_->active.find(name);
  return it != impl_->active.end() && it->second.state == BehaviorStatus::running;
}

ControlLoop* Robot::loop(std::string_view name) noexcept {
  for (auto& l : impl_->loops) {
    if (l->name() == name) return l.get();
  }
  return nullptr;
}

CModule* Robot::module(std::string_view name) noexcept {
  for (auto& [n, mod] : impl_->modules) {
    if (n == name) return mod.get();
  }
  return nullptr;
}

std::vector<CModule*> Robot::modules() const { return impl_->all(); }

}  // namespace tripodal
