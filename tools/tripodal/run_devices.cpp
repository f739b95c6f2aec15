#include "run_devices.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <iomanip>
#include <ostream>
#include <string_view>
#include <vector>

#include "run_measures.hpp"
#include "run_outputs.hpp"
#include "shutdown.hpp"
#include "tripodal/board/board_hardware.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/path_planner.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/robot/plugin_library.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::app {

namespace {

constexpr double kSyncWaitS = 5.0;  // wall-clock seconds: a board that has not answered SYNC by then is not there
constexpr Duration kBrakeMax = std::chrono::seconds(3);  // the devices' time the base may take to brake at the end

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + '"';
}

}  // namespace

std::string DeviceFigures::json() const {
  std::string outs = "[";
  for (std::size_t i = 0; i < outages.size(); ++i) {
    const Outage& o = outages[i];
    outs += fmt::format("{}{{\"lost_s\": {:.3f}, \"restored_s\": {:.3f}, \"resumed_s\": {:.3f}}}", i == 0 ? "" : ", ", o.lost_s,
                        o.restored_s, o.resumed_s);
  }
  outs += "]";
  return fmt::format(
      "{{\n  \"port\": {},\n  \"lidar_port\": {},\n  \"first_sync_s\": {:.3f},\n"
      "  \"link\": {{\"requests\": {}, \"responses\": {}, \"missed\": {}, \"error_responses\": {}, \"retries\": {}, "
      "\"link_losses\": {}, \"watchdog_trips\": {}, \"resyncs\": {}, \"reopens\": {}, \"port_failures\": {}, "
      "\"decoder_errors\": {}, "
      "\"bytes_sent\": {}, \"bytes_received\": {}, \"max_round_trip_ms\": {:.3f}}},\n"
      "  \"lidar\": {{\"scans\": {}, \"dropped\": {}, \"decoder_errors\": {}, \"restarts\": {}, \"faults\": {}}},\n"
      "  \"outages\": {}\n}}\n",
      json_string(port), json_string(lidar_port), first_sync_s, link.requests, link.responses, link.missed, link.error_responses,
      link.retries, link.link_losses, link.watchdog_trips, link.resyncs, link.reopens, link.port_failures, decoder_errors,
      link.bytes_sent, link.bytes_received, to_seconds(link.max_round_trip) * 1000.0, lidar_scans, lidar_dropped,
      lidar_decoder_errors, lidar_restarts, lidar_faults, outs);
}

bool runs_on_devices(const RobotProfile& profile) {
  if (!profile.hardware || profile.hardware->type != "board") return false;
  const auto it = profile.hardware->parameters.find("port");
  return it != profile.hardware->parameters.end() && !it->second.empty();
}

