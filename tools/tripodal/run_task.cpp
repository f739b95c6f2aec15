#include "run_task.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <deque>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "guide_hri.hpp"
#include "run_charging.hpp"
#include "run_outputs.hpp"
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
#include "tripodal/trace/mcap.hpp"
#include "tripodal/trace/rosbag.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_recorder.hpp"
#include "tripodal/trace/trace_writer.hpp"
#ifdef TRIPODAL_HAVE_DDS
#include "tripodal/dds/dds_hardware.hpp"
#include "tripodal/dds/robot_bridge.hpp"
#include "tripodal/dds/robot_modules.hpp"
#endif

namespace tripodal::app {

namespace {

using navi::Point2D;

// ---------------------------------------------------------------------------------------------
// Path figures

}  // namespace

PathFigures path_figures(const std::vector<Point2D>& path, double tolerance_m) {
  PathFigures f;
  if (path.size() < 2) return f;
  const std::vector<Point2D> simple = douglas_peucker(path, tolerance_m);
  const navi::PathStats s = navi::path_stats(simple, std::numbers::pi / 6.0);
  f.length_m = navi::polyline_length_m(path);
  f.turns = s.turns;
  return f;
}

namespace {

// The cells of the room a cleaning footprint can reach at all: within `reach_m` (half the cleaning
// width; for the UV dose, the lamp's reach) of a cell where the robot can stand (clearance >= its
// radius) connected to its start.
std::vector<char> reachable_area(const Navigation& nav, navi::PathPlanner& planner, const std::vector<std::string>& sections,
                                 Pose2D start, double reach_m) {
  const navi::OccupancyGrid& g = nav.maps->grid();
  if (nav.splitter == nullptr || nav.coverage == nullptr) return std::vector<char>(g.size(), 0);  // a robot that does not clean
  std::vector<char> in_room(g.size(), 0);
  for (const std::string& name : sections) {
    if (const navi::Section* s = nav.splitter->section(name)) {
      for (const std::size_t i : s->cells) in_room[i] = 1;
    }
  }
  std::vector<char> stand(g.size(), 0);
  std::deque<navi::CellIndex> queue;
  const navi::CellIndex s0 = g.cell_at({start.x_m, start.y_m});
  if (planner.traversable(s0)) {
    stand[g.index(s0)] = 1;
    queue.push_back(s0);
  }
  while (!queue.empty()) {
    const navi::CellIndex c = queue.front();
    queue.pop_front();
    for (const auto& d : std::array<navi::CellIndex, 4>{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}}) {
      const navi::CellIndex n{c.x + d.x, c.y + d.y};
      if (!planner.traversable(n) || stand[g.index(n)] != 0) continue;
      stand[g.index(n)] = 1;
      queue.push_back(n);
    }
  }
  const double r_cells = reach_m / g.resolution_m();
  const int r = static_cast<int>(std::floor(r_cells));
  std::vector<navi::CellIndex> disc;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      if (dx * dx + dy * dy <= r_cells * r_cells + 1e-9) disc.push_back({dx, dy});
    }
  }
  std::vector<char> reach(g.size(), 0);
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (stand[i] == 0) continue;
    const navi::CellIndex c = g.cell(i);
    for (const navi::CellIndex& d : disc) {
      const navi::CellIndex n{c.x + d.x, c.y + d.y};
      if (g.contains(n) && in_room[g.index(n)] != 0) reach[g.index(n)] = 1;
    }
  }
  return reach;
}

// What a dose-planned disinfection of these sections will take, for the up-front check: each
// section's coverage path as it will be planned, at its lane speeds, its turns at the cleaning
// behavior's yaw rate, the way between sections at the lane speed; the charge from the board's
// currents (the lamp and the boards all along, the atomizer while the tank lasts, the motors at
// the duty of the speed).
struct DoseEstimate {
  double time_s = 0.0;
  double charge_ah = 0.0;
  double path_m = 0.0;
};

DoseEstimate estimate_dose(navi::CCoverageModule& cov, const navi::CSectionSplitter& splitter,
                           const std::vector<std::string>& sections, Point2D from, const board::FirmwareConfig& fw) {
  double yaw_rate = 1.0;
  for (const ParameterSpec& p : BhCleaningTwoWheel::static_manifest().parameters) {
    if (p.name == "max_yaw_rate_rad_s" && p.default_value) yaw_rate = std::get<double>(*p.default_value);
  }
  const double plan_speed = cov.dose_plan() ? cov.dose_plan()->speed_m_s : cov.dose_limits().max_speed_m_s;
  DoseEstimate e;
  double motor_as = 0.0;  // motor duty x seconds, both motors
  for (const std::string& name : sections) {
    const navi::Section* sec = splitter.section(name);
    if (sec == nullptr) continue;
    const navi::CoverageResult r = cov.plan(*sec, from);
    if (r.path.empty()) continue;
    const double transit = std::hypot(r.path.front().x_m - from.x_m, r.path.front().y_m - from.y_m);
    e.time_s += transit / plan_speed;
    motor_as += 2.0 * plan_speed / fw.max_wheel_speed_m_s * transit / plan_speed;
    for (std::size_t i = 0; i + 1 < r.path.size(); ++i) {
      const double v = i < r.speed_m_s.size() ? r.speed_m_s[i] : plan_speed;
      const double len = std::hypot(r.path[i + 1].x_m - r.path[i].x_m, r.path[i + 1].y_m - r.path[i].y_m);
      e.time_s += len / v;
      e.path_m += len;
      motor_as += 2.0 * v / fw.max_wheel_speed_m_s * len / v;
    }
    // turning in place: one motor forward, one back, at the yaw rate's wheel speed
    const int passes = cov.dose_plan() ? cov.dose_plan()->passes : 1;
    e.time_s += passes * r.stats.total_turn_rad / yaw_rate;
    from = r.path.back();
  }
  const double atomizer_s = std::min(e.time_s, fw.tank_initial_l / fw.atomizer_l_per_h * 3600.0);
  e.charge_ah = ((fw.idle_current_a + fw.uv_lamp_current_a) * e.time_s + fw.atomizer_current_a * atomizer_s +
                 fw.motor_current_a * motor_as) /
                3600.0;
  return e;
}

