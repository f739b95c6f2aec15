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

#include "tripodal/app/png.hpp"
#include "tripodal/behaviors/navigation_behaviors.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/reactive/reactive_config.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::app {

namespace {

using navi::Point2D;

// ---------------------------------------------------------------------------------------------
// Path figures

void douglas_peucker(const std::vector<Point2D>& p, std::size_t a, std::size_t b, double tol, std::vector<char>& keep) {
  // iterative, so a long trajectory cannot overflow the stack
  std::vector<std::pair<std::size_t, std::size_t>> todo{{a, b}};
  while (!todo.empty()) {
    const auto [i, j] = todo.back();
    todo.pop_back();
    if (j <= i + 1) continue;
    const double dx = p[j].x_m - p[i].x_m, dy = p[j].y_m - p[i].y_m;
    const double len = std::hypot(dx, dy);
    double worst = -1.0;
    std::size_t at = i;
    for (std::size_t k = i + 1; k < j; ++k) {
      const double ex = p[k].x_m - p[i].x_m, ey = p[k].y_m - p[i].y_m;
      const double d = len > 0.0 ? std::abs(ex * dy - ey * dx) / len : std::hypot(ex, ey);
      if (d > worst) {
        worst = d;
        at = k;
      }
    }
    if (worst > tol) {
      keep[at] = 1;
      todo.emplace_back(i, at);
      todo.emplace_back(at, j);
    }
  }
}

}  // namespace

PathFigures path_figures(const std::vector<Point2D>& path, double tolerance_m) {
  PathFigures f;
  if (path.size() < 2) return f;
  std::vector<char> keep(path.size(), 0);
  keep.front() = keep.back() = 1;
  douglas_peucker(path, 0, path.size() - 1, tolerance_m, keep);
  std::vector<Point2D> simple;
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (keep[i] != 0) simple.push_back(path[i]);
  }
  const navi::PathStats s = navi::path_stats(simple, std::numbers::pi / 6.0);
  f.length_m = navi::polyline_length_m(path);
  f.turns = s.turns;
  return f;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Modules of the profile, as this program implements them

ModuleManifest manifest_of(std::string name, Layer layer, ModuleKind kind, std::vector<std::string> in,
                           std::vector<std::string> out, std::string description) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = layer;
  m.kind = kind;
  m.inputs = std::move(in);
  m.outputs = std::move(out);
  m.description = std::move(description);
  return m;
}

// Resources and the map are fed by the simulator / loaded once: nothing to do per period.
class PassiveModule final : public RobotModule {};

// The navi localizer as a robot module: updates the estimate each period, posts its events to
// the nets, keeps the supervisor's watchdog fed, and publishes the pose behaviors read.
class LocalizerModule final : public RobotModule {
 public:
  LocalizerModule(navi::CLocalizer& localizer, NavigationData& navi) : localizer_(localizer), navi_(navi) {}

 protected:
  void on_update(Time now) override {
    events_.clear();
    localizer_.update(now, events_);
    for (const navi::NaviEvent& e : events_) port().post_event(e.name);
    port().heartbeat();
    localizer_.publish(navi_);
  }

 private:
  navi::CLocalizer& localizer_;
  NavigationData& navi_;
  std::vector<navi::NaviEvent> events_;
};

// The section splitter as the planner's knowledge: sections(room), nearest first from the
// localizer's position (paper, section 3.2: the sections are reported with the current position).
class SectionSplitterModule final : public RobotModule {
 public:
  SectionSplitterModule(const NaviWorkspace& ws, const NavigationData& navi) : ws_(ws), navi_(navi) {}

 protected:
  std::optional<TaskKnowledge::ListResult> on_answer(std::string_view function, std::string_view room) const override {
    if (function != "sections") return std::nullopt;
    auto r = ws_.sections_of_room(room);
    const Point2D at{navi_.map_from_base.x_m, navi_.map_from_base.y_m};
    if (r.ok && navi_.localized) r.names = navi::order_nearest_first(ws_.grid(), ws_.sections(), r.names, at);
    return TaskKnowledge::ListResult{r.ok, std::move(r.names), std::move(r.error)};
  }