namespace {

// What needs a simulator in this process, or a run on simulated time, does not go with devices.
void refuse_simulated_options(const RunOptions& o, const RobotProfile& profile, const std::string& port) {
  const auto refuse = [&](const char* option, const std::string& why) {
    throw ConfigError(SourceLocation{option, 1, 1}, std::string(option) + ": " + why + " (the board is on " + port + ")");
  };
  if (!o.realtime) refuse("--realtime", "a robot on its devices runs on wall-clock time: add --realtime");
  // A speed-up is for devices that run at the same speed (tripodal-board-sim --speed S): the line's
  // byte timing, the board's watchdog and the host's link timeouts then scale alike. A real device
  // runs at 1x.
  const double speed = o.realtime_speed;
  if (!(speed >= 0.1 && speed <= 50.0))
    refuse("--realtime", fmt::format("SPEED {} for devices: from 0.1 to 50 (the device simulator's --speed)", speed));
  if (!o.board_line.empty()) refuse("--board", "the simulated board's line; a port is given");
  if (!o.faults.empty()) refuse("--faults", "injected into a simulated world; the world is the device's");
  if (!o.record.empty()) refuse("--record", "records a run on simulated time");
  if (o.monitor) refuse("--monitor", "the monitor paces a run on simulated time; not yet beside devices");
  if (profile.dds) throw ConfigError(profile.dds->where, "dds: a robot on devices runs without DDS here");
}

// The world gives the map only: the robot's moves and sensors are the devices'.
sim::World load_map_world(const std::filesystem::path& file) {
  sim::World world = sim::load_world(file);
  if (world.map_file.empty())
    throw ConfigError(SourceLocation{file.string(), 1, 1},
                      "a robot on devices loads the world's map: the world names no map file");
  return world;
}

// The built-in types with the real board as the hardware "board", not the simulated one.
void add_device_plugins(RobotPlugins& plugins, const RobotProfile& profile, const RunOptions& o) {
  register_all(plugins);
  plugins.hardware = HardwareRegistry{"hardware type"};
  board::register_board_hardware(plugins.hardware);
  (void)load_profile_plugins(profile, plugins, o.plugins);
}

// The map and regions from the world, the coverage pattern and dose target from the options.
RobotOptions device_robot_options(const RobotProfile& profile, const sim::World& world, const RunOptions& o) {
  RobotOptions ro;
  for (const ModuleEntry& e : profile.navigation) {
    if (e.type == navi::CGridMaps::static_manifest().name && e.parameters.count("map") == 0) {
      ro.parameters.push_back({e.name, "map", std::filesystem::absolute(world.map_file).string()});
      if (!world.regions_file.empty() && e.parameters.count("regions") == 0)
        ro.parameters.push_back({e.name, "regions", std::filesystem::absolute(world.regions_file).string()});
    }
    if (e.type != navi::CCoveragePlanner::static_manifest().name) continue;
    if (!o.pattern.empty()) ro.parameters.push_back({e.name, "pattern", o.pattern});
    if (!o.dose_plan)
      ro.parameters.push_back({e.name, "dose_target_j_m2", "0"});
    else if (o.uv_target_dose_j_m2)
      ro.parameters.push_back({e.name, "dose_target_j_m2", fmt::format("{}", *o.uv_target_dose_j_m2)});
  }
  return ro;
}

board::BoardHardware& board_of(Robot& robot, const SourceLocation& where) {
  auto* host = dynamic_cast<board::BoardHost*>(robot.hardware());
  if (host == nullptr) throw ConfigError(where, "hardware 'board' with a port: expected the control board's hardware");
  return host->board();
}

// What the run measures on the sequencing thread, after each of its periods: the lifecycle's
// lines, the board's link as the sequencing layer sees it, the floor cleaned and the path. The
// main thread reads it once the robot's threads have stopped (but `synced` and `busy`, atomics it
// polls meanwhile).
class DeviceMeasures {
 public:
  DeviceMeasures(Robot& robot, const Navigation& nav, const LifecycleRecorder& life, DeviceFigures& dev, RunResult& res,
                 std::ostream* log, const Pose2D& start)
      : reachable(nav.maps->grid().size(), 0),
        cleaned(nav.maps->grid()),  // from the localized pose: no ground truth here
        robot_(robot),
        nav_(nav),
        life_(life),
        dev_(dev),
        res_(res),
        log_(log),
        start_(start),
        reach_planner_(nav.maps->grid(), navi::PathPlannerOptions{.robot_radius_m = nav.maps->robot_radius_m()}),
        half_width_(nav.coverage != nullptr ? nav.coverage->footprint_width_m() / 2.0 : 0.0),
        last_(start) {}

  void after_sequencing(Time now);
  // The lifecycle's lines not printed yet, but the firings.
  void print_lifecycle() {
    for (; printed_ < life_.entries().size(); ++printed_) {
      const LifecycleEntry& e = life_.entries()[printed_];
      if (e.text.find(" fire ") == std::string::npos) log(e.time, e.text);
    }
  }
  void log(Time t, const std::string& text) const {
    if (log_ == nullptr) return;
    *log_ << std::setw(9) << fixed(to_seconds(t), 1) << " s  " << text << '\n';
    log_->flush();
  }
  [[nodiscard]] const std::string& port() const noexcept { return dev_.port; }

