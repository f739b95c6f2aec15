#include "run_task.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "guide_hri.hpp"
#include "run_charging.hpp"
#include "run_devices.hpp"
#include "run_measures.hpp"
#include "run_outputs.hpp"
#include "run_recording.hpp"
#include "shutdown.hpp"
#include "tripodal/behaviors/navigation_behaviors.hpp"
#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/board_monitor.hpp"
#include "tripodal/board/rplidar_a1.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/monitor/robot_monitor.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/navi/scan_matching_localizer.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/robot/plugin_library.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"
#ifdef TRIPODAL_HAVE_DDS
#include "tripodal/dds/dds_hardware.hpp"
#include "tripodal/dds/robot_bridge.hpp"
#include "tripodal/dds/robot_modules.hpp"
#endif

namespace tripodal::app {

std::vector<ParameterOverride> simulation_overrides(const RobotProfile& profile, const sim::World& world, std::uint64_t seed) {
  std::vector<ParameterOverride> out;
  // A simulator in this process takes the seed (a sim-server has its own --seed).
  if (profile.hardware && (profile.hardware->type == "sim" || profile.hardware->type == "board")) {
    out.push_back({profile.hardware->name, "seed", std::to_string(seed)});
  }
  for (const ModuleEntry& e : profile.navigation) {
    if (e.type == navi::CGroundTruthLocalizer::static_manifest().name)
      out.push_back({e.name, "seed", std::to_string(seed % (1ULL << 52))});
    if (e.type == navi::CScanMatchingLocalizer::static_manifest().name) {
      // The robot starts on its charger, whose place in the map it knows: the world's start pose
      // (the profile's initial pose is the workspace's charger; another world starts elsewhere).
      const auto text = [](double v) {
        std::ostringstream s;
        s << std::setprecision(17) << v;
        return s.str();
      };
      out.push_back({e.name, "initial_x_m", text(world.start_pose.x_m)});
      out.push_back({e.name, "initial_y_m", text(world.start_pose.y_m)});
      out.push_back({e.name, "initial_theta_rad", text(world.start_pose.theta_rad)});
    }
  }
  return out;
}

namespace {
#ifdef TRIPODAL_HAVE_DDS
void register_dds_robot_modules(RobotPlugins& plugins) { dds::register_dds_modules(plugins.resources, plugins.controllers); }
#else
void register_dds_robot_modules(RobotPlugins&) {}
#endif
}  // namespace

// The robot on DDS when its profile has a `dds:` section (docs/distribution.md); a tool built
// without the dds area refuses such a profile rather than run a robot its peers cannot see.
#ifdef TRIPODAL_HAVE_DDS
using DdsBridge = dds::RobotBridge;
std::unique_ptr<DdsBridge> make_dds_bridge(Robot& robot, const Clock& clock, const RobotProfile& profile) {
  // The run's clock is the simulation's, never the wall's: it goes out on /clock.
  return profile.dds ? std::make_unique<DdsBridge>(robot, clock, *profile.dds, dds::RobotBridgeOptions{.simulated_time = true}) : nullptr;
}
#else
struct DdsBridge {
  void update() {}
  [[nodiscard]] bool paused() const noexcept { return false; }
  [[nodiscard]] std::string topic(std::string_view) const { return {}; }
};
std::unique_ptr<DdsBridge> make_dds_bridge(Robot&, const Clock&, const RobotProfile& profile) {
  if (profile.dds) {
    throw ConfigError(profile.dds->where, "dds: this tripodal was built without DDS (TRIPODAL_DDS=OFF or Cyclone DDS not found); "
                                          "remove the section or build with Cyclone DDS");
  }
  return nullptr;
}
#endif

// Hardware "dds" for `tripodal run`: the base in another process, the map the world's, as a real
// robot loads its map while its base is elsewhere.
#ifdef TRIPODAL_HAVE_DDS
// The world's joints (a neck) as the hardware dds carries them: the sim-server simulates the same world's.
std::vector<dds::DdsJoint> dds_joints_of(const sim::World* world) {
  std::vector<dds::DdsJoint> out;
  if (world == nullptr) return out;
  for (const sim::JointConfig& j : world->robot.joints) out.push_back({j.name, j.min_rad, j.max_rad, j.initial_rad, j.rate_hz});
  return out;
}
class WorldDdsHardware final : public dds::DdsHardware, public navi::MapSource {
 public:
  WorldDdsHardware(const HardwareConfig& c, std::shared_ptr<const sim::World> world)
      : DdsHardware(c, dds_joints_of(world.get())), world_(std::move(world)) {}
  [[nodiscard]] const navi::OccupancyGrid& world_map() const noexcept override { return world_->grid; }
  [[nodiscard]] const navi::RegionMap& world_regions() const noexcept override { return world_->regions; }

