// report.json of `tripodal run`: the figures of a run (RunResult) as JSON.
#include <cmath>

#include <nlohmann/json.hpp>

#include "run_task.hpp"

namespace tripodal::app {

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
                            {"hybrid", stats(sec.hybrid, sec.hybrid_coverage)},
                            {"balloon", stats(sec.balloon, sec.balloon_coverage)},
                            {"boustrophedon", stats(sec.boustrophedon, sec.boustrophedon_coverage)}});
  }
  Json report = {{"robot", robot},
                       {"task", task},
                       {"coverage_pattern", coverage_pattern},
                       {"seed", seed},
                       {"state", state},
                       {"succeeded", succeeded},
                       {"reason", reason},
                       {"stopped_by", stopped_by},
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
                       {"robot_steps", robot_steps},
                       {"base_at_rest", base_at_rest},
                       {"base_command_at_end_rad_s", base_command_at_end_rad_s}};
  report["duration_clock"] = wall_clock ? "wall" : "simulated";  // devices on ttys: timed by the wall clock
  if (!loops.empty()) {
    const auto us = [&](Duration d) { return rounded(static_cast<double>(d.count()) / 1000.0, 1); };
    Json list = Json::array();
    for (const LoopTimingReport& l : loops) {
      list.push_back({{"name", l.name},
                      {"period_s", to_seconds(l.period)},
                      {"budget_s", to_seconds(l.budget)},
                      {"cycles", l.cycles},
                      {"period_error_us",
                       {{"p50", us(l.period_error_p50)}, {"p99", us(l.period_error_p99)}, {"max", us(l.period_error_max)}}},
                      {"execution_us", {{"p99", us(l.execution_p99)}, {"max", us(l.execution_max)}}},
                      {"overruns", l.overruns},
                      {"skipped_ticks", l.skipped_ticks},
                      {"deadline_faults", l.deadline_faults},
                      {"sched_fifo", l.realtime},
                      {"warning", l.warning}});
    }
    report["realtime"] = {{"speed", realtime_speed}, {"loops", std::move(list)}};
  }
  if (disinfection) {
    const DisinfectionFigures& d = *disinfection;
    const auto ms = [&](Duration t) { return rounded(to_seconds(t) * 1000.0, 3); };
    const double mean_rtt_ms = d.link.responses == 0 ? 0.0 : to_seconds(d.link.total_round_trip) * 1000.0 / static_cast<double>(d.link.responses);
    report["disinfection"] = {{"line", d.line},
                              {"uv_target_dose_j_m2", d.uv_target_dose_j_m2},
                              {"dose_coverage", rounded(d.dose_coverage, 4)},
                              {"median_dose_j_m2", rounded(d.median_dose_j_m2, 2)},
                              {"lamp_on_s", rounded(d.lamp_on_s, 2)},
                              {"disinfectant_used_l", rounded(d.disinfectant_used_l, 4)},
                              {"disinfectant_left_l", rounded(d.disinfectant_left_l, 4)},
                              {"battery_used_ah", rounded(d.battery_used_ah, 4)},
                              {"lamp_energy_wh", rounded(d.lamp_energy_wh, 3)},
                              {"uvc_energy_j", rounded(d.uvc_energy_j, 1)},
                              {"link",
                               {{"requests", d.link.requests},
                                {"responses", d.link.responses},
                                {"missed", d.link.missed},
                                {"error_responses", d.link.error_responses},
                                {"retries", d.link.retries},
                                {"link_losses", d.link.link_losses},
                                {"mean_round_trip_ms", rounded(mean_rtt_ms, 3)},
                                {"max_round_trip_ms", ms(d.link.max_round_trip)},
                                {"decoder_errors", d.decoder_errors},
                                {"board_requests", d.board_requests},
                                {"watchdog_trips", d.watchdog_trips},
                                {"bytes_to_board", d.bytes_to_board},
                                {"bytes_to_host", d.bytes_to_host},
                                {"bytes_lost", d.bytes_lost}}}};
    if (d.plan) {
      report["disinfection"]["dose_plan"] = {{"target_j_m2", d.plan->target_j_m2},
                                             {"spacing_m", rounded(d.plan->spacing_m, 3)},
                                             {"speed_m_s", rounded(d.plan->speed_m_s, 4)},
                                             {"passes", d.plan->passes},
                                             {"reach_m", rounded(d.plan->reach_m, 4)},
                                             {"estimate_s", rounded(d.estimate_s, 1)},
                                             {"estimate_ah", rounded(d.estimate_ah, 3)},
                                             {"lamp_floor_m2", rounded(d.lamp_floor_m2, 2)},
                                             {"lamp_floor_dose_coverage", rounded(d.lamp_floor_dose_coverage, 4)}};
    }
  }
  // Task text and names come from the user: bytes that are not UTF-8 are replaced, not thrown on.
  return report.dump(2, ' ', false, Json::error_handler_t::replace) + '\n';
}

}  // namespace tripodal::app
