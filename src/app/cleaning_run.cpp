#include "tripodal/app/cleaning_run.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "tripodal/app/png.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

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

// The robot's navigation modules, which the measures read.
struct Navigation {
  const navi::CGridMaps* maps = nullptr;
  const navi::CSectionSplitter* splitter = nullptr;
  navi::CCoverageModule* coverage = nullptr;
};

// ---------------------------------------------------------------------------------------------
// Output

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

struct TrajectorySample {
  Time t{0};
  Pose2D truth;
  Pose2D estimate;
  bool localized = false;
  bool cleaning = false;
};

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream f(file, std::ios::binary | std::ios::trunc);
  if (!f || !f.write(text.data(), static_cast<std::streamsize>(text.size()))) throw std::runtime_error("cannot write " + file.string());
}

constexpr std::array<std::array<std::uint8_t, 3>, 8> kSectionColours{{
    {{255, 236, 179}}, {{200, 230, 255}}, {{225, 210, 255}}, {{255, 215, 215}},
    {{215, 245, 215}}, {{255, 225, 190}}, {{210, 240, 240}}, {{240, 240, 200}},
}};

// The map (2 pixels per cell): walls black, unknown grey, sections tinted, cleaned cells green,
// cells the footprint could reach but did not clean red, virtual walls dashed red, the true path
// dark blue, start and end markers.
RgbImage draw_map(const Navigation& nav, const navi::CleanedCells& cleaned, const std::vector<char>& reachable,
                  const std::vector<TrajectorySample>& traj) {
  constexpr int kScale = 2;
  const navi::OccupancyGrid& g = nav.maps->grid();
  RgbImage img(g.width() * kScale, g.height() * kScale);
  auto fill_cell = [&](navi::CellIndex c, std::array<std::uint8_t, 3> rgb, double alpha) {
    for (int dy = 0; dy < kScale; ++dy) {
      for (int dx = 0; dx < kScale; ++dx) {
        img.blend(c.x * kScale + dx, (g.height() - 1 - c.y) * kScale + dy, rgb[0], rgb[1], rgb[2], alpha);
      }
    }
  };
  const auto& label = nav.splitter->sections().label;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const navi::CellIndex c = g.cell(i);
    switch (g.state(i)) {
      case navi::Occupancy::occupied: fill_cell(c, {0, 0, 0}, 1.0); continue;
      case navi::Occupancy::unknown: fill_cell(c, {170, 170, 170}, 1.0); continue;
      case navi::Occupancy::free: break;
    }
    if (label[i] >= 0) fill_cell(c, kSectionColours[static_cast<std::size_t>(label[i]) % kSectionColours.size()], 1.0);
    if (cleaned.cleaned(i)) fill_cell(c, {60, 170, 60}, 0.45);
    else if (reachable[i] != 0) fill_cell(c, {230, 40, 40}, 0.6);
  }
  for (const int row : nav.splitter->sections().virtual_wall_rows) {
    const int y = (g.height() - 1 - row) * kScale;  // the edge between rows row and row + 1
    for (int x = 0; x < img.width; ++x) {
      if ((x / 6) % 2 == 0) img.set(x, y, 220, 0, 0);
    }
  }
  auto to_px = [&](Pose2D p, double& px, double& py) {
    const Point2D gf = g.to_grid_frame({p.x_m, p.y_m});
    px = gf.x_m / g.resolution_m() * kScale;
    py = (g.height() - gf.y_m / g.resolution_m()) * kScale;
  };
  for (std::size_t k = 1; k < traj.size(); ++k) {
    double x0, y0, x1, y1;
    to_px(traj[k - 1].truth, x0, y0);
    to_px(traj[k].truth, x1, y1);
    const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(x1 - x0, y1 - y0))));
    for (int s = 0; s <= n; ++s) {
      const double t = static_cast<double>(s) / n;
      img.blend(static_cast<int>(std::floor(x0 + t * (x1 - x0))), static_cast<int>(std::floor(y0 + t * (y1 - y0))), 20, 40, 140, 0.85);
    }
  }
  auto marker = [&](Pose2D p, std::array<std::uint8_t, 3> rgb) {
    double px, py;
    to_px(p, px, py);
    for (int dy = -4; dy <= 4; ++dy) {
      for (int dx = -4; dx <= 4; ++dx) {
        if (dx * dx + dy * dy <= 16) img.set(static_cast<int>(px) + dx, static_cast<int>(py) + dy, rgb[0], rgb[1], rgb[2]);
      }
    }
  };
  if (!traj.empty()) {
    marker(traj.front().truth, {0, 120, 255});
    marker(traj.back().truth, {255, 140, 0});
  }
  return img;
}