std::string step_text(const ProcessStep& s) {
  std::string out = s.process + "(";
  for (std::size_t i = 0; i < s.params.size(); ++i) out += (i ? ", " : "") + s.params[i].name + "=" + s.params[i].value;
  return out + ")";
}

// Collects the processes and recoveries of the task for the report.
class ReportObserver final : public TaskObserver {
 public:
  std::vector<std::string> processes, recoveries;
  std::string current;  // the process running now, for the progress bar
  void on_process_started(const ProcessRecord& p) override { current = step_text(p.step); }
  void on_process_succeeded(const ProcessRecord& p) override { add(p, "succeeded"); }
  void on_process_failed(const ProcessRecord& p) override { add(p, "failed: " + p.message); }
  void on_recovery(const RecoveryRecord& r) override {
    recoveries.push_back(fixed(to_seconds(r.time), 3) + " " + r.reason);
  }

 private:
  void add(const ProcessRecord& p, const std::string& how) {
    processes.push_back(fixed(to_seconds(p.started), 3) + "-" + fixed(to_seconds(p.finished.value_or(p.started)), 3) + " " + p.run +
                        " " + step_text(p.step) + " " + how);
    current.clear();
  }
};

// The dose of each reachable cell (the dose map is on the world's grid, the reachable cells on the
// robot's map: matched by the cell centre), the tank, and both sides of the link.
DisinfectionFigures disinfection_figures(sim::SimBoardHardware& hw, const std::vector<char>& reachable,
                                         const std::vector<char>& lamp_floor, const navi::OccupancyGrid& grid, double target_j_m2,
                                         double soc_at_start) {
  DisinfectionFigures f;
  board::EmbeddedBoard& b = hw.embedded();
  const std::filesystem::path device = b.device();
  f.line = device.empty() ? "in_process" : "pty " + device.string();
  f.uv_target_dose_j_m2 = target_j_m2;
  std::vector<double> doses;
  for (std::size_t i = 0; i < reachable.size(); ++i) {
    if (reachable[i] != 0) doses.push_back(hw.uv_dose().dose_at_j_m2(grid.cell_center(grid.cell(i))));
  }
  if (!doses.empty()) {
    const auto dosed = std::count_if(doses.begin(), doses.end(), [&](double d) { return d >= target_j_m2; });
    f.dose_coverage = static_cast<double>(dosed) / static_cast<double>(doses.size());
    auto mid = doses.begin() + static_cast<std::ptrdiff_t>(doses.size() / 2);
    std::nth_element(doses.begin(), mid, doses.end());
    f.median_dose_j_m2 = *mid;
  }
  std::size_t floor_cells = 0, floor_dosed = 0;
  for (std::size_t i = 0; i < lamp_floor.size(); ++i) {
    if (lamp_floor[i] == 0) continue;
    ++floor_cells;
    floor_dosed += hw.uv_dose().dose_at_j_m2(grid.cell_center(grid.cell(i))) >= target_j_m2 ? 1 : 0;
  }
  f.lamp_floor_m2 = static_cast<double>(floor_cells) * grid.resolution_m() * grid.resolution_m();
  f.lamp_floor_dose_coverage = floor_cells == 0 ? 0.0 : static_cast<double>(floor_dosed) / static_cast<double>(floor_cells);
  f.lamp_on_s = to_seconds(hw.uv_dose().lamp_on());
  const board::FirmwareConfig& fc = b.firmware().config();
  f.battery_used_ah = b.firmware().charge_drawn_ah();  // what the load drew, charges on the dock aside
  (void)soc_at_start;
  const double volts = b.firmware().battery().voltage_mv > 0 ? b.firmware().battery().voltage_mv / 1000.0 : board::kBatteryFullV;
  f.lamp_energy_wh = fc.uv_lamp_current_a * 0.5 * (board::kBatteryFullV + volts) * f.lamp_on_s / 3600.0;
  f.uvc_energy_j = hw.uv_dose().lamp().uvc_power_w * f.lamp_on_s;
  f.disinfectant_left_l = b.firmware().tank_l();
  f.disinfectant_used_l = b.firmware().disinfectant_used_l();
  f.link = b.host().link().stats();
  f.decoder_errors = b.host().link().decoder_stats().errors() + b.firmware().decoder_stats().errors();
  f.board_requests = b.firmware().counters().requests;
  f.watchdog_trips = b.firmware().counters().watchdog_trips;
  f.bytes_to_board = b.line().host().bytes_sent();
  f.bytes_to_host = b.line().board().bytes_sent();
  f.bytes_lost = b.line().host().bytes_lost() + b.line().board().bytes_lost();
  return f;
}

}  // namespace