  std::atomic<bool> synced{false}, busy{false};
  std::vector<char> reachable;
  navi::CleanedCells cleaned;
  std::vector<TrajectorySample> traj;
  std::vector<navi::Point2D> path_all, path_cleaning;

 private:
  void watch_link(Time now);
  void measure_room() {
    room_sections_ = plan_sections(robot_.planner());
    reachable = reachable_area(nav_, reach_planner_, room_sections_, start_, half_width_);
    res_.reachable_cells = static_cast<std::size_t>(std::count(reachable.begin(), reachable.end(), char{1}));
  }
  [[nodiscard]] bool moving() const {
    return robot_.behavior_active("BhAutoMove") || robot_.behavior_active("BhCleaningTwoWheel");
  }

  Robot& robot_;
  const Navigation& nav_;
  const LifecycleRecorder& life_;
  DeviceFigures& dev_;
  RunResult& res_;
  std::ostream* log_;
  Pose2D start_;
  std::vector<std::string> room_sections_;
  navi::PathPlanner reach_planner_;
  double half_width_;
  bool measured_busy_ = false, was_cleaning_ = false, link_up_ = false;
  std::uint64_t losses_seen_ = 0;
  std::uint64_t resyncs_at_loss_ = 0;  // the link's resyncs when losses_seen_ last rose
  Pose2D last_;
  Time next_sample_{};
  std::size_t printed_ = 0;
};

// The board's link as the sequencing layer sees it (the snapshot of the resource board_link): its
// first SYNC, each loss and return, and when the task moves again after one.
void DeviceMeasures::watch_link(Time now) {
  if (const auto* r = robot_.sequencing_resources().find<board::BoardLinkReading>("board_link");
      r != nullptr && r->has_reading()) {
    const board::BoardLinkReading& l = r->latest();
    if (l.stats.link_losses > losses_seen_) {
      // Back and lost again between two samples of this loop: the SYNC answered since the previous
      // loss says that outage ended, before this loss (the link's own stamp of it).
      if (!dev_.outages.empty() && dev_.outages.back().restored_s < 0.0 && l.stats.resyncs > resyncs_at_loss_) {
        dev_.outages.back().restored_s = to_seconds(l.lost_at);
        log(now, "board: link restored and lost again since the last look");
      }
      losses_seen_ = l.stats.link_losses;
      resyncs_at_loss_ = l.stats.resyncs;
      dev_.outages.push_back({to_seconds(now), -1.0, -1.0});
      log(now, fmt::format("board: link lost ({} missed, {} port failures so far): the motors stop", l.stats.missed,
                           l.stats.port_failures));
      link_up_ = false;
    } else if (l.synchronised && !link_up_) {
      link_up_ = true;
      if (!synced.load(std::memory_order_relaxed)) {
        dev_.first_sync_s = to_seconds(now);
        log(now, "board: SYNC answered on " + dev_.port);
      } else if (!dev_.outages.empty()) {
        dev_.outages.back().restored_s = to_seconds(now);
        log(now, fmt::format("board: link restored (SYNC answered again, {} reopens of the port)", l.stats.reopens));
      }
      synced.store(true, std::memory_order_release);
    }
  }
  if (!dev_.outages.empty() && dev_.outages.back().restored_s >= 0.0 && dev_.outages.back().resumed_s < 0.0 && moving()) {
    dev_.outages.back().resumed_s = to_seconds(now);
    log(now, "board: the task moves again");
  }
}

void DeviceMeasures::after_sequencing(Time now) {
  print_lifecycle();
  watch_link(now);
  const bool is_busy = robot_.planner().busy();
  if (is_busy && !measured_busy_) measure_room();
  measured_busy_ = is_busy;
  // The cleaned cells and the path from the localizer's estimate: the true pose is the device
  // simulator's (or the world's), not this process's.
  const NavigationData& navi = robot_.navigation();
  const Pose2D pose = navi.map_from_base;
  const bool cleaning = robot_.behavior_active("BhCleaningTwoWheel") || robot_.behavior_active("BhCleaning");
  if (cleaning && navi.localized) {
    if (was_cleaning_)
      cleaned.mark_segment({last_.x_m, last_.y_m}, {pose.x_m, pose.y_m}, half_width_);
    else
      cleaned.mark_disc({pose.x_m, pose.y_m}, half_width_);
  }
  was_cleaning_ = cleaning && navi.localized;
  last_ = pose;
  if (now >= next_sample_) {  // 10 Hz trajectory
    next_sample_ = now + std::chrono::milliseconds(100);
    traj.push_back({now, pose, pose, navi.localized, cleaning});
    path_all.push_back({pose.x_m, pose.y_m});
    if (cleaning) path_cleaning.push_back({pose.x_m, pose.y_m});
  }
  busy.store(is_busy, std::memory_order_release);
}

// The task is given before the threads start (the planner's observers then run on one thread):
// it waits, standing still, for the board's first SYNC.
void give_task(const RunOptions& o, Robot& robot, RunResult& res) {
  if (o.task.empty()) return;
  const CommandAnswer answer = robot.command(o.task);
  if (answer.accepted) return;
  res.state = "refused";
  res.reason = answer.text;
  if (o.log != nullptr) *o.log << answer.text << '\n';
}

// Waits (on the wall clock, the robot on its threads) for the board's first SYNC, then for the
// task's end, the run's deadline or a signal. A board that does not answer ends the run "failed".
void await_end(const RunOptions& o, Robot& robot, board::BoardHardware& hw, const ScaledClock& clock, const SteadyClock& wall,
               Time task_start, const DeviceMeasures& m, RunResult& res) {
  const auto stopped = [&] { return o.stop != nullptr && *o.stop != 0; };
  const auto wait = [&] { wall.sleep_until(wall.now() + std::chrono::milliseconds(10)); };
  const Time sync_by = clock.now() + from_seconds(kSyncWaitS * res.realtime_speed);
  while (!m.synced.load(std::memory_order_acquire) && clock.now() < sync_by && !stopped()) wait();
  if (!m.synced.load(std::memory_order_acquire) && !stopped()) {
    robot.stop();
    const board::LinkStats& s = hw.link().stats();
    res.state = "failed";
    res.reason = fmt::format(
        "the board on {} did not answer SYNC within {:.0f} s ({} requests sent, {} bytes received, {} decoder errors)", m.port(),
        kSyncWaitS, s.requests, s.bytes_received, hw.link().decoder_stats().errors());
    return;
  }
  const Time deadline = task_start + from_seconds(o.max_duration_s);
  while (clock.now() < deadline && !stopped() && (o.task.empty() || m.busy.load(std::memory_order_acquire))) wait();
}

// The threads have stopped: a task still running is cancelled, with the reason the run ends for.
void cancel_unfinished(const RunOptions& o, Robot& robot, RunResult& res) {
  const int sig = stop_signal(o.stop);
  res.stopped_by = stop_reason(sig);
  if (!robot.planner().busy()) return;
  robot.planner().cancel(sig != 0              ? res.stopped_by
                         : !res.reason.empty() ? res.reason
                                               : "no end within " + fixed(o.max_duration_s, 0) + " s");
  robot.step_sequencing();
  if (res.state.empty() || sig != 0) res.state = sig != 0 ? "interrupted" : "timed out";
}

// The robot's threads have stopped: this thread runs the link now. The lamp and the fog at their
// channels' safe values (off; the board applies the channels at its next cycle, as in the run),
// the wheels braked to zero through the base's controller (its limits, as every cycle of the
// run), until the board has answered a DRIVE sent after that. Whether it did.
bool rest_on_devices(Robot& robot, board::BoardHardware& hw, const Clock& clock) {
  CommandChannels& channels = hw.command_channels();
  for (const std::string_view name : {"uv_lamp", "atomizer", "atomizer_fan"}) {
    if (const auto i = channels.find(name)) channels.set(*i, channels.spec(*i).safe);
  }
  if (CController* c = robot.behavior_loop().controller())
    (void)brake_through_controller(*c, clock, kBrakeMax, [&hw](Time now) { hw.cycle(now); });
  const Time zero_sent = clock.now();
  bool zero_answered = false;
  for (int i = 0; i < 50 && !zero_answered; ++i) {
    hw.cycle(clock.now());
    zero_answered = hw.link().synchronised() && hw.link().has_drive() &&
                    hw.link().drive_stamp() > zero_sent + std::chrono::milliseconds(10) &&
                    hw.link().pending_actuator_commands() == 0;
    clock.sleep_until(clock.now() + std::chrono::milliseconds(10));
  }
  return zero_answered;
}

// The task's outcome and the floor's figures, as run_task reports them.
void set_task_figures(RunResult& res, Robot& robot, const Navigation& nav, const DeviceMeasures& m,
                      const ReportObserver& report) {
  const TaskReport tr = robot.planner().report();
  res.succeeded = tr.state == TaskState::succeeded;
  if (res.state.empty()) res.state = std::string(to_string(tr.state));
  if (res.reason.empty()) res.reason = tr.reason;
  set_floor_figures(res, nav, m.reachable, m.cleaned, m.path_all, m.path_cleaning);
  res.processes = report.processes;
  res.recoveries = report.recoveries;
  res.robot_steps = robot.behavior_loop().cycles();
  res.loops = robot.timing();
}

void read_device_figures(DeviceFigures& dev, board::BoardHardware& hw) {
  dev.link = hw.link().stats();
  dev.decoder_errors = hw.link().decoder_stats().errors();
  if (const board::RplidarA1* lidar = hw.lidar()) {
    const board::RplidarStats& l = lidar->stats();
    dev.lidar_scans = l.scans;
    dev.lidar_dropped = l.dropped;
    dev.lidar_decoder_errors = l.decoder_errors;
    dev.lidar_restarts = l.restarts;
    dev.lidar_faults = l.faults;
  }
}

// The devices' summary lines; `wall_s`: the wall-clock seconds the run took (said at a speed-up).
void log_device_figures(std::ostream& log, const DeviceFigures& dev, double speed, double duration_s, double wall_s) {
  log << fmt::format("devices: board on {}: {} requests, {} responses, {} missed, {} decoder errors, {} link losses, {} reopens",
                     dev.port, dev.link.requests, dev.link.responses, dev.link.missed, dev.decoder_errors, dev.link.link_losses,
                     dev.link.reopens);
  if (!dev.lidar_port.empty())
    log << fmt::format("; lidar on {}: {} scans, {} dropped, {} decoder errors, {} restarts", dev.lidar_port, dev.lidar_scans,
                       dev.lidar_dropped, dev.lidar_decoder_errors, dev.lidar_restarts);
  log << '\n';
  if (speed != 1.0)
    log << fmt::format("devices: at {}x: {:.1f} s of the devices' time in {:.1f} s of wall clock\n", speed, duration_s, wall_s);
  for (const DeviceFigures::Outage& u : dev.outages) {
    log << fmt::format("devices: link lost at {:.3f} s, restored at {:.3f} s, task moving again at {:.3f} s\n", u.lost_s,
                       u.restored_s, u.resumed_s);
  }
  log.flush();
}

void write_device_outputs(const std::filesystem::path& out, const Navigation& nav, const DeviceMeasures& m, const RunResult& res,
                          const DeviceFigures& dev, const LifecycleRecorder& life) {
  std::filesystem::create_directories(out);
  write_png(out / "map.png", draw_map(nav, m.cleaned, m.reachable, m.traj));
  write_text(out / "trajectory.csv", trajectory_csv(m.traj));
  write_text(out / "report.json", res.json());
  write_text(out / "devices.json", dev.json());
  write_text(out / "lifecycle.txt", life.str());
}

}  // namespace