 private:
  const NaviWorkspace& ws_;
  const NavigationData& navi_;
};

const ModuleEntry* find_entry(const RobotProfile& p, std::string_view type) {
  for (const ModuleEntry* e : p.all_modules()) {
    if (e->type == type) return e;
  }
  return nullptr;
}

double number_parameter(const ModuleEntry* e, std::string_view name, double fallback) {
  if (e == nullptr) return fallback;
  const auto it = e->parameters.find(name);
  if (it == e->parameters.end()) return fallback;
  try {
    std::size_t used = 0;
    const double v = std::stod(it->second, &used);
    if (used == it->second.size() && std::isfinite(v) && v > 0.0) return v;
  } catch (const std::exception&) {
  }
  throw ConfigError(e->where, "parameter '" + std::string(name) + "' of '" + e->name + "' must be a positive number, not \"" +
                                  it->second + "\"");
}

// The base controller: the profile's controller entry names its full configuration (limits,
// wheel geometry) in a reactive configuration file, parameter `config`.
ControllerConfig controller_config(const RobotProfile& p) {
  if (p.controllers.empty()) throw ConfigError(p.where, "the robot has no controller; `tripodal run` needs one to drive its base");
  const ModuleEntry& e = p.controllers.front();
  const auto it = e.parameters.find("config");
  if (it == e.parameters.end()) {
    throw ConfigError(e.where, "controller '" + e.name +
                                   "' needs parameters: {config: FILE}, the reactive configuration with its limits and wheels");
  }
  const std::filesystem::path file = p.file.parent_path() / it->second;
  const ReactiveConfig rc = load_reactive_config(file.string());
  const ControllerConfig* c = rc.find_controller(e.name);
  if (c == nullptr) throw ConfigError(e.where, file.string() + " configures no controller named '" + e.name + "'");
  if (c->type != e.type) {
    throw ConfigError(e.where, "controller '" + e.name + "' is of type '" + e.type + "' here but '" + c->type + "' in " + file.string());
  }
  return *c;
}

// ---------------------------------------------------------------------------------------------
// Output

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