std::string trajectory_csv(const std::vector<TrajectorySample>& traj) {
  std::string out = "t_s,x_m,y_m,theta_rad,estimate_x_m,estimate_y_m,estimate_theta_rad,localized,cleaning\n";
  char buf[256];
  for (const TrajectorySample& s : traj) {
    std::snprintf(buf, sizeof buf, "%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%d\n", to_seconds(s.t), s.truth.x_m, s.truth.y_m,
                  s.truth.theta_rad, s.estimate.x_m, s.estimate.y_m, s.estimate.theta_rad, s.localized ? 1 : 0, s.cleaning ? 1 : 0);
    out += buf;
  }
  return out;
}

// The cells of the room a cleaning footprint can reach at all: within half the cleaning width of
// a cell where the robot can stand (clearance >= its radius) connected to its start.
std::vector<char> reachable_area(const Navigation& nav, navi::PathPlanner& planner, const std::vector<std::string>& sections,
                                 Pose2D start) {
  const navi::OccupancyGrid& g = nav.maps->grid();
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
  const double r_cells = nav.coverage->cleaning_width_m() / 2.0 / g.resolution_m();
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

}  // namespace

std::string RunResult::json() const {
  using Json = nlohmann::ordered_json;  // keys in the order written
  // Figures rounded to what the report means (cm, 0.01 % coverage); a value that is not finite
  // stays NaN or inf, which the writer turns into null.
  const auto rounded = [](double v, int digits) {
    const double scale = std::pow(10.0, digits);
    return std::isfinite(v) ? std::round(v * scale) / scale : v;
  };
  const auto figures = [&](const PathFigures& f) {
    return Json{{"length_m", rounded(f.length_m, 2)}, {"turns", f.turns}, {"rotation_rad", rounded(f.rotation_rad, 2)}};
  };
  const auto stats = [&](const navi::PathStats& st, double cov) {
    return Json{{"length_m", rounded(st.length_m, 2)},
                {"turns", st.turns},
                {"total_turn_rad", rounded(st.total_turn_rad, 2)},
                {"coverage", rounded(cov, 4)}};
  };
  Json section_list = Json::array();
  for (const SectionFigures& sec : sections) {
    section_list.push_back({{"name", sec.name},
                            {"area_m2", rounded(sec.area_m2, 2)},
                            {"balloon", stats(sec.balloon, sec.balloon_coverage)},
                            {"boustrophedon", stats(sec.boustrophedon, sec.boustrophedon_coverage)}});
  }
  const Json report = {{"robot", robot},
                       {"task", task},
                       {"coverage_pattern", coverage_pattern},
                       {"seed", seed},
                       {"state", state},
                       {"succeeded", succeeded},
                       {"reason", reason},
                       {"duration_s", rounded(duration_s, 2)},
                       {"coverage", rounded(coverage, 4)},
                       {"reachable_cells", reachable_cells},
                       {"cleaned_reachable_cells", cleaned_cells},
                       {"reachable_area_m2", rounded(reachable_area_m2, 2)},
                       {"path", figures(total)},
                       {"cleaning_path", figures(cleaning)},
                       {"sections", std::move(section_list)},
                       {"processes", processes},
                       {"recoveries", recoveries},
                       {"faults", faults},
                       {"collisions", collisions},
                       {"robot_steps", robot_steps}};
  // Task text and names come from the user: bytes that are not UTF-8 are replaced, not thrown on.
  return report.dump(2, ' ', false, Json::error_handler_t::replace) + '\n';
}

