#include "tripodal/testing/robot_harness.hpp"

#include <stdexcept>
#include <utility>

#include "tripodal/robot/plugin_library.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/trace/trace_reader.hpp"

namespace tripodal::testing {

namespace {

constexpr std::string_view kTraceType = "trace";
constexpr std::string_view kClosedLoopType = "sim_from_trace";

// The first recorded pose: of `channel`, or of the first odometry channel when it is empty.
std::optional<Pose2D> first_pose(const std::filesystem::path& path, const std::string& channel) {
  trace::TraceReader reader(path);
  trace::TraceRecord rec;
  while (reader.next(rec)) {
    const auto* odo = std::get_if<OdometryReading>(&rec.data);
    if (odo == nullptr) continue;
    if (channel.empty() || reader.channel(rec.channel).name == channel) return odo->pose;
  }
  return std::nullopt;
}

}  // namespace

// Turns the planner's and supervisor's callbacks into the log's events, and keeps each behavior's
// status for the step being recorded (an outcome within a period wins over the later idle).
class RobotHarness::Observer final : public TaskObserver, public SupervisorObserver {
 public:
  explicit Observer(RobotHarness& h) : h_(h) {}

  void on_command_refused(std::string_view /*command*/, std::string_view answer, Time /*now*/) override {
    note("task.refused", std::string(answer));
  }
  void on_task_started(const TaskReport& task, const Plan& /*plan*/, Time /*now*/) override { note("task.started", task.command); }
  void on_process_started(const ProcessRecord& p) override { note(p.step.process + ".started", {}); }
  void on_process_succeeded(const ProcessRecord& p) override { note(p.step.process + ".succeeded", {}); }
  void on_process_failed(const ProcessRecord& p) override { note(p.step.process + ".failed", p.message); }
  void on_recovery(const RecoveryRecord& r) override { note("recovery", r.reason); }
  void on_task_succeeded(const TaskReport& /*task*/) override { note("task.succeeded", {}); }
  void on_task_failed(const TaskReport& task) override { note("task.failed", task.reason); }

  void on_behavior_activated(std::string_view /*run*/, std::string_view behavior, const ParameterValues& /*params*/,
                             Time /*now*/) override {
    set(behavior, BehaviorStatus::running, false);
  }
  void on_behavior_deactivated(std::string_view /*run*/, std::string_view behavior, Time /*now*/) override {
    set(behavior, BehaviorStatus::idle, false);
  }
  void on_firing(std::string_view /*run*/, const PetriNet& /*net*/, const Firing& firing) override {
    if (!firing.event.empty()) event(firing.event, {});
  }
  void on_event_dropped(std::string_view e, Time /*now*/) override { event(e, "consumed by no process"); }
  void on_fault(std::string_view source, std::string_view reason, Time /*now*/) override {
    note("fault:" + std::string(source), std::string(reason));
  }

  /// The statuses of this step, then the outcomes are forgotten.
  void fill(std::vector<BehaviorSample>& out) {
    size_to_log();
    out.resize(status_.size());
    for (std::size_t i = 0; i < status_.size(); ++i) {
      out[i].status = outcome_[i] ? *outcome_[i] : status_[i];
      outcome_[i].reset();
    }
  }

 private:
  void note(std::string name, std::string detail) { h_.log_.events_.push_back(HarnessEvent{h_.now(), std::move(name), std::move(detail)}); }

  void event(std::string_view e, std::string detail) {
    note(std::string(e), std::move(detail));
    for (const auto& [suffix, st] : {std::pair{std::string_view(".done"), BehaviorStatus::succeeded},
                                     std::pair{std::string_view(".failed"), BehaviorStatus::failed}}) {
      if (e.size() > suffix.size() && e.substr(e.size() - suffix.size()) == suffix) {
        set(e.substr(0, e.size() - suffix.size()), st, true);
      }
    }
  }

  void set(std::string_view behavior, BehaviorStatus st, bool outcome) {
    const auto i = h_.log_.behavior_index(behavior);
    if (!i) return;
    size_to_log();
    if (outcome) outcome_[*i] = st;
    else status_[*i] = st;
  }

  void size_to_log() {
    status_.resize(h_.log_.names_.size(), BehaviorStatus::idle);
    outcome_.resize(h_.log_.names_.size());
  }