RunResult run_on_devices(const RunOptions& o, const RobotProfile& profile) {
  const std::string port = profile.hardware->parameters.at("port");
  const auto lidar_it = profile.hardware->parameters.find("lidar_port");
  const std::string lidar_port = lidar_it != profile.hardware->parameters.end() ? lidar_it->second : std::string();
  refuse_simulated_options(o, profile, port);
  const double speed = o.realtime_speed;
  const sim::World world = load_map_world(o.world);
  RobotPlugins plugins;
  add_device_plugins(plugins, profile, o);
  const RobotOptions ro = device_robot_options(profile, world, o);

  RunResult res;
  res.robot = profile.name;
  res.task = o.task;
  res.realtime_speed = speed;
  // The robot's time: the wall clock's at 1x; at a speed-up the devices' (tripodal-board-sim --speed),
  // so that every period and timeout of the host (the link's response timeout, the lidar's) scales alike.
  ScaledClock clock(speed);
  const auto robot = Robot::assemble(profile, plugins, clock, ro);
  board::BoardHardware& hw = board_of(*robot, profile.hardware->where);
  Navigation nav{robot->module<navi::CGridMaps>(), robot->module<navi::CSectionSplitter>(),
                 robot->module<navi::CCoveragePlanner>()};
  if (nav.maps == nullptr)
    throw ConfigError(profile.where, "`tripodal run` measures the run on the map: the robot needs a GridMaps module");
  if (nav.coverage != nullptr) res.coverage_pattern = nav.coverage->pattern();
  const Pose2D start = world.start_pose;  // where the device simulator (or the operator) puts the robot
  if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(start);

  LifecycleRecorder life(true);
  robot->planner().add_observer(life);
  ReportObserver report;  // the processes and recoveries, as run_task reports them
  robot->planner().add_observer(report);
  robot->supervisor().add_observer(life);
  DeviceFigures dev;
  dev.port = port;
  dev.lidar_port = lidar_port;
  DeviceMeasures m(*robot, nav, life, dev, res, o.log, start);
  RealtimeOptions rto;
  rto.after_sequencing = [&m](Time now) { m.after_sequencing(now); };

  give_task(o, *robot, res);
  m.busy.store(robot->planner().busy(), std::memory_order_release);
  const SteadyClock wall;
  const Time task_start = clock.now();
  const Time wall_start = wall.now();
  robot->start(std::move(rto));
  if (o.log != nullptr) {
    for (const std::string& w : robot->realtime_warnings()) *o.log << w << '\n';
  }
  await_end(o, *robot, hw, clock, wall, task_start, m, res);
  robot->stop();
  const Time ended = clock.now();
  cancel_unfinished(o, *robot, res);
  m.print_lifecycle();

  res.base_command_at_end_rad_s = {0.0, 0.0};
  res.base_at_rest = rest_on_devices(*robot, hw, clock);
  if (o.log != nullptr && !res.base_at_rest)
    *o.log << "board: no answer to the last DRIVE (speeds 0): its watchdog stops the motors\n";

  set_task_figures(res, *robot, nav, m, report);
  res.duration_s = to_seconds(ended - task_start);
  res.wall_clock = speed == 1.0;  // at a speed-up the devices' time, S times the wall clock's
  read_device_figures(dev, hw);
  if (o.log != nullptr) log_device_figures(*o.log, dev, speed, res.duration_s, to_seconds(wall.now() - wall_start));
  if (!o.out.empty()) write_device_outputs(o.out, nav, m, res, dev, life);
  return res;
}

}  // namespace tripodal::app