RunResult run_task(const RunOptions& o) {
  const RobotProfile profile = load_robot_profile(o.robot);
  auto world = std::make_shared<sim::World>(sim::load_world(o.world));
  RunResult res;
  res.robot = profile.name;
  res.task = o.task;
  res.seed = o.seed.value_or(world->seed);
  res.coverage_pattern = o.boustrophedon ? "boustrophedon" : "balloon";
  std::vector<navi::LocalizationFault>& faults = world->faults.localization_loss;
  faults.insert(faults.end(), o.faults.begin(), o.faults.end());
  if (!profile.hardware || profile.hardware->type != "sim") {
    throw ConfigError(profile.hardware ? profile.hardware->where : profile.where,
                      "`tripodal run` runs the robot on the simulator: its profile needs hardware: {type: sim}");
  }

  // The robot, on simulated hardware in this world, with this run's seed and coverage pattern.
  RobotPlugins plugins = RobotPlugins::with_builtins();
  sim::register_sim_hardware(plugins.hardware, world);
  RobotOptions ro;
  const std::string seed_text = std::to_string(res.seed);
  ro.parameters.push_back({profile.hardware->name, "seed", seed_text});
  for (const ModuleEntry& e : profile.navigation) {
    if (e.type == navi::CLocalizer::static_manifest().name) ro.parameters.push_back({e.name, "seed", std::to_string(res.seed % (1ULL << 52))});
    if (e.type == navi::CCoverageModule::static_manifest().name && o.boustrophedon) ro.parameters.push_back({e.name, "pattern", "boustrophedon"});
  }
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock, ro);
  auto& sim = dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator();
  Navigation nav{robot->module<navi::CGridMaps>(), robot->module<navi::CSectionSplitter>(), robot->module<navi::CCoverageModule>()};
  if (nav.maps == nullptr || nav.splitter == nullptr || nav.coverage == nullptr) {
    throw ConfigError(profile.where, "`tripodal run` measures cleaning: the robot needs GridMaps, SectionSplitter and CoveragePlanner modules");
  }
  if (nav.maps->robot_radius_m() < world->robot.radius_m) {
    throw ConfigError(nav.maps->where(), "robot_radius_m " + fixed(nav.maps->robot_radius_m(), 3) +
                                             " m is smaller than the simulated body (" + fixed(world->robot.radius_m, 3) +
                                             " m): planned paths would collide");
  }
  const Pose2D start = world->start_pose;
  if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(start);
  LifecycleRecorder life(true);
  ReportObserver report;
  robot->planner().add_observer(life);
  robot->supervisor().add_observer(life);
  robot->planner().add_observer(report);

  SteadyClock wall;
  std::optional<sim::RealtimePacer> pacer;
  if (o.realtime) pacer.emplace(wall, o.realtime_speed);

  robot->run_until(clock.now());  // the localizer's first estimate, before the planner asks where to start
  const CommandAnswer answer = robot->command(o.task);
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
  if (!answer.accepted) {
    res.state = "refused";
    res.reason = answer.text;
    if (o.log != nullptr) *o.log << answer.text << '\n';
    return res;
  }
  flush_log();

  // The room's sections and the reachable area, for the measures.
  std::vector<std::string> room_sections;
  for (const PlanStage& stage : robot->planner().current_plan().stages) {
    for (const ProcessStep& step : stage.steps) {
      for (const BindingParam& p : step.params) {
        if (p.name == "section" && std::find(room_sections.begin(), room_sections.end(), p.value) == room_sections.end()) {
          room_sections.push_back(p.value);
        }
      }
    }
  }
  navi::PathPlanner reach_planner(nav.maps->grid(), navi::PathPlannerOptions{.robot_radius_m = nav.maps->robot_radius_m()});
  const std::vector<char> reachable = reachable_area(nav, reach_planner, room_sections, start);
  for (const char c : reachable) res.reachable_cells += c != 0 ? 1 : 0;

  navi::CleanedCells cleaned(nav.maps->grid());  // from the true pose, while a cleaning behavior runs
  std::vector<TrajectorySample> traj;
  std::vector<Point2D> path_all, path_cleaning;
  const double half_width = nav.coverage->cleaning_width_m() / 2.0;
  const Duration tick_period = robot->behavior_loop().period();
  const Time deadline = from_seconds(o.max_duration_s);
  bool was_cleaning = false;
  Pose2D last_truth = sim.pose();
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
  std::size_t sequencing_steps = 0;
  while (robot->planner().busy() && clock.now() < deadline) {
    robot->run_for(tick_period);
    ++sequencing_steps;
    for (; sim_events_noted < sim.events().size(); ++sim_events_noted) {
      const sim::SimEvent& e = sim.events()[sim_events_noted];
      life.note(e.stamp, "simulator: " + std::string(sim::to_string(e.kind)) + (e.detail.empty() ? "" : " " + e.detail));
    }
    const Time now = clock.now();
    const Pose2D truth = sim.pose();
    const bool cleaning = is_cleaning();
    if (cleaning) {
      if (was_cleaning) cleaned.mark_segment({last_truth.x_m, last_truth.y_m}, {truth.x_m, truth.y_m}, half_width);
      else cleaned.mark_disc({truth.x_m, truth.y_m}, half_width);
    }
    was_cleaning = cleaning;
    last_truth = truth;
    flush_log();
    if (now >= next_sample) {  // 10 Hz trajectory
      next_sample += std::chrono::milliseconds(100);
      const NavigationData& navi = robot->navigation();
      traj.push_back({now, truth, navi.map_from_base, navi.localized, cleaning});
      path_all.push_back({truth.x_m, truth.y_m});
      if (cleaning) path_cleaning.push_back({truth.x_m, truth.y_m});
    }
    if (to_seconds(now) >= next_progress_s) {
      draw_progress(false);
      next_progress_s += o.progress_is_terminal ? (o.realtime ? 1.0 : 10.0) : 60.0;
    }
    if (pacer) pacer->pace(now);
  }
  if (robot->planner().busy()) {
    robot->planner().cancel("no end within " + fixed(o.max_duration_s, 0) + " s of simulated time");
    robot->step_sequencing();
    res.state = "timed out";
  }
  flush_log();
  draw_progress(true);

  const TaskReport tr = robot->planner().report();
  res.succeeded = tr.state == TaskState::succeeded;
  if (res.state.empty()) res.state = std::string(to_string(tr.state));
  res.reason = tr.reason;
  res.duration_s = to_seconds(clock.now());
  res.cleaned_cells = covered();
  res.coverage = res.reachable_cells == 0 ? 0.0 : static_cast<double>(res.cleaned_cells) / static_cast<double>(res.reachable_cells);
  const double res_m = nav.maps->grid().resolution_m();
  res.reachable_area_m2 = static_cast<double>(res.reachable_cells) * res_m * res_m;
  res.total = path_figures(path_all);
  res.total.length_m = sim.distance_m();
  res.total.rotation_rad = sim.rotation_rad();
  res.cleaning = path_figures(path_cleaning);
  res.processes = report.processes;
  res.recoveries = report.recoveries;
  res.collisions = sim.collisions();
  res.robot_steps = robot->behavior_loop().cycles();
  for (const navi::LocalizationFault& f : faults) {
    res.faults.push_back("localization loss " + fixed(to_seconds(f.start), 1) + "-" + fixed(to_seconds(f.end), 1) + " s");
  }
  for (const sim::SimEvent& e : sim.events()) {
    res.faults.push_back(fixed(to_seconds(e.stamp), 3) + " " + std::string(sim::to_string(e.kind)) + (e.detail.empty() ? "" : " " + e.detail));
  }

  // The planned paths against the boustrophedon of the same sections (same grid and width).
  for (const std::string& name : room_sections) {
    const navi::Section* s = nav.splitter->section(name);
    if (s == nullptr) continue;
    SectionFigures f;
    f.name = name;
    f.area_m2 = s->area_m2;
    const navi::CoverageResult b = nav.coverage->planner().balloon(*s);
    const navi::CoverageResult p = nav.coverage->planner().boustrophedon(*s);
    f.balloon = b.stats;
    f.boustrophedon = p.stats;
    f.balloon_coverage = b.coverage();
    f.boustrophedon_coverage = p.coverage();
    res.sections.push_back(f);
  }
  (void)sequencing_steps;

  if (!o.out.empty()) {
    std::filesystem::create_directories(o.out);
    write_png(o.out / "map.png", draw_map(nav, cleaned, reachable, traj));
    write_text(o.out / "trajectory.csv", trajectory_csv(traj));
    write_text(o.out / "report.json", res.json());
    write_text(o.out / "lifecycle.txt", life.str());
  }
  return res;
}

}  // namespace tripodal::app