 private:
  std::shared_ptr<const sim::World> world_;
};
void register_remote_hardware(HardwareRegistry& registry, const std::shared_ptr<const sim::World>& world) {
  registry.add(dds::DdsHardware::static_manifest(), [world](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
    return std::make_unique<WorldDdsHardware>(c, world);
  });
}
#else
void register_remote_hardware(HardwareRegistry&, const std::shared_ptr<const sim::World>&) {}
#endif

void register_tool_plugins(RobotPlugins& plugins, const std::shared_ptr<const sim::World>& world) {
  register_all(plugins, world);
  register_remote_hardware(plugins.hardware, world);
  register_dds_robot_modules(plugins);
}

void register_tool_plugins(RobotPlugins& plugins, const std::shared_ptr<const sim::World>& world, const RobotProfile& profile,
                           const std::vector<std::filesystem::path>& libraries) {
  register_tool_plugins(plugins, world);
  (void)load_profile_plugins(profile, plugins, libraries);
}

namespace {

using navi::Point2D;

// The profile as the run takes it: --hardware and --hardware-param over its hardware slot.
RobotProfile run_profile(const RunOptions& o) {
  RobotProfile profile = load_robot_profile(o.robot);
  if (!o.hardware.empty()) {
    if (!profile.hardware) {
      profile.hardware = ModuleEntry{};
      profile.hardware->name = "hardware";
      profile.hardware->where = profile.where;
    }
    if (profile.hardware->type != o.hardware) profile.hardware->parameters.clear();  // the profile's were for its own type
    profile.hardware->type = o.hardware;
  }
  if (!o.hardware_parameters.empty() && !profile.hardware) {
    throw ConfigError(profile.where, "--hardware-param: the profile has no hardware slot (hardware: {type: ...}) and no --hardware is given");
  }
  for (const auto& [key, value] : o.hardware_parameters) profile.hardware->parameters.insert_or_assign(key, value);
  return profile;
}

// The options that need a hardware slot of a kind: refused, located, before anything is built.
void check_hardware_options(const RunOptions& o, const RobotProfile& profile) {
  if (!profile.hardware) {
    throw ConfigError(profile.where,
                      "`tripodal run` runs the robot on the simulator: its profile needs hardware: {type: sim} "
                      "(or {type: board}, the control board simulated in the same world, {type: dds}, the simulator "
                      "in another process: tripodal sim-server, or a plugin's type derived from sim::SimHardware)");
  }
  const bool remote = profile.hardware->type == "dds";
#ifndef TRIPODAL_HAVE_DDS
  if (remote) {
    throw ConfigError(profile.hardware->where, "hardware dds: this tripodal was built without DDS (TRIPODAL_DDS=OFF or Cyclone DDS not found)");
  }
#endif
  if (remote && !o.faults.empty()) {
    throw ConfigError(SourceLocation{"--faults", 1, 1}, "the simulator is in another process (hardware dds): give the faults to its world");
  }
  const bool on_board = profile.hardware->type == "board";
  if (!o.board_line.empty() && !on_board) {
    throw ConfigError(profile.hardware->where, "--board " + o.board_line + " needs a robot on the control board (hardware: {type: board})");
  }
  if (o.uv_target_dose_j_m2 && !on_board) {
    throw ConfigError(profile.hardware->where, "--uv-target-dose needs a robot on the control board (hardware: {type: board})");
  }
}

// The robot's parameters for this run: the simulation's seed and start, the board's line, the
// coverage pattern and the dose the lanes are planned for.
RobotOptions run_robot_options(const RunOptions& o, const RobotProfile& profile, const sim::World& world, std::uint64_t seed) {
  RobotOptions ro;
  ro.parameters = simulation_overrides(profile, world, seed);
  if (!o.board_line.empty()) ro.parameters.push_back({profile.hardware->name, "line", o.board_line});
  for (const ModuleEntry& e : profile.navigation) {
    if (e.type != navi::CCoveragePlanner::static_manifest().name) continue;
    if (!o.pattern.empty()) ro.parameters.push_back({e.name, "pattern", o.pattern});
    // The dose the lanes are planned for (the profile's dose_target_j_m2 otherwise).
    if (!o.dose_plan)
      ro.parameters.push_back({e.name, "dose_target_j_m2", "0"});
    else if (o.uv_target_dose_j_m2)
      ro.parameters.push_back({e.name, "dose_target_j_m2", fmt::format("{}", *o.uv_target_dose_j_m2)});
  }
  return ro;
}

// A plugin's hardware type runs here when it simulates (derives from sim::SimHardware).
GroundTruth checked_truth(Robot& robot, const RobotProfile& profile, const sim::World& world) {
  GroundTruth truth(robot.hardware(), world.start_pose);
  if (profile.hardware->type != "dds" && truth.local() == nullptr) {
    throw ConfigError(profile.hardware->where, "hardware type '" + profile.hardware->type +
                                                   "' does not run on the simulator: `tripodal run` needs hardware: {type: sim}, "
                                                   "{type: board}, {type: dds} or a type derived from sim::SimHardware");
  }
  return truth;
}

// Cleaning is measured when the robot has SectionSplitter and CoveragePlanner; the map always.
Navigation checked_navigation(Robot& robot, const RobotProfile& profile, const sim::World& world) {
  Navigation nav{robot.module<navi::CGridMaps>(), robot.module<navi::CSectionSplitter>(), robot.module<navi::CCoveragePlanner>()};
  if (nav.maps == nullptr)
    throw ConfigError(profile.where, "`tripodal run` measures the run on the map: the robot needs a GridMaps module");
  if (nav.maps->robot_radius_m() < world.robot.radius_m) {
    throw ConfigError(nav.maps->where(), "robot_radius_m " + fixed(nav.maps->robot_radius_m(), 3) +
                                             " m is smaller than the simulated body (" + fixed(world.robot.radius_m, 3) +
                                             " m): planned paths would collide");
  }
  return nav;
}

// The planner's lamp must be the one the simulated board lights (one lamp, two consumers).
void check_same_lamp(const Navigation& nav, const sim::SimBoardHardware* board_hw,
                     const std::optional<navi::DosePlan>& dose_plan) {
  if (board_hw == nullptr || !dose_plan) return;
  const navi::UvLamp& a = nav.coverage->uv_lamp();
  const navi::UvLamp& b = board_hw->uv_dose().lamp();
  if (a.uvc_power_w != b.uvc_power_w || a.height_m != b.height_m || a.radius_m != b.radius_m) {
    throw ConfigError(nav.coverage->where(),
                      fmt::format("the coverage planner plans the dose for a lamp of {} W, {} m high, {} m lit "
                                  "radius, the board's lamp is {} W, {} m, {} m: give both the same uv_ parameters",
                                  a.uvc_power_w, a.height_m, a.radius_m, b.uvc_power_w, b.height_m, b.radius_m));
  }
}

// Why a dose-planned disinfection cannot be done (the battery down to the board monitor's low
// threshold, or the time limit, cannot carry its estimate `est`); "" when it can. Logs the plan.
std::string dose_refusal(const RunOptions& o, const RobotProfile& profile, const sim::World& world,
                         const board::BoardFirmware& fw, const navi::DosePlan& plan, const DoseEstimate& est) {
  double low_percent = 15.0;
  for (const ModuleEntry& e : profile.modules) {
    if (e.type != "BoardMonitor") continue;
    if (const auto it = e.parameters.find("battery_low_percent"); it != e.parameters.end()) low_percent = std::stod(it->second);
  }
  const double available_ah = std::max(0.0, fw.state_of_charge() - low_percent / 100.0) * fw.config().battery_capacity_ah;
  if (o.log != nullptr) {
    *o.log << fmt::format(
        "dose plan: {} J/m2: lanes {:.2f} m apart at {:.3f} m/s (faster between closer lanes), {} pass{}; "
        "estimated {:.0f} s, {:.2f} Ah of the {:.2f} Ah above the {}% low-battery mark\n",
        plan.target_j_m2, plan.spacing_m, plan.speed_m_s, plan.passes, plan.passes > 1 ? "es" : "", est.time_s, est.charge_ah,
        available_ah, low_percent);
  }
  // More than one charge: the robot stops at the dock on the way when its profile and the world can.
  const std::optional<ChargingStops> stops =
      est.charge_ah > available_ah ? plan_charging_stops(profile, world, fw.config(), est.charge_ah, available_ah, low_percent)
                                   : std::nullopt;
  if (stops && o.log != nullptr) {
    *o.log << fmt::format("more than one charge: {} stop{} at the dock '{}' planned (about {:.0f} s charging)\n", stops->stops,
                          stops->stops == 1 ? "" : "s", stops->dock, stops->charge_s);
  }
  if (stops && o.time_limit_s && est.time_s + stops->charge_s > *o.time_limit_s) {
    return fmt::format(
        "target dose {} J/m2 cannot be reached within the time limit of {:.0f} s: the plan needs about {:.0f} s "
        "and {:.0f} s of charging at the dock",
        plan.target_j_m2, *o.time_limit_s, est.time_s, stops->charge_s);
  }
  if (est.charge_ah > available_ah && !stops) {
    return fmt::format(
        "target dose {} J/m2 cannot be reached within the battery: the plan (lanes {:.2f} m apart at {:.3f} m/s, "
        "{} pass{}) needs about {:.2f} Ah ({:.0f} s), the battery holds {:.2f} Ah above the {}% low mark",
        plan.target_j_m2, plan.spacing_m, plan.speed_m_s, plan.passes, plan.passes > 1 ? "es" : "", est.charge_ah, est.time_s,
        available_ah, low_percent);
  }
  if (o.time_limit_s && est.time_s > *o.time_limit_s) {
    return fmt::format(
        "target dose {} J/m2 cannot be reached within the time limit of {:.0f} s: the plan (lanes {:.2f} m apart "
        "at {:.3f} m/s, {} pass{}) needs about {:.0f} s",
        plan.target_j_m2, *o.time_limit_s, plan.spacing_m, plan.speed_m_s, plan.passes, plan.passes > 1 ? "es" : "", est.time_s);
  }
  return {};
}

// The monitor (docs/monitor.md): its own thread serves the clients; the run hands it the robot's
// state and takes the operator's requests between periods.
struct MonitorParts {
  std::unique_ptr<monitor::MonitorServer> server;
  std::unique_ptr<monitor::RobotMonitor> watch;
};
// Which robot the monitor shows, for an operator with one page per robot of a fleet: how the
// fleet reaches it (empty: not on DDS).
std::string monitor_identity(const RobotProfile& p) {
  if (!p.dds) return {};
  std::string out = "DDS domain " + std::to_string(p.dds->domain_id) + ", namespace '" + p.dds->ros_namespace + "'";
  if (p.dds->security_identity.empty()) return out + ", not secured";
  return out + ", secured as '" + p.dds->security_identity + "' (keys " + p.dds->security_keys.string() + ")";
}
MonitorParts start_monitor(const RunOptions& o, Robot& robot, const Clock& clock, const RobotProfile& profile) {
  MonitorParts m;
  if (!o.monitor) return m;
  monitor::MonitorServerOptions so = monitor::server_options(*o.monitor, o.monitor_token_file);
  so.read_without_token = o.monitor_read_open;
  so.allowed_hosts = o.monitor_allowed_hosts;
  so.allowed_origins = o.monitor_allowed_origins;
  m.server = std::make_unique<monitor::MonitorServer>(std::move(so));
  // the operator's live maps go beside the run's own outputs
  m.watch = std::make_unique<monitor::RobotMonitor>(
      robot, clock, *m.server,
      monitor::RobotMonitorOptions{
          .start_paused = o.start_paused, .map_dir = o.out, .robot_name = profile.name, .identity = monitor_identity(profile)});
  m.server->start();
  if (o.log != nullptr) {
    *o.log << "monitor: " << m.server->url() << "  (token " << m.server->token()
           << (o.start_paused ? "; paused until resumed" : "") << ")\n";
    o.log->flush();
  }
  return m;
}

// One `tripodal run`: the robot on the simulator, what the run is measured by, and the measures as
// they accumulate. run_task drives it through its phases: start, drive, finish, measure, write.
class TaskRun {
 public:
  TaskRun(const RunOptions& o, const RobotProfile& profile, const std::shared_ptr<sim::World>& world, RunResult& res)
      : o_(o),
        profile_(profile),
        world_(*world),
        res_(res),
        plugins_(tool_plugins(o, profile, world)),
        threaded_(o.realtime && !o.monitor && !profile.dds),
        wall_clock_(o.realtime_speed),
        clock_(threaded_ ? static_cast<Clock&>(wall_clock_) : static_cast<Clock&>(sim_clock_)),
        robot_(assemble()),
        truth_(checked_truth(*robot_, profile, *world)),
        board_hw_(dynamic_cast<sim::SimBoardHardware*>(robot_->hardware())),
        nav_(checked_navigation(*robot_, profile, *world)),
        start_(world->start_pose),
        dose_plan_(nav_.coverage != nullptr ? nav_.coverage->dose_plan() : no_dose_plan()),
        target_dose_j_m2_(o.uv_target_dose_j_m2.value_or(dose_plan_ ? dose_plan_->target_j_m2 : kDefaultUvTargetDose)) {
    if (nav_.coverage != nullptr) res_.coverage_pattern = nav_.coverage->pattern();
    check_same_lamp(nav_, board_hw_, dose_plan_);
    if (CController* c = robot_->behavior_loop().controller()) c->reset_odometry(start_);
    robot_->planner().add_observer(life_);
    robot_->supervisor().add_observer(life_);
    robot_->planner().add_observer(report_);
  }

