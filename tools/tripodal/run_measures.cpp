#include "run_measures.hpp"

#include <algorithm>
#include <array>
#include <deque>
#include <numbers>

#include "tripodal/behaviors/navigation_behaviors.hpp"

namespace tripodal::app {

using navi::Point2D;

PathFigures path_figures(const std::vector<Point2D>& path, double tolerance_m) {
  PathFigures f;
  if (path.size() < 2) return f;
  const std::vector<Point2D> simple = douglas_peucker(path, tolerance_m);
  const navi::PathStats s = navi::path_stats(simple, std::numbers::pi / 6.0);
  f.length_m = navi::polyline_length_m(path);
  f.turns = s.turns;
  return f;
}

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

DoseEstimate estimate_dose(navi::CCoveragePlanner& cov, const navi::CSectionSplitter& splitter,
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

DisinfectionFigures disinfection_figures(sim::SimBoardHardware& hw, const std::vector<char>& reachable,
                                         const std::vector<char>& lamp_floor, const navi::OccupancyGrid& grid,
                                         double target_j_m2) {
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

std::size_t cleaned_reachable(const std::vector<char>& reachable, const navi::CleanedCells& cleaned) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < reachable.size(); ++i) n += (reachable[i] != 0 && cleaned.cleaned(i)) ? 1 : 0;
  return n;
}

void set_floor_figures(RunResult& res, const Navigation& nav, const std::vector<char>& reachable,
                       const navi::CleanedCells& cleaned, const std::vector<navi::Point2D>& path_all,
                       const std::vector<navi::Point2D>& path_cleaning) {
  res.reachable_cells =
      static_cast<std::size_t>(std::count_if(reachable.begin(), reachable.end(), [](char c) { return c != 0; }));
  res.cleaned_cells = cleaned_reachable(reachable, cleaned);
  res.coverage =
      res.reachable_cells == 0 ? 0.0 : static_cast<double>(res.cleaned_cells) / static_cast<double>(res.reachable_cells);
  const double res_m = nav.maps->grid().resolution_m();
  res.reachable_area_m2 = static_cast<double>(res.reachable_cells) * res_m * res_m;
  res.total = path_figures(path_all);
  res.cleaning = path_figures(path_cleaning);
}

std::vector<std::string> plan_sections(const CPlanner& planner) {
  std::vector<std::string> sections;
  for (const PlanStage& stage : planner.current_plan().stages) {
    for (const ProcessStep& step : stage.steps) {
      for (const BindingParam& p : step.params) {
        if (p.name == "section" && std::find(sections.begin(), sections.end(), p.value) == sections.end()) {
          sections.push_back(p.value);
        }
      }
    }
  }
  return sections;
}

std::vector<SectionFigures> section_figures(const Navigation& nav, const std::vector<std::string>& sections) {
  std::vector<SectionFigures> out;
  for (const std::string& name : sections) {
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
    out.push_back(f);
  }
  return out;
}

}  // namespace tripodal::app