std::string json_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
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
RgbImage draw_map(const NaviWorkspace& ws, const navi::CleanedCells& cleaned, const std::vector<char>& reachable,
                  const std::vector<TrajectorySample>& traj) {
  constexpr int kScale = 2;
  const navi::OccupancyGrid& g = ws.grid();
  RgbImage img(g.width() * kScale, g.height() * kScale);
  auto fill_cell = [&](navi::CellIndex c, std::array<std::uint8_t, 3> rgb, double alpha) {
    for (int dy = 0; dy < kScale; ++dy) {
      for (int dx = 0; dx < kScale; ++dx) {
        img.blend(c.x * kScale + dx, (g.height() - 1 - c.y) * kScale + dy, rgb[0], rgb[1], rgb[2], alpha);
      }
    }
  };
  const auto& label = ws.sections().label;
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
  for (const int row : ws.sections().virtual_wall_rows) {
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
std::vector<char> reachable_area(NaviWorkspace& ws, const std::vector<std::string>& sections, Pose2D start) {
  const navi::OccupancyGrid& g = ws.grid();
  std::vector<char> in_room(g.size(), 0);
  for (const std::string& name : sections) {
    if (const navi::Section* s = ws.section(name)) {
      for (const std::size_t i : s->cells) in_room[i] = 1;
    }
  }
  std::vector<char> stand(g.size(), 0);
  std::deque<navi::CellIndex> queue;
  const navi::CellIndex s0 = g.cell_at({start.x_m, start.y_m});
  if (ws.planner().traversable(s0)) {
    stand[g.index(s0)] = 1;
    queue.push_back(s0);
  }
  while (!queue.empty()) {
    const navi::CellIndex c = queue.front();
    queue.pop_front();
    for (const auto& d : std::array<navi::CellIndex, 4>{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}}) {
      const navi::CellIndex n{c.x + d.x, c.y + d.y};
      if (!ws.planner().traversable(n) || stand[g.index(n)] != 0) continue;
      stand[g.index(n)] = 1;
      queue.push_back(n);
    }
  }
  const double r_cells = ws.options().cleaning_width_m / 2.0 / g.resolution_m();
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
  std::ostringstream o;
  auto list = [&](const std::vector<std::string>& v) {
    o << "[";
    for (std::size_t i = 0; i < v.size(); ++i) o << (i ? ", " : "") << json_string(v[i]);
    o << "]";
  };
  auto figures = [&](const PathFigures& f) {
    o << "{\"length_m\": " << fixed(f.length_m, 2) << ", \"turns\": " << f.turns << ", \"rotation_rad\": " << fixed(f.rotation_rad, 2)
      << "}";
  };
  auto stats = [&](const navi::PathStats& s, double cov) {
    o << "{\"length_m\": " << fixed(s.length_m, 2) << ", \"turns\": " << s.turns << ", \"total_turn_rad\": " << fixed(s.total_turn_rad, 2)
      << ", \"coverage\": " << fixed(cov, 4) << "}";
  };
  o << "{\n  \"robot\": " << json_string(robot) << ",\n  \"task\": " << json_string(task) << ",\n  \"coverage_pattern\": " << json_string(coverage_pattern) << ",\n  \"seed\": " << seed
    << ",\n  \"state\": " << json_string(state) << ",\n  \"succeeded\": " << (succeeded ? "true" : "false")
    << ",\n  \"reason\": " << json_string(reason) << ",\n  \"duration_s\": " << fixed(duration_s, 2)
    << ",\n  \"coverage\": " << fixed(coverage, 4) << ",\n  \"reachable_cells\": " << reachable_cells
    << ",\n  \"cleaned_reachable_cells\": " << cleaned_cells << ",\n  \"reachable_area_m2\": " << fixed(reachable_area_m2, 2)
    << ",\n  \"path\": ";
  figures(total);
  o << ",\n  \"cleaning_path\": ";
  figures(cleaning);
  o << ",\n  \"sections\": [";
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const SectionFigures& s = sections[i];
    o << (i ? ",\n" : "\n") << "    {\"name\": " << json_string(s.name) << ", \"area_m2\": " << fixed(s.area_m2, 2) << ", \"balloon\": ";
    stats(s.balloon, s.balloon_coverage);
    o << ", \"boustrophedon\": ";
    stats(s.boustrophedon, s.boustrophedon_coverage);
    o << "}";
  }
  o << "\n  ],\n  \"processes\": ";
  list(processes);
  o << ",\n  \"recoveries\": ";
  list(recoveries);
  o << ",\n  \"faults\": ";
  list(faults);
  o << ",\n  \"collisions\": " << collisions << ",\n  \"robot_steps\": " << robot_steps << "\n}\n";
  return o.str();
}