  void start();
  void drive();
  Time finish();
  void measure(Time ended);
  void write_outputs() const;

 private:
  static const std::optional<navi::DosePlan>& no_dose_plan() {
    static const std::optional<navi::DosePlan> none;
    return none;
  }
  static RobotPlugins tool_plugins(const RunOptions& o, const RobotProfile& profile, const std::shared_ptr<sim::World>& world) {
    RobotPlugins plugins;
    register_tool_plugins(plugins, world, profile, o.plugins);
    return plugins;
  }
  // The robot, on simulated hardware in this world, with this run's seed and coverage pattern;
  // the board's modules and actuator behaviors for a robot on the control board. --realtime
  // (without a monitor or DDS, which pace one thread): the robot on its own threads, on the wall
  // clock sped up SPEED times; otherwise the caller's thread steps it on simulated time.
  std::unique_ptr<Robot> assemble() {
    const RobotOptions ro = run_robot_options(o_, profile_, world_, res_.seed);
    if (threaded_ && !o_.record.empty()) {
      throw ConfigError(SourceLocation{"--record", 1, 1},
                        "--record goes with a run on simulated time (without --realtime): its recorder "
                        "reads the loop between cycles, which the robot's own threads do not leave");
    }
    return Robot::assemble(profile_, plugins_, clock_, ro);
  }