std::vector<ParameterOverride> simulation_overrides(const RobotProfile& profile, const sim::World& world, std::uint64_t seed) {
  std::vector<ParameterOverride> out;
  // A simulator in this process takes the seed (a sim-server has its own --seed).
  if (profile.hardware && (profile.hardware->type == "sim" || profile.hardware->type == "board")) {
    out.push_back({profile.hardware->name, "seed", std::to_string(seed)});
  }
  for (const ModuleEntry& e : profile.navigation) {
    if (e.type == navi::CLocalizer::static_manifest().name) out.push_back({e.name, "seed", std::to_string(seed % (1ULL << 52))});
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
class WorldDdsHardware final : public dds::DdsHardware, public navi::MapSource {
 public:
  WorldDdsHardware(const HardwareConfig& c, std::shared_ptr<const sim::World> world) : DdsHardware(c), world_(std::move(world)) {}
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

// What a run measures itself by: the simulator's ground truth, in this process, or in the
// sim-server's, as its lock-step answers carry it (before the first: the world's start).
class GroundTruth {
 public:
  GroundTruth(CHardware* hw, Pose2D start) : start_(start) {
    if (auto* s = dynamic_cast<sim::SimulatorSources*>(hw)) {
      sources_ = s;
      local_ = &s->simulation();
    }
#ifdef TRIPODAL_HAVE_DDS
    remote_ = dynamic_cast<const dds::DdsHardware*>(hw);
#endif
  }
  [[nodiscard]] const sim::Simulator* local() const noexcept { return local_; }
  /// Any thread: the pose the hardware published after its last advance.
  [[nodiscard]] Pose2D pose() const {
    if (sources_ != nullptr) return sources_->true_pose(Time{}).value_or(start_);
#ifdef TRIPODAL_HAVE_DDS
    if (remote_ != nullptr && remote_->truth()) return remote_->truth()->map_from_base;
#endif
    return start_;
  }
  [[nodiscard]] double distance_m() const {
    if (local_ != nullptr) return local_->distance_m();
#ifdef TRIPODAL_HAVE_DDS
    if (remote_ != nullptr && remote_->truth()) return remote_->truth()->distance_m;
#endif
    return 0.0;
  }
  [[nodiscard]] std::size_t collisions() const {
    if (local_ != nullptr) return local_->collisions();
#ifdef TRIPODAL_HAVE_DDS
    if (remote_ != nullptr && remote_->truth()) return remote_->truth()->collisions;
#endif
    return 0;
  }
  /// Of the body, absolute (rad): the simulator's own, or summed from the poses sampled here.
  [[nodiscard]] double rotation_rad() const { return local_ != nullptr ? local_->rotation_rad() : sampled_rotation_rad_; }
  void sample() {
    const Pose2D p = pose();
    sampled_rotation_rad_ += std::abs(wrap_angle(p.theta_rad - last_.theta_rad));
    last_ = p;
  }

 private:
  Pose2D start_;
  Pose2D last_ = start_;
  double sampled_rotation_rad_ = 0.0;
  const sim::Simulator* local_ = nullptr;
  const sim::SimulatorSources* sources_ = nullptr;
#ifdef TRIPODAL_HAVE_DDS
  const dds::DdsHardware* remote_ = nullptr;
#endif
};

/// `tripodal run --record FILE.mcap`: the run is recorded into a trace beside FILE (the recorder
/// writes as the run goes, so a long run holds no readings in memory), which becomes MCAP at the
/// end through the trace kit's exporter, so that the file replays as a trace and opens in any MCAP
/// tool. The life cycle (task, processes, every firing) goes to the "events" channel.
class RunRecording {
 public:
  RunRecording(const std::filesystem::path& mcap, const Robot& robot)
      : mcap_(mcap), trace_path_(with_parent_folder(mcap.string() + ".trace.partial")), writer_(trace_path_), recorder_(writer_) {
    const ResourceTable& table = robot.resources();
    for (std::size_t i = 0; i < table.size(); ++i) {
      try {
        recorder_.watch(table.at(i));
      } catch (const std::invalid_argument&) {
        ++unrecorded_;  // a reading the trace format does not carry (joints, buttons ...)
      }
    }
    recorder_.record_commands("cmd");
    recorder_.record_events("events");
  }
  RunRecording(const RunRecording&) = delete;
  RunRecording& operator=(const RunRecording&) = delete;
  ~RunRecording() {
    std::error_code ignored;
    std::filesystem::remove(trace_path_, ignored);
  }

  void record(Time now, Robot& robot, const LifecycleRecorder& life) {
    recorder_.record(now);
    const CoordinatorOutput& fused = robot.behavior_loop().coordinator().output();
    recorder_.record_command(fused.stamp, fused.command, fused.winner);
    for (; noted_ < life.entries().size(); ++noted_) {
      const LifecycleEntry& e = life.entries()[noted_];
      recorder_.record_event(e.time, e.text);
    }
  }

  /// Writes the MCAP file; returns how many messages it holds.
  std::uint64_t finish() {
    writer_.close();
    trace::TraceReader reader(trace_path_);
    trace::mcap::Writer out(mcap_);
    trace::export_trace_to_mcap(reader, out);
    return out.messages_written();
  }

  [[nodiscard]] std::size_t unrecorded_resources() const noexcept { return unrecorded_; }

 private:
  // As --out does, the file's folder is made when missing (its failure is the writer's to report).
  static std::filesystem::path with_parent_folder(std::filesystem::path file) {
    std::error_code ignored;
    if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ignored);
    return file;
  }

  std::filesystem::path mcap_;
  std::filesystem::path trace_path_;
  trace::TraceWriter writer_;
  trace::TraceRecorder recorder_;
  std::size_t noted_ = 0;
  std::size_t unrecorded_ = 0;
};

RunResult run_task(const RunOptions& o) {
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
  auto world = std::make_shared<sim::World>(sim::load_world(o.world));
  RunResult res;
  res.robot = profile.name;
  res.task = o.task;
  res.seed = o.seed.value_or(world->seed);
  res.coverage_pattern = o.pattern;
  std::vector<navi::LocalizationFault>& faults = world->faults.localization_loss;
  faults.insert(faults.end(), o.faults.begin(), o.faults.end());
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

  // The robot, on simulated hardware in this world, with this run's seed and coverage pattern;
  // the board's modules and actuator behaviors for a robot on the control board.
  RobotPlugins plugins;
  register_tool_plugins(plugins, world, profile, o.plugins);
  RobotOptions ro;
  ro.parameters = simulation_overrides(profile, *world, res.seed);
  if (!o.board_line.empty()) ro.parameters.push_back({profile.hardware->name, "line", o.board_line});
  for (const ModuleEntry& e : profile.navigation) {
    if (e.type != navi::CCoverageModule::static_manifest().name) continue;
    if (!o.pattern.empty()) ro.parameters.push_back({e.name, "pattern", o.pattern});
    // The dose the lanes are planned for (the profile's dose_target_j_m2 otherwise).
    if (!o.dose_plan)
      ro.parameters.push_back({e.name, "dose_target_j_m2", "0"});
    else if (o.uv_target_dose_j_m2)
      ro.parameters.push_back({e.name, "dose_target_j_m2", fmt::format("{}", *o.uv_target_dose_j_m2)});
  }
  // --realtime (without a monitor or DDS, which pace one thread): the robot on its own threads, on
  // the wall clock sped up SPEED times; otherwise the caller's thread steps it on simulated time.
  const bool threaded = o.realtime && !o.monitor && !profile.dds;
  if (threaded && !o.record.empty()) {
    throw ConfigError(SourceLocation{"--record", 1, 1},
                      "--record goes with a run on simulated time (without --realtime): its recorder "
                      "reads the loop between cycles, which the robot's own threads do not leave");
  }
  SimClock sim_clock;
  ScaledClock wall_clock(o.realtime_speed);
  Clock& clock = threaded ? static_cast<Clock&>(wall_clock) : static_cast<Clock&>(sim_clock);
  const auto robot = Robot::assemble(profile, plugins, clock, ro);
  GroundTruth truth(robot->hardware(), world->start_pose);
  // A plugin's hardware type runs here when it simulates (derives from sim::SimHardware).
  if (!remote && truth.local() == nullptr) {
    throw ConfigError(profile.hardware->where, "hardware type '" + profile.hardware->type +
                                                   "' does not run on the simulator: `tripodal run` needs hardware: {type: sim}, "
                                                   "{type: board}, {type: dds} or a type derived from sim::SimHardware");
  }
  sim::SimBoardHardware* const board_hw = dynamic_cast<sim::SimBoardHardware*>(robot->hardware());
  Navigation nav{robot->module<navi::CGridMaps>(), robot->module<navi::CSectionSplitter>(), robot->module<navi::CCoverageModule>()};
  if (nav.coverage != nullptr) res.coverage_pattern = nav.coverage->pattern();
  // Cleaning is measured when the robot has SectionSplitter and CoveragePlanner; the map always.
  if (nav.maps == nullptr)
    throw ConfigError(profile.where, "`tripodal run` measures the run on the map: the robot needs a GridMaps module");
  if (nav.maps->robot_radius_m() < world->robot.radius_m) {
    throw ConfigError(nav.maps->where(), "robot_radius_m " + fixed(nav.maps->robot_radius_m(), 3) +
                                             " m is smaller than the simulated body (" + fixed(world->robot.radius_m, 3) +
                                             " m): planned paths would collide");
  }
  const Pose2D start = world->start_pose;
  // The planner's lamp must be the one the simulated board lights (one lamp, two consumers).
  static const std::optional<navi::DosePlan> no_dose_plan;
  const std::optional<navi::DosePlan>& dose_plan = nav.coverage != nullptr ? nav.coverage->dose_plan() : no_dose_plan;
  if (board_hw != nullptr && dose_plan) {
    const navi::UvLamp& a = nav.coverage->uv_lamp();
    const navi::UvLamp& b = board_hw->uv_dose().lamp();
    if (a.uvc_power_w != b.uvc_power_w || a.height_m != b.height_m || a.radius_m != b.radius_m) {
      throw ConfigError(nav.coverage->where(),
                        fmt::format("the coverage planner plans the dose for a lamp of {} W, {} m high, {} m lit "
                                    "radius, the board's lamp is {} W, {} m, {} m: give both the same uv_ parameters",
                                    a.uvc_power_w, a.height_m, a.radius_m, b.uvc_power_w, b.height_m, b.radius_m));
    }
  }
  const double target_dose_j_m2 = o.uv_target_dose_j_m2.value_or(dose_plan ? dose_plan->target_j_m2 : kDefaultUvTargetDose);
  const double soc_at_start = board_hw != nullptr ? board_hw->embedded().firmware().state_of_charge() : 0.0;
  if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(start);
  LifecycleRecorder life(true);
  ReportObserver report;
  robot->planner().add_observer(life);
  robot->supervisor().add_observer(life);
  robot->planner().add_observer(report);
  std::unique_ptr<RunRecording> recording;
  if (!o.record.empty()) recording = std::make_unique<RunRecording>(o.record, *robot);

  // On DDS without a task given here, the run waits for one from a peer: paced like the monitor's.
  const std::unique_ptr<DdsBridge> bridge = make_dds_bridge(*robot, clock, profile);
  const bool serve_dds = bridge != nullptr && o.task.empty();
  if (bridge && o.log != nullptr) {
    *o.log << "dds: domain " << profile.dds->domain_id << ", namespace '" << profile.dds->ros_namespace << "' ("
           << bridge->topic("events") << (profile.dds->tasks ? ", tasks on " + bridge->topic("task") : std::string()) << ")\n";
    o.log->flush();
  }

  SteadyClock wall;
  std::optional<sim::RealtimePacer> pacer;
  if (!threaded && (o.realtime || o.monitor || serve_dds)) pacer.emplace(wall, o.realtime ? o.realtime_speed : 1.0);

  // The monitor: its own thread serves the clients; this loop hands it the robot's state and takes
  // the operator's requests between periods.
  std::unique_ptr<monitor::MonitorServer> server;
  std::unique_ptr<monitor::RobotMonitor> watch;
  if (o.monitor) {
    monitor::MonitorServerOptions so = monitor::server_options(*o.monitor, o.monitor_token_file);
    so.read_without_token = o.monitor_read_open;
    so.allowed_hosts = o.monitor_allowed_hosts;
    so.allowed_origins = o.monitor_allowed_origins;
    server = std::make_unique<monitor::MonitorServer>(std::move(so));
    // the operator's live maps go beside the run's own outputs
    watch = std::make_unique<monitor::RobotMonitor>(*robot, clock, *server,
                                                    monitor::RobotMonitorOptions{.start_paused = o.start_paused, .map_dir = o.out});
    server->start();
    if (o.log != nullptr) {
      *o.log << "monitor: " << server->url() << "  (token " << server->token() << (o.start_paused ? "; paused until resumed" : "")
             << ")\n";
      o.log->flush();
    }
  }
  const bool serve = watch != nullptr || serve_dds;
  auto stopped = [&] { return o.stop != nullptr && *o.stop != 0; };

  if (!threaded) robot->run_until(sim_clock.now());  // the localizer's first estimate, before the planner asks where to start
  std::size_t printed = 0;
  bool bar_shown = false;  // a bar drawn in place on the terminal, to be wiped before a log line
  auto flush_log = [&] {
    if (o.log == nullptr) return;
    if (bar_shown && printed < life.entries().size() && o.progress != nullptr) {
      *o.progress << '\r' << std::string(100, ' ') << '\r';
      o.progress->flush();
      bar_shown = false;
    }
    for (; printed < life.entries().size(); ++printed) {
      const LifecycleEntry& e = life.entries()[printed];
      if (e.text.find(" fire ") != std::string::npos) continue;  // every firing: in lifecycle.txt only
      *o.log << std::setw(9) << fixed(to_seconds(e.time), 1) << " s  " << e.text << '\n';
    }
    o.log->flush();
  };
  if (!o.task.empty()) {
    const CommandAnswer answer = robot->command(o.task);
    if (!answer.accepted) {
      res.state = "refused";
      res.reason = answer.text;
      if (o.log != nullptr) *o.log << answer.text << '\n';
      // Not served, the run ends here, but it still writes its (empty) map and report below.
    }
  }
  flush_log();

  // The room's sections and the reachable area, for the measures: of the task running (a task
  // submitted on the monitor's console is measured from when it starts).
  std::vector<std::string> room_sections;
  std::vector<char> reachable(nav.maps->grid().size(), 0);  // none until a task names its room
  std::vector<char> lamp_floor;                             // with a dose plan: the floor the lamp can dose at all
  navi::PathPlanner reach_planner(nav.maps->grid(), navi::PathPlannerOptions{.robot_radius_m = nav.maps->robot_radius_m()});
  auto measure_room = [&] {
    room_sections.clear();
    for (const PlanStage& stage : robot->planner().current_plan().stages) {
      for (const ProcessStep& step : stage.steps) {
        for (const BindingParam& p : step.params) {
          if (p.name == "section" && std::find(room_sections.begin(), room_sections.end(), p.value) == room_sections.end()) {
            room_sections.push_back(p.value);
          }
        }
      }
    }
    reachable = reachable_area(nav, reach_planner, room_sections, start,
                               nav.coverage != nullptr ? nav.coverage->footprint_width_m() / 2.0 : 0.0);
    if (dose_plan) lamp_floor = reachable_area(nav, reach_planner, room_sections, start, dose_plan->reach_m);
    res.reachable_cells = 0;
    for (const char c : reachable) res.reachable_cells += c != 0 ? 1 : 0;
  };
  bool measured_busy = robot->planner().busy();
  if (measured_busy) measure_room();
  // A dose-planned disinfection is checked up front: refused when the battery (down to the board
  // monitor's low threshold) or the time limit cannot carry it.
  if (measured_busy && dose_plan && board_hw != nullptr && nav.splitter != nullptr) {
    const board::BoardFirmware& fw = board_hw->embedded().firmware();
    double low_percent = 15.0;
    for (const ModuleEntry& e : profile.modules) {
      if (e.type != "BoardMonitor") continue;
      if (const auto it = e.parameters.find("battery_low_percent"); it != e.parameters.end()) low_percent = std::stod(it->second);
    }
    const double available_ah = std::max(0.0, fw.state_of_charge() - low_percent / 100.0) * fw.config().battery_capacity_ah;
    const DoseEstimate est = estimate_dose(*nav.coverage, *nav.splitter, room_sections, {start.x_m, start.y_m}, fw.config());
    res.dose_estimate_s = est.time_s;
    res.dose_estimate_ah = est.charge_ah;
    if (o.log != nullptr) {
      *o.log << fmt::format(
          "dose plan: {} J/m2: lanes {:.2f} m apart at {:.3f} m/s (faster between closer lanes), {} pass{}; "
          "estimated {:.0f} s, {:.2f} Ah of the {:.2f} Ah above the {}% low-battery mark\n",
          dose_plan->target_j_m2, dose_plan->spacing_m, dose_plan->speed_m_s, dose_plan->passes,
          dose_plan->passes > 1 ? "es" : "", est.time_s, est.charge_ah, available_ah, low_percent);
    }
    std::string why;
    const std::optional<ChargingStops> stops =
        est.charge_ah > available_ah ? plan_charging_stops(profile, *world, fw.config(), est.charge_ah, available_ah, low_percent)
                                     : std::nullopt;
    if (stops && o.log != nullptr) {
      *o.log << fmt::format("more than one charge: {} stop{} at the dock '{}' planned (about {:.0f} s charging)\n", stops->stops,
                            stops->stops == 1 ? "" : "s", stops->dock, stops->charge_s);
    }
    if (stops && o.time_limit_s && est.time_s + stops->charge_s > *o.time_limit_s) {
      why = fmt::format(
          "target dose {} J/m2 cannot be reached within the time limit of {:.0f} s: the plan needs about {:.0f} s "
          "and {:.0f} s of charging at the dock",
          dose_plan->target_j_m2, *o.time_limit_s, est.time_s, stops->charge_s);
    } else if (est.charge_ah > available_ah && !stops) {
      why = fmt::format(
          "target dose {} J/m2 cannot be reached within the battery: the plan (lanes {:.2f} m apart at {:.3f} m/s, "
          "{} pass{}) needs about {:.2f} Ah ({:.0f} s), the battery holds {:.2f} Ah above the {}% low mark",
          dose_plan->target_j_m2, dose_plan->spacing_m, dose_plan->speed_m_s, dose_plan->passes,
          dose_plan->passes > 1 ? "es" : "", est.charge_ah, est.time_s, available_ah, low_percent);
    } else if (o.time_limit_s && est.time_s > *o.time_limit_s) {
      why = fmt::format(
          "target dose {} J/m2 cannot be reached within the time limit of {:.0f} s: the plan (lanes {:.2f} m apart "
          "at {:.3f} m/s, {} pass{}) needs about {:.0f} s",
          dose_plan->target_j_m2, *o.time_limit_s, dose_plan->spacing_m, dose_plan->speed_m_s, dose_plan->passes,
          dose_plan->passes > 1 ? "es" : "", est.time_s);
    }
    if (!why.empty()) {
      robot->planner().cancel(why);
      robot->step_sequencing();
      res.state = "refused";
      res.reason = why;
      if (o.log != nullptr) *o.log << why << '\n';
    }
  }

  navi::CleanedCells cleaned(nav.maps->grid());  // from the true pose, while a cleaning behavior runs
  std::vector<TrajectorySample> traj;
  std::vector<Point2D> path_all, path_cleaning;
  const double half_width =
      nav.coverage != nullptr ? nav.coverage->footprint_width_m() / 2.0 : 0.0;  // the fog's, whatever the lanes' spacing
  const Duration tick_period = robot->behavior_loop().period();
  const Time deadline = time_from_seconds(o.max_duration_s);
  bool was_cleaning = false;
  Pose2D last_truth = truth.pose();
  double next_progress_s = 0.0;
  Time next_sample = clock.now();
  auto is_cleaning = [&] { return robot->behavior_active("BhCleaning") || robot->behavior_active("BhCleaningTwoWheel"); };
  auto covered = [&] {
    std::size_t n = 0;
    for (std::size_t i = 0; i < reachable.size(); ++i) n += (reachable[i] != 0 && cleaned.cleaned(i)) ? 1 : 0;
    return n;
  };
  auto draw_progress = [&](bool final) {
    if (o.progress == nullptr) return;
    *o.progress << (o.progress_is_terminal ? "\r" : "");
    if (res.reachable_cells > 0) {  // a cleaning task: the bar is the coverage of the room
      const double cov = static_cast<double>(covered()) / static_cast<double>(res.reachable_cells);
      constexpr int kWidth = 30;
      const int full = static_cast<int>(std::lround(cov * kWidth));
      *o.progress << '[' << std::string(static_cast<std::size_t>(full), '#')
                  << std::string(static_cast<std::size_t>(kWidth - full), '.') << "] " << std::setw(5) << fixed(100.0 * cov, 1)
                  << " %  ";
    }
    *o.progress << "t=" << std::setw(7) << fixed(to_seconds(clock.now()), 0) << " s  "
                << (report.current.empty() ? "-" : report.current) << (o.progress_is_terminal && !final ? "          " : "\n");
    o.progress->flush();
    bar_shown = o.progress_is_terminal && !final;
  };

  std::size_t sim_events_noted = 0;
  auto monitor_update = [&] {
    if (bridge) bridge->update();
    if (!watch) return;
    monitor::MonitorExtras extras;
    extras.true_pose = truth.pose();
    if (res.reachable_cells > 0) extras.coverage = static_cast<double>(covered()) / static_cast<double>(res.reachable_cells);
    extras.cleaned_mask = &cleaned.mask();
    watch->update(extras);
  };
  // What the run measures after each step of the robot: on simulated time after each tick, on the
  // robot's own threads after each sequencing period, on the sequencing thread.
  auto measure_when_busy = [&] {
    if (robot->planner().busy() && !measured_busy) measure_room();
    measured_busy = robot->planner().busy();
  };
  auto observe = [&] {
    // (the simulator's events, written by the loop's thread on --realtime, are noted at the end)
    for (; !threaded && truth.local() != nullptr && sim_events_noted < truth.local()->events().size(); ++sim_events_noted) {
      const sim::SimEvent& e = truth.local()->events()[sim_events_noted];
      life.note(e.stamp, "simulator: " + std::string(sim::to_string(e.kind)) + (e.detail.empty() ? "" : " " + e.detail));
    }
    const Time now = clock.now();
    truth.sample();
    const Pose2D true_pose = truth.pose();
    const bool cleaning = is_cleaning();
    if (cleaning) {
      if (was_cleaning)
        cleaned.mark_segment({last_truth.x_m, last_truth.y_m}, {true_pose.x_m, true_pose.y_m}, half_width);
      else
        cleaned.mark_disc({true_pose.x_m, true_pose.y_m}, half_width);
    }
    was_cleaning = cleaning;
    last_truth = true_pose;
    if (recording) recording->record(now, *robot, life);
    flush_log();
    if (now >= next_sample) {  // 10 Hz trajectory
      next_sample += std::chrono::milliseconds(100);
      const NavigationData& navi = robot->navigation();
      traj.push_back({now, true_pose, navi.map_from_base, navi.localized, cleaning});
      path_all.push_back({true_pose.x_m, true_pose.y_m});
      if (cleaning) path_cleaning.push_back({true_pose.x_m, true_pose.y_m});
    }
    if (to_seconds(now) >= next_progress_s) {
      draw_progress(false);
      next_progress_s += o.progress_is_terminal ? (o.realtime || serve ? 1.0 : 10.0) : 60.0;
    }
  };
  if (threaded) {
    // The main thread only waits (and takes the signal); the robot's threads run the task.
    std::atomic<bool> busy{robot->planner().busy()};
    bool warned = false;
    RealtimeOptions rto;
    rto.after_sequencing = [&](Time) {
      if (!warned && o.log != nullptr) {  // what the threads asked of the system and were refused, once
        for (const std::string& w : robot->realtime_warnings()) *o.log << w << '\n';
        warned = true;
      }
      measure_when_busy();
      observe();
      busy.store(robot->planner().busy(), std::memory_order_release);
    };
    robot->start(std::move(rto));
    while (clock.now() < deadline && !stopped() && busy.load(std::memory_order_acquire)) {
      wall.sleep_until(wall.now() + std::chrono::milliseconds(10));
    }
    robot->stop();
    for (; truth.local() != nullptr && sim_events_noted < truth.local()->events().size(); ++sim_events_noted) {
      const sim::SimEvent& e = truth.local()->events()[sim_events_noted];
      life.note(e.stamp, "simulator: " + std::string(sim::to_string(e.kind)) + (e.detail.empty() ? "" : " " + e.detail));
    }
  }
  while (!threaded && clock.now() < deadline && !stopped() && (serve || robot->planner().busy())) {
    monitor_update();
    if ((watch && watch->paused()) || (bridge && bridge->paused())) {
      wall.sleep_until(wall.now() + std::chrono::milliseconds(20));
      if (pacer) pacer.emplace(wall, o.realtime ? o.realtime_speed : 1.0);  // no catching up after a pause
      continue;
    }
    measure_when_busy();
    robot->run_for(tick_period);
    observe();
    if (pacer) pacer->pace(clock.now());
  }
  monitor_update();
  const int sig = stop_signal(o.stop);
  res.stopped_by = stop_reason(sig);
  if (robot->planner().busy()) {
    robot->planner().cancel(sig != 0 ? res.stopped_by : "no end within " + fixed(o.max_duration_s, 0) + " s of simulated time");
    robot->step_sequencing();
    res.state = sig != 0 ? "interrupted" : "timed out";
  }
  // The run's time is the task's: braking to rest below is not part of it (on a remote base,
  // which cannot be read back, it takes the whole braking allowance).
  const Time ended = clock.now();
  // Whatever ended the run, the base is left at rest before the devices close.
  WheelCommands commanded;
  if (board_hw != nullptr) {
    // The board's firmware holds the speeds the host asked (m/s); its motors then spin down with
    // their own inertia, which the simulator's wheels follow.
    const board::BoardFirmware& fw = board_hw->embedded().firmware();
    std::array<double, 2> per_m_s{};
    board_hw->simulator().inverse_kinematics({1.0, 0.0, 0.0}, per_m_s);  // rad/s of each wheel at 1 m/s
    commanded = [&fw, per_m_s] { return std::vector<double>{fw.required_m_s(0) * per_m_s[0], fw.required_m_s(1) * per_m_s[1]}; };
  } else if (const sim::Simulator* s = truth.local()) {
    commanded = [s] { return std::vector<double>(s->wheel_commands().begin(), s->wheel_commands().end()); };
  }
  // On the robot's own threads (stopped by now) the wheels are commanded zero at once.
  const BaseStop rest = stop_base(*robot, commanded, threaded ? Duration{0} : tick_period);
  res.base_command_at_end_rad_s = rest.command_rad_s;
  res.base_at_rest = rest.at_rest;
  if (recording) {
    recording->record(clock.now(), *robot, life);
    const std::uint64_t messages = recording->finish();
    if (o.log != nullptr) {
      *o.log << "recorded " << messages << " messages into " << o.record.string()
             << (recording->unrecorded_resources() > 0
                     ? " (" + std::to_string(recording->unrecorded_resources()) + " resources carry readings MCAP export does not)"
                     : std::string())
             << '\n';
    }
  }
  flush_log();
  draw_progress(true);

  const TaskReport tr = robot->planner().report();
  res.succeeded = tr.state == TaskState::succeeded;
  // With the monitor a task from the console may follow a refused --task: the last task counts.
  if (res.state.empty() || (serve && res.state == "refused" && tr.state != TaskState::idle)) res.state = std::string(to_string(tr.state));
  // A refused task leaves the planner idle: the refusal's words stay the reason.
  const bool only_refused = res.state == "refused" && tr.state == TaskState::idle;
  if (!only_refused && (!serve || tr.state != TaskState::idle)) res.reason = tr.reason;
  res.duration_s = to_seconds(ended);
  res.cleaned_cells = covered();
  res.coverage = res.reachable_cells == 0 ? 0.0 : static_cast<double>(res.cleaned_cells) / static_cast<double>(res.reachable_cells);
  const double res_m = nav.maps->grid().resolution_m();
  res.reachable_area_m2 = static_cast<double>(res.reachable_cells) * res_m * res_m;
  res.total = path_figures(path_all);
  res.total.length_m = truth.distance_m();
  res.total.rotation_rad = truth.rotation_rad();
  res.cleaning = path_figures(path_cleaning);
  res.processes = report.processes;
  res.recoveries = report.recoveries;
  res.charging = charging_summary(tr);
  res.collisions = truth.collisions();
  res.robot_steps = robot->behavior_loop().cycles();
  if (threaded) {
    res.realtime_speed = o.realtime_speed;
    res.loops = robot->timing();
  }
  for (const navi::LocalizationFault& f : faults) {
    res.faults.push_back("localization loss " + fixed(to_seconds(f.start), 1) + "-" + fixed(to_seconds(f.end), 1) + " s");
  }
  for (const sim::SimEvent& e : truth.local() != nullptr ? truth.local()->events() : std::vector<sim::SimEvent>{}) {
    res.faults.push_back(fixed(to_seconds(e.stamp), 3) + " " + std::string(sim::to_string(e.kind)) + (e.detail.empty() ? "" : " " + e.detail));
  }

  // The planned paths of the three patterns over the same sections (same grid and width).
  for (const std::string& name : room_sections) {
    const navi::Section* s = nav.splitter != nullptr && nav.coverage != nullptr ? nav.splitter->section(name) : nullptr;
    if (s == nullptr) continue;
    SectionFigures f;
    f.name = name;
    f.area_m2 = s->area_m2;
    const navi::CoverageResult h = nav.coverage->planner().hybrid(*s);
    const navi::CoverageResult b = nav.coverage->planner().balloon(*s);
    const navi::CoverageResult p = nav.coverage->planner().boustrophedon(*s);
    f.hybrid = h.stats;
    f.hybrid_coverage = h.coverage();
    f.balloon = b.stats;
    f.boustrophedon = p.stats;
    f.balloon_coverage = b.coverage();
    f.boustrophedon_coverage = p.coverage();
    res.sections.push_back(f);
  }

  if (board_hw != nullptr) {
    res.disinfection = disinfection_figures(*board_hw, reachable, lamp_floor, nav.maps->grid(), target_dose_j_m2, soc_at_start);
    if (dose_plan) {
      res.disinfection->plan = *dose_plan;
      res.disinfection->estimate_s = res.dose_estimate_s;
      res.disinfection->estimate_ah = res.dose_estimate_ah;
    }
  }

  if (!o.out.empty()) {
    std::filesystem::create_directories(o.out);
    write_png(o.out / "map.png", draw_map(nav, cleaned, reachable, traj));
    if (board_hw != nullptr) {
      const std::vector<char>& floor = lamp_floor.empty() ? reachable : lamp_floor;
      const navi::OccupancyGrid& g = nav.maps->grid();
      write_png(o.out / "dose.png", draw_dose_map(g, floor, target_dose_j_m2, [&](std::size_t i) {
                  return board_hw->uv_dose().dose_at_j_m2(g.cell_center(g.cell(i)));
                }));
    }
    write_text(o.out / "trajectory.csv", trajectory_csv(traj));
    write_text(o.out / "report.json", res.json());
    write_text(o.out / "lifecycle.txt", life.str());
  }
  return res;
}

}  // namespace tripodal::app