RunResult run_task(const RunOptions& o) {
  const RobotProfile profile = load_robot_profile(o.robot);
  sim::World world = sim::load_world(o.world);
  RunResult res;
  res.robot = profile.name;
  res.task = o.task;
  res.seed = o.seed.value_or(world.seed);

  const ControllerConfig base = controller_config(profile);
  const ModuleEntry* maps = find_entry(profile, "GridMaps");
  NaviWorkspaceOptions wo;
  wo.robot_radius_m = number_parameter(maps, "robot_radius_m", world.robot.radius_m);
  wo.cleaning_width_m = number_parameter(maps, "cleaning_width_m", 2.0 * wo.robot_radius_m);
  if (wo.robot_radius_m < world.robot.radius_m) {
    throw ConfigError(maps->where, "robot_radius_m " + fixed(wo.robot_radius_m, 3) + " m is smaller than the simulated body (" +
                                       fixed(world.robot.radius_m, 3) + " m): planned paths would collide");
  }
  if (o.boustrophedon) wo.pattern = NaviWorkspaceOptions::Pattern::boustrophedon;
  res.coverage_pattern = o.boustrophedon ? "boustrophedon" : "balloon";
  NaviWorkspace ws(world.grid, world.regions, wo);

  std::vector<navi::LocalizationFault> faults = world.faults.localization_loss;
  faults.insert(faults.end(), o.faults.begin(), o.faults.end());
  world.faults.localization_loss = faults;
  const Pose2D start = world.start_pose;
  sim::Simulator sim(std::move(world), base, res.seed);
  auto controller = default_controller_registry().create(base, sim);
  controller->reset_odometry(start);
  ResourceTable table;
  sim.add_resources(table, true);
  NavigationData navi;

  // The localizer: its parameters from the profile, the run's seed, the fault schedule.
  navi::CLocalizer localizer(&sim);
  {
    ParameterValues lp;
    if (const ModuleEntry* e = find_entry(profile, "Localizer")) {
      for (const auto& [k, v] : e->parameters) lp.emplace(k, Value{v});
    }
    lp.insert_or_assign("seed", Value{static_cast<double>(res.seed % (1ULL << 52))});
    const ModuleEntry* e = find_entry(profile, "Localizer");
    localizer.configure(lp, e != nullptr ? e->where : SourceLocation{});
    for (const navi::LocalizationFault& f : faults) localizer.add_fault(f);
  }
  ws.set_relocalizer([&localizer](Time t) { return localizer.relocalize(t); });

  BehaviorRegistry behaviors;
  register_navigation_behaviors(behaviors, ws);
  ModuleRegistry modules;
  auto passive = [](const ModuleConfig&) { return std::make_unique<PassiveModule>(); };
  modules.add(manifest_of("LaserScanner", Layer::reactive, ModuleKind::resource, {}, {"laser_scan"}, "simulated laser scanner"), passive);
  modules.add(manifest_of("Gyro", Layer::reactive, ModuleKind::resource, {}, {"yaw_rate"}, "simulated gyro"), passive);
  modules.add(manifest_of("GridMaps", Layer::sequencing, ModuleKind::navigation, {}, {"grid_map"}, "the world's map"), passive);
  modules.add(manifest_of("Localizer", Layer::sequencing, ModuleKind::navigation, {"laser_scan", "odometry", "grid_map"},
                          {"map_from_base"}, "navi::CLocalizer on the simulator's ground truth"),
              [&](const ModuleConfig&) { return std::make_unique<LocalizerModule>(localizer, navi); });
  modules.add(manifest_of("SectionSplitter", Layer::sequencing, ModuleKind::navigation, {"grid_map", "map_from_base"}, {"sections"},
                          "navi::CSectionSplitter: sections(room)"),
              [&](const ModuleConfig&) { return std::make_unique<SectionSplitterModule>(ws, navi); });

  SimClock clock;
  RobotOptions ro;
  ro.period = o.robot_period;
  ro.resources = &table;
  ro.navigation = &navi;
  ro.base = controller->capabilities();
  const auto robot = Robot::assemble(profile, RobotCatalog{&modules, &behaviors, &default_controller_registry()}, clock, ro);
  LifecycleRecorder life(true);
  ReportObserver report;
  robot->planner().add_observer(life);
  robot->supervisor().add_observer(life);
  robot->planner().add_observer(report);

  SteadyClock wall;
  std::optional<sim::RealtimePacer> pacer;
  if (o.realtime) pacer.emplace(wall, o.realtime_speed);

  robot->step();  // the localizer's first estimate, before the planner asks where to start
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
  const std::vector<char> reachable = reachable_area(ws, room_sections, start);
  for (const char c : reachable) res.reachable_cells += c != 0 ? 1 : 0;

  navi::CleanedCells cleaned(ws.grid());  // from the true pose, while a cleaning behavior runs
  std::vector<TrajectorySample> traj;
  std::vector<Point2D> path_all, path_cleaning;
  const double half_width = wo.cleaning_width_m / 2.0;
  const Duration physics = base.period;
  const auto per_robot_step = std::max<std::int64_t>(1, o.robot_period / physics);
  const Time deadline = from_seconds(o.max_duration_s);
  Twist2D command;
  bool was_cleaning = false;
  Pose2D last_truth = sim.pose();
  double next_progress_s = 0.0;
  auto is_cleaning = [&] {
    for (const char* name : {"BhCleaning", "BhCleaningTwoWheel"}) {
      const CBehavior* b = robot->behaviors().find(name);
      if (b != nullptr && b->running()) return true;
    }
    return false;
  };
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

  std::int64_t tick = 0;
  std::size_t sim_events_noted = 0;
  while (robot->planner().busy() && clock.now() < deadline) {
    sim.step(physics);
    clock.set(sim.now());
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
    if (++tick % per_robot_step == 0) {
      robot->step();
      ++res.robot_steps;
      command = robot->coordinator().output().command;
      flush_log();
      if (tick % (per_robot_step * 2) == 0) {  // 10 Hz trajectory at the default periods
        traj.push_back({now, truth, navi.map_from_base, navi.localized, cleaning});
        path_all.push_back({truth.x_m, truth.y_m});
        if (cleaning) path_cleaning.push_back({truth.x_m, truth.y_m});
      }
      if (to_seconds(now) >= next_progress_s) {
        draw_progress(false);
        next_progress_s += o.progress_is_terminal ? (o.realtime ? 1.0 : 10.0) : 60.0;
      }
    }
    controller->set_command(command, now);
    (void)controller->update(now);
    if (pacer) pacer->pace(now);
  }
  if (robot->planner().busy()) {
    robot->planner().cancel("no end within " + fixed(o.max_duration_s, 0) + " s of simulated time");
    robot->step();
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
  res.reachable_area_m2 = static_cast<double>(res.reachable_cells) * ws.grid().resolution_m() * ws.grid().resolution_m();
  res.total = path_figures(path_all);
  res.total.length_m = sim.distance_m();
  res.total.rotation_rad = sim.rotation_rad();
  res.cleaning = path_figures(path_cleaning);
  res.processes = report.processes;
  res.recoveries = report.recoveries;
  res.collisions = sim.collisions();
  for (const navi::LocalizationFault& f : faults) {
    res.faults.push_back("localization loss " + fixed(to_seconds(f.start), 1) + "-" + fixed(to_seconds(f.end), 1) + " s");
  }
  for (const sim::SimEvent& e : sim.events()) {
    res.faults.push_back(fixed(to_seconds(e.stamp), 3) + " " + std::string(sim::to_string(e.kind)) + (e.detail.empty() ? "" : " " + e.detail));
  }

  // The planned paths against the boustrophedon of the same sections (same grid and width).
  for (const std::string& name : room_sections) {
    const navi::Section* s = ws.section(name);
    if (s == nullptr) continue;
    SectionFigures f;
    f.name = name;
    f.area_m2 = s->area_m2;
    const navi::CoverageResult b = ws.coverage_planner().balloon(*s);
    const navi::CoverageResult p = ws.coverage_planner().boustrophedon(*s);
    f.balloon = b.stats;
    f.boustrophedon = p.stats;
    f.balloon_coverage = b.coverage();
    f.boustrophedon_coverage = p.coverage();
    res.sections.push_back(f);
  }

  if (!o.out.empty()) {
    std::filesystem::create_directories(o.out);
    write_png(o.out / "map.png", draw_map(ws, cleaned, reachable, traj));
    write_text(o.out / "trajectory.csv", trajectory_csv(traj));
    write_text(o.out / "report.json", res.json());
    write_text(o.out / "lifecycle.txt", life.str());
  }
  return res;
}

}  // namespace tripodal::app