  [[nodiscard]] bool stopped() const { return o_.stop != nullptr && *o_.stop != 0; }
  [[nodiscard]] bool is_cleaning() const {
    return robot_->behavior_active("BhCleaning") || robot_->behavior_active("BhCleaningTwoWheel");
  }
  [[nodiscard]] std::size_t covered() const { return cleaned_reachable(reachable_, cleaned_); }
  void give_task();
  void check_dose_plan();
  void flush_log();
  void draw_progress(bool final);
  void measure_room();
  void measure_when_busy();
  void note_sim_events();
  void observe();
  void monitor_update();
  void drive_threaded();
  void drive_stepped();
  void rest_base();

  const RunOptions& o_;
  const RobotProfile& profile_;
  const sim::World& world_;
  RunResult& res_;
  RobotPlugins plugins_;
  bool threaded_;
  SimClock sim_clock_;
  ScaledClock wall_clock_;
  Clock& clock_;
  std::unique_ptr<Robot> robot_;
  GroundTruth truth_;
  sim::SimBoardHardware* board_hw_;
  Navigation nav_;
  Pose2D start_;
  const std::optional<navi::DosePlan>& dose_plan_;
  double target_dose_j_m2_;
  LifecycleRecorder life_{true};
  ReportObserver report_;
  std::unique_ptr<RunRecording> recording_;
  std::unique_ptr<DdsBridge> bridge_;
  bool serve_dds_ = false;  // on DDS without a task given here, the run waits for one from a peer
  SteadyClock wall_;
  std::optional<sim::RealtimePacer> pacer_;
  MonitorParts monitor_;
  bool serve_ = false;
  // the log: the lines printed, a bar drawn in place on the terminal, to be wiped before a log line
  std::size_t printed_ = 0;
  bool bar_shown_ = false;
  // The room's sections and the reachable area, for the measures: of the task running (a task
  // submitted on the monitor's console is measured from when it starts).
  std::vector<std::string> room_sections_;
  std::vector<char> reachable_ = std::vector<char>(nav_.maps->grid().size(), 0);  // none until a task names its room
  std::vector<char> lamp_floor_;  // with a dose plan: the floor the lamp can dose at all
  navi::PathPlanner reach_planner_{nav_.maps->grid(), navi::PathPlannerOptions{.robot_radius_m = nav_.maps->robot_radius_m()}};
  bool measured_busy_ = false;
  navi::CleanedCells cleaned_{nav_.maps->grid()};  // from the true pose, while a cleaning behavior runs
  std::vector<TrajectorySample> traj_;
  std::vector<Point2D> path_all_, path_cleaning_;
  // the fog's, whatever the lanes' spacing
  double half_width_ = nav_.coverage != nullptr ? nav_.coverage->footprint_width_m() / 2.0 : 0.0;
  Duration tick_period_ = robot_->behavior_loop().period();
  Time deadline_ = time_from_seconds(o_.max_duration_s);
  bool was_cleaning_ = false;
  Pose2D last_truth_{};
  double next_progress_s_ = 0.0;
  Time next_sample_{};
  std::size_t sim_events_noted_ = 0;
};

void TaskRun::start() {
  if (!o_.record.empty()) recording_ = std::make_unique<RunRecording>(o_.record, *robot_);
  bridge_ = make_dds_bridge(*robot_, clock_, profile_);
  serve_dds_ = bridge_ != nullptr && o_.task.empty();
  if (bridge_ && o_.log != nullptr) {
    *o_.log << "dds: domain " << profile_.dds->domain_id << ", namespace '" << profile_.dds->ros_namespace << "' ("
            << bridge_->topic("events") << (profile_.dds->tasks ? ", tasks on " + bridge_->topic("task") : std::string())
            << ")\n";
    o_.log->flush();
  }
  if (!threaded_ && (o_.realtime || o_.monitor || serve_dds_)) pacer_.emplace(wall_, o_.realtime ? o_.realtime_speed : 1.0);
  monitor_ = start_monitor(o_, *robot_, clock_, profile_);
  serve_ = monitor_.watch != nullptr || serve_dds_;

  if (!threaded_) robot_->run_until(sim_clock_.now());  // the localizer's first estimate, before the planner asks where to start
  give_task();
  flush_log();
  measured_busy_ = robot_->planner().busy();
  if (measured_busy_) measure_room();
  check_dose_plan();
  last_truth_ = truth_.pose();
  next_sample_ = clock_.now();
}

void TaskRun::give_task() {
  if (o_.task.empty()) return;
  const CommandAnswer answer = robot_->command(o_.task);
  if (!answer.accepted) {
    res_.state = "refused";
    res_.reason = answer.text;
    if (o_.log != nullptr) *o_.log << answer.text << '\n';
    // Not served, the run ends here, but it still writes its (empty) map and report below.
  }
}

// A dose-planned disinfection is checked up front: refused when the battery (down to the board
// monitor's low threshold) or the time limit cannot carry it.
void TaskRun::check_dose_plan() {
  if (!measured_busy_ || !dose_plan_ || board_hw_ == nullptr || nav_.splitter == nullptr) return;
  const board::BoardFirmware& fw = board_hw_->embedded().firmware();
  const DoseEstimate est = estimate_dose(*nav_.coverage, *nav_.splitter, room_sections_, {start_.x_m, start_.y_m}, fw.config());
  res_.dose_estimate_s = est.time_s;
  res_.dose_estimate_ah = est.charge_ah;
  const std::string why = dose_refusal(o_, profile_, world_, fw, *dose_plan_, est);
  if (!why.empty()) {
    robot_->planner().cancel(why);
    robot_->step_sequencing();
    res_.state = "refused";
    res_.reason = why;
    if (o_.log != nullptr) *o_.log << why << '\n';
  }
}

void TaskRun::flush_log() {
  if (o_.log == nullptr) return;
  if (bar_shown_ && printed_ < life_.entries().size() && o_.progress != nullptr) {
    *o_.progress << '\r' << std::string(100, ' ') << '\r';
    o_.progress->flush();
    bar_shown_ = false;
  }
  for (; printed_ < life_.entries().size(); ++printed_) {
    const LifecycleEntry& e = life_.entries()[printed_];
    if (e.text.find(" fire ") != std::string::npos) continue;  // every firing: in lifecycle.txt only
    *o_.log << std::setw(9) << fixed(to_seconds(e.time), 1) << " s  " << e.text << '\n';
  }
  o_.log->flush();
}

void TaskRun::draw_progress(bool final) {
  if (o_.progress == nullptr) return;
  *o_.progress << (o_.progress_is_terminal ? "\r" : "");
  if (res_.reachable_cells > 0) {  // a cleaning task: the bar is the coverage of the room
    const double cov = static_cast<double>(covered()) / static_cast<double>(res_.reachable_cells);
    constexpr int kWidth = 30;
    const int full = static_cast<int>(std::lround(cov * kWidth));
    *o_.progress << '[' << std::string(static_cast<std::size_t>(full), '#')
                 << std::string(static_cast<std::size_t>(kWidth - full), '.') << "] " << std::setw(5) << fixed(100.0 * cov, 1)
                 << " %  ";
  }
  *o_.progress << "t=" << std::setw(7) << fixed(to_seconds(clock_.now()), 0) << " s  "
               << (report_.current.empty() ? "-" : report_.current) << (o_.progress_is_terminal && !final ? "          " : "\n");
  o_.progress->flush();
  bar_shown_ = o_.progress_is_terminal && !final;
}

void TaskRun::measure_room() {
  room_sections_ = plan_sections(robot_->planner());
  reachable_ = reachable_area(nav_, reach_planner_, room_sections_, start_,
                              nav_.coverage != nullptr ? nav_.coverage->footprint_width_m() / 2.0 : 0.0);
  if (dose_plan_) lamp_floor_ = reachable_area(nav_, reach_planner_, room_sections_, start_, dose_plan_->reach_m);
  res_.reachable_cells = 0;
  for (const char c : reachable_) res_.reachable_cells += c != 0 ? 1 : 0;
}

// What the run measures after each step of the robot: on simulated time after each tick, on the
// robot's own threads after each sequencing period, on the sequencing thread.
void TaskRun::measure_when_busy() {
  if (robot_->planner().busy() && !measured_busy_) measure_room();
  measured_busy_ = robot_->planner().busy();
}

void TaskRun::note_sim_events() {
  for (; truth_.local() != nullptr && sim_events_noted_ < truth_.local()->events().size(); ++sim_events_noted_) {
    const sim::SimEvent& e = truth_.local()->events()[sim_events_noted_];
    life_.note(e.stamp, "simulator: " + std::string(sim::to_string(e.kind)) + (e.detail.empty() ? "" : " " + e.detail));
  }
}

void TaskRun::observe() {
  // (the simulator's events, written by the loop's thread on --realtime, are noted at the end)
  if (!threaded_) note_sim_events();
  const Time now = clock_.now();
  truth_.sample();
  const Pose2D true_pose = truth_.pose();
  const bool cleaning = is_cleaning();
  if (cleaning) {
    if (was_cleaning_)
      cleaned_.mark_segment({last_truth_.x_m, last_truth_.y_m}, {true_pose.x_m, true_pose.y_m}, half_width_);
    else
      cleaned_.mark_disc({true_pose.x_m, true_pose.y_m}, half_width_);
  }
  was_cleaning_ = cleaning;
  last_truth_ = true_pose;
  if (recording_) recording_->record(now, *robot_, life_);
  flush_log();
  if (now >= next_sample_) {  // 10 Hz trajectory
    next_sample_ += std::chrono::milliseconds(100);
    const NavigationData& navi = robot_->navigation();
    traj_.push_back({now, true_pose, navi.map_from_base, navi.localized, cleaning});
    path_all_.push_back({true_pose.x_m, true_pose.y_m});
    if (cleaning) path_cleaning_.push_back({true_pose.x_m, true_pose.y_m});
  }
  if (to_seconds(now) >= next_progress_s_) {
    draw_progress(false);
    next_progress_s_ += o_.progress_is_terminal ? (o_.realtime || serve_ ? 1.0 : 10.0) : 60.0;
  }
}

void TaskRun::monitor_update() {
  if (bridge_) bridge_->update();
  if (!monitor_.watch) return;
  monitor::MonitorExtras extras;
  extras.true_pose = truth_.pose();
  if (res_.reachable_cells > 0) extras.coverage = static_cast<double>(covered()) / static_cast<double>(res_.reachable_cells);
  extras.cleaned_mask = &cleaned_.mask();
  monitor_.watch->update(extras);
}

void TaskRun::drive() {
  if (threaded_)
    drive_threaded();
  else
    drive_stepped();
  monitor_update();
}

// The main thread only waits (and takes the signal); the robot's threads run the task.
void TaskRun::drive_threaded() {
  std::atomic<bool> busy{robot_->planner().busy()};
  bool warned = false;
  RealtimeOptions rto;
  rto.after_sequencing = [&](Time) {
    if (!warned && o_.log != nullptr) {  // what the threads asked of the system and were refused, once
      for (const std::string& w : robot_->realtime_warnings()) *o_.log << w << '\n';
      warned = true;
    }
    measure_when_busy();
    observe();
    busy.store(robot_->planner().busy(), std::memory_order_release);
  };
  robot_->start(std::move(rto));
  while (clock_.now() < deadline_ && !stopped() && busy.load(std::memory_order_acquire)) {
    wall_.sleep_until(wall_.now() + std::chrono::milliseconds(10));
  }
  robot_->stop();
  note_sim_events();
}

void TaskRun::drive_stepped() {
  while (clock_.now() < deadline_ && !stopped() && (serve_ || robot_->planner().busy())) {
    monitor_update();
    if ((monitor_.watch && monitor_.watch->paused()) || (bridge_ && bridge_->paused())) {
      wall_.sleep_until(wall_.now() + std::chrono::milliseconds(20));
      if (pacer_) pacer_.emplace(wall_, o_.realtime ? o_.realtime_speed : 1.0);  // no catching up after a pause
      continue;
    }
    measure_when_busy();
    robot_->run_for(tick_period_);
    observe();
    if (pacer_) pacer_->pace(clock_.now());
  }
}

// The task cancelled if it still runs, the base at rest, the recording written; returns when the
// run ended (the task's time: braking to rest is not part of it; on a remote base, which cannot be
// read back, it takes the whole braking allowance).
Time TaskRun::finish() {
  const int sig = stop_signal(o_.stop);
  res_.stopped_by = stop_reason(sig);
  if (robot_->planner().busy()) {
    robot_->planner().cancel(sig != 0 ? res_.stopped_by
                                      : "no end within " + fixed(o_.max_duration_s, 0) + " s of simulated time");
    robot_->step_sequencing();
    res_.state = sig != 0 ? "interrupted" : "timed out";
  }
  const Time ended = clock_.now();
  rest_base();
  if (recording_) {
    recording_->record(clock_.now(), *robot_, life_);
    const std::uint64_t messages = recording_->finish();
    if (o_.log != nullptr) {
      *o_.log << "recorded " << messages << " messages into " << o_.record.string()
              << (recording_->unrecorded_resources() > 0 ? " (" + std::to_string(recording_->unrecorded_resources()) +
                                                               " resources carry readings MCAP export does not)"
                                                         : std::string())
              << '\n';
    }
  }
  flush_log();
  draw_progress(true);
  return ended;
}

// Whatever ended the run, the base is left at rest before the devices close.
void TaskRun::rest_base() {
  WheelCommands commanded;
  if (board_hw_ != nullptr) {
    // The board's firmware holds the speeds the host asked (m/s); its motors then spin down with
    // their own inertia, which the simulator's wheels follow.
    const board::BoardFirmware& fw = board_hw_->embedded().firmware();
    std::array<double, 2> per_m_s{};
    board_hw_->simulator().inverse_kinematics({1.0, 0.0, 0.0}, per_m_s);  // rad/s of each wheel at 1 m/s
    commanded = [&fw, per_m_s] { return std::vector<double>{fw.required_m_s(0) * per_m_s[0], fw.required_m_s(1) * per_m_s[1]}; };
  } else if (const sim::Simulator* s = truth_.local()) {
    commanded = [s] { return std::vector<double>(s->wheel_commands().begin(), s->wheel_commands().end()); };
  }
  // On the robot's own threads (stopped by now) the controller brakes the wheels on this thread.
  const BaseStop rest = stop_base(*robot_, clock_, commanded, threaded_ ? Duration{0} : tick_period_);
  res_.base_command_at_end_rad_s = rest.command_rad_s;
  res_.base_at_rest = rest.at_rest;
}

void TaskRun::measure(Time ended) {
  const TaskReport tr = robot_->planner().report();
  res_.succeeded = tr.state == TaskState::succeeded;
  // With the monitor a task from the console may follow a refused --task: the last task counts.
  if (res_.state.empty() || (serve_ && res_.state == "refused" && tr.state != TaskState::idle))
    res_.state = std::string(to_string(tr.state));
  // A refused task leaves the planner idle: the refusal's words stay the reason.
  const bool only_refused = res_.state == "refused" && tr.state == TaskState::idle;
  if (!only_refused && (!serve_ || tr.state != TaskState::idle)) res_.reason = tr.reason;
  res_.duration_s = to_seconds(ended);
  set_floor_figures(res_, nav_, reachable_, cleaned_, path_all_, path_cleaning_);
  res_.total.length_m = truth_.distance_m();  // the ground truth's, not the sampled path's
  res_.total.rotation_rad = truth_.rotation_rad();
  res_.processes = report_.processes;
  res_.recoveries = report_.recoveries;
  res_.charging = charging_summary(tr);
  res_.collisions = truth_.collisions();
  res_.robot_steps = robot_->behavior_loop().cycles();
  if (threaded_) {
    res_.realtime_speed = o_.realtime_speed;
    res_.loops = robot_->timing();
  }
  for (const navi::LocalizationFault& f : world_.faults.localization_loss) {
    res_.faults.push_back("localization loss " + fixed(to_seconds(f.start), 1) + "-" + fixed(to_seconds(f.end), 1) + " s");
  }
  for (const sim::SimEvent& e : truth_.local() != nullptr ? truth_.local()->events() : std::vector<sim::SimEvent>{}) {
    res_.faults.push_back(fixed(to_seconds(e.stamp), 3) + " " + std::string(sim::to_string(e.kind)) +
                          (e.detail.empty() ? "" : " " + e.detail));
  }
  res_.sections = section_figures(nav_, room_sections_);
  if (board_hw_ != nullptr) {
    res_.disinfection = disinfection_figures(*board_hw_, reachable_, lamp_floor_, nav_.maps->grid(), target_dose_j_m2_);
    if (dose_plan_) {
      res_.disinfection->plan = *dose_plan_;
      res_.disinfection->estimate_s = res_.dose_estimate_s;
      res_.disinfection->estimate_ah = res_.dose_estimate_ah;
    }
  }
}

void TaskRun::write_outputs() const {
  if (o_.out.empty()) return;
  std::filesystem::create_directories(o_.out);
  write_png(o_.out / "map.png", draw_map(nav_, cleaned_, reachable_, traj_));
  if (board_hw_ != nullptr) {
    const std::vector<char>& floor = lamp_floor_.empty() ? reachable_ : lamp_floor_;
    const navi::OccupancyGrid& g = nav_.maps->grid();
    write_png(o_.out / "dose.png", draw_dose_map(g, floor, target_dose_j_m2_, [&](std::size_t i) {
                return board_hw_->uv_dose().dose_at_j_m2(g.cell_center(g.cell(i)));
              }));
  }
  write_text(o_.out / "trajectory.csv", trajectory_csv(traj_));
  write_text(o_.out / "report.json", res_.json());
  write_text(o_.out / "lifecycle.txt", life_.str());
}

}  // namespace

RunResult run_task(const RunOptions& o) {
  const RobotProfile profile = run_profile(o);
  // A port given (--hardware-param port=/dev/ttyUSB0): the devices are real, the run is run_devices.cpp's.
  if (runs_on_devices(profile)) return run_on_devices(o, profile);
  auto world = std::make_shared<sim::World>(sim::load_world(o.world));
  RunResult res;
  res.robot = profile.name;
  res.task = o.task;
  res.seed = o.seed.value_or(world->seed);
  res.coverage_pattern = o.pattern;
  std::vector<navi::LocalizationFault>& faults = world->faults.localization_loss;
  faults.insert(faults.end(), o.faults.begin(), o.faults.end());
  check_hardware_options(o, profile);
  TaskRun run(o, profile, world, res);
  run.start();
  run.drive();
  const Time ended = run.finish();
  run.measure(ended);
  run.write_outputs();
  return res;
}

}  // namespace tripodal::app