  RobotHarness& h_;
  std::vector<BehaviorStatus> status_;
  std::vector<std::optional<BehaviorStatus>> outcome_;
};

RobotHarness::RobotHarness(Mode mode, const RobotProfile& profile, RobotPlugins plugins, const std::filesystem::path& trace,
                           RobotHarnessOptions options)
    : mode_(mode),
      options_(std::move(options)),
      summary_(trace::summarize_trace(trace)),
      offset_(mode == Mode::closed_loop ? summary_.first.time_since_epoch() : Duration{}),
      clock_(mode == Mode::replay ? summary_.first : Time{}),
      plugins_(std::move(plugins)) {
  if (summary_.empty) throw std::invalid_argument("RobotHarness: the trace " + trace.string() + " has no records");
  if (!options_.localization_channel.empty() &&
      trace::find_channel(summary_.channels, options_.localization_channel, trace::ChannelKind::kOdometry) == nullptr) {
    throw std::invalid_argument("RobotHarness: the trace " + trace.string() + " has no odometry channel '" +
                                options_.localization_channel + "' for the localization");
  }
  const std::optional<Pose2D> start = first_pose(trace, options_.localization_channel);
  if (!start) {
    throw std::invalid_argument("RobotHarness: the trace " + trace.string() +
                                " records no pose to start from (no odometry reading" +
                                (options_.localization_channel.empty() ? "" : " on '" + options_.localization_channel + "'") + ")");
  }
  start_pose_ = *start;
  (void)load_profile_plugins(profile, plugins_, options_.plugins);

  // The recorded robot's hardware is replaced; the rest of its profile is kept as written.
  RobotProfile p = profile;
  std::vector<std::string> outputs;
  std::map<std::string, std::string, std::less<>> kept;
  if (p.hardware) {
    if (const ModuleManifest* m = plugins_.hardware.find(p.hardware->type)) outputs = m->outputs;
    if (auto it = p.hardware->parameters.find("seed"); it != p.hardware->parameters.end()) kept.insert(*it);
  } else {
    p.hardware.emplace();
    p.hardware->kind = ModuleKind::other;
    p.hardware->name = "hardware";
    p.hardware->where = p.where;
  }
  p.hardware->parameters.clear();
  if (mode_ == Mode::replay) {
    if (plugins_.hardware.contains(kTraceType)) {
      throw std::invalid_argument("RobotHarness: the plugins already register a hardware type 'trace'; the harness adds its own");
    }
    register_trace_hardware(plugins_.hardware, outputs, options_.world);
    p.hardware->type = std::string(kTraceType);
    p.hardware->parameters = {{"trace", std::filesystem::absolute(trace).string()},
                              {"localization", options_.localization_channel}};
  } else {
    if (!options_.world) throw std::invalid_argument("RobotHarness: a closed-loop run needs a simulated world (options.world)");
    sim::World world = *options_.world;
    world.start_pose = start_pose_;
    auto w = std::make_shared<const sim::World>(std::move(world));
    ModuleManifest m = sim::SimHardware::static_manifest();
    m.name = std::string(kClosedLoopType);
    m.description = "the embedded simulator, the robot starting at a trace's recorded start";
    if (plugins_.hardware.contains(kClosedLoopType)) {
      throw std::invalid_argument("RobotHarness: the plugins already register a hardware type '" + std::string(kClosedLoopType) + "'");
    }
    plugins_.hardware.add(std::move(m), [w](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
      return std::make_unique<sim::SimHardware>(c, w);  // "world" is not kept: the run is in w
    });
    p.hardware->type = std::string(kClosedLoopType);
    p.hardware->parameters = std::move(kept);
  }

  for (const ModuleEntry& b : p.behaviors) log_.names_.push_back(b.name);
  observer_ = std::make_unique<Observer>(*this);
  robot_ = Robot::assemble(p, plugins_, clock_, options_.robot);
  trace_hw_ = dynamic_cast<TraceHardware*>(robot_->hardware());
  if (CController* c = robot_->behavior_loop().controller()) c->reset_odometry(start_pose_);
  robot_->planner().add_observer(*observer_);
  robot_->supervisor().add_observer(*observer_);
  laser_ = robot_->resources().first<LaserScan>();
  robot_->run_until(clock_.now());  // the first readings and the localizer's first estimate
}

RobotHarness::~RobotHarness() {
  if (robot_) robot_->stop();
}

Time RobotHarness::now() const noexcept { return clock_.now() + offset_; }

CommandAnswer RobotHarness::command(std::string_view text) { return robot_->command(text); }

const RunLog& RobotHarness::run(std::optional<Time> until, bool stop_when_idle) {
  const Duration period = robot_->behavior_loop().period();
  // A replay has nothing to give after its last record; a closed loop may run on past it.
  const Time trace_end = summary_.last + period;
  const Time end = !until ? trace_end : mode_ == Mode::replay ? std::min(*until, trace_end) : *until;
  while (now() + period <= end) {
    robot_->run_for(period);
    if (trace_hw_ != nullptr && !trace_hw_->error().empty()) {
      throw std::runtime_error("RobotHarness: the replay stopped at t=" + format_seconds(now()) + " s: " + trace_hw_->error());
    }
    record_step();
    if (stop_when_idle && !robot_->planner().busy()) break;
  }
  return log_;
}

void RobotHarness::record_step() {
  StepRecord rec;
  rec.t = now();
  const CycleReport& cycle = robot_->behavior_loop().last_cycle();
  rec.command = cycle.coordinator.command;
  rec.safety_limited = cycle.coordinator.safety_limited;
  rec.all_expired = cycle.coordinator.all_expired;
  if (laser_ != nullptr && laser_->has_reading()) {
    rec.clearance_m = footprint_clearance_m(laser_->latest(), options_.laser_in_body, options_.robot_radius_m, rec.command);
  }
  observer_->fill(rec.behaviors);
  log_.steps_.push_back(std::move(rec));
}

}  // namespace tripodal::testing
