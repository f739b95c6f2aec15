#include "robot_panels.hpp"

#include "tripodal/board/board_hardware.hpp"

namespace tripodal::monitor {
namespace {

using nlohmann::json;

// The control board's link as the host sees it (hardware type "board", real or simulated): the
// panel of the page. Everything here is what the board reported over the line or the host counted.
json board_json(const board::BoardLinkReading& link, Time now) {
  const board::LinkStats& s = link.stats;
  const double answered = static_cast<double>(s.responses + s.error_responses);
  json j{{"connected", link.synchronised},
         {"requests", s.requests},
         {"responses", s.responses},
         {"missed", s.missed},
         {"error_responses", s.error_responses},
         {"link_losses", s.link_losses},
         {"resyncs", s.resyncs},
         {"reopens", s.reopens},
         {"retries", s.retries},
         {"watchdog_trips", s.watchdog_trips},
         {"decoder_errors", link.decoder_errors},
         {"bytes_sent", s.bytes_sent},
         {"bytes_received", s.bytes_received},
         {"round_trip_ms",
          {{"last", to_seconds(s.last_round_trip) * 1e3},
           {"max", to_seconds(s.max_round_trip) * 1e3},
           {"mean", answered > 0 ? to_seconds(s.total_round_trip) * 1e3 / answered : 0.0}}},
         {"pending_actuator_commands", link.pending_actuator_commands},
         {"battery", nullptr},
         {"tank", nullptr},
         {"status", nullptr}};
  if (!link.synchronised) j["lost_for_s"] = to_seconds(now - link.lost_at);
  if (link.has_battery) {
    const board::BatteryState& b = link.battery;
    j["battery"] = {{"percent", b.percent}, {"charging", b.charging}, {"voltage_v", b.voltage_mv / 1000.0}};
  }
  if (link.has_tank) j["tank"] = {{"percent", link.tank_percent}, {"empty", link.tank_empty}};
  if (link.has_drive) {
    const std::uint8_t f = link.drive_status;
    j["status"] = {{"uv_lamp", (f & board::kStatusUvLamp) != 0},
                   {"atomizer", (f & board::kStatusAtomizer) != 0},
                   {"emergency_stop", (f & board::kStatusEmergencyStop) != 0},
                   {"watchdog_latched", (f & board::kStatusLinkLost) != 0},
                   {"age_s", to_seconds(now - link.drive_stamp)}};
  }
  return j;
}

// What the robot's HRI displays (paper, section 4: its internal state), and the last exchange.
json hri_display_json(const HriDisplay& d) {
  json j{{"task", d.state.task},   {"task_state", d.state.task_state}, {"process", d.state.process},
         {"fault", d.state.fault}, {"status", display_text(d.state)},  {"last", nullptr}};
  if (d.last) {
    j["last"] = {{"source", d.last->source}, {"input", d.last->input}, {"kind", std::string(to_string(d.last->kind))},
                 {"reply", d.last->reply},   {"entry", d.last->entry}, {"task", d.last->task}};
  }
  return j;
}

}  // namespace

json status_panel(Robot& robot, Time now, double t, const MonitorExtras& extras, const ConsoleState& console) {
  const NavigationData& nav = robot.navigation();
  const CycleReport& cycle = robot.behavior_loop().last_cycle();
  json behaviors = json::array();
  for (const std::string& b : robot.supervisor().active_behaviors()) {
    const auto it = console.behavior_params.find(b);
    behaviors.push_back({{"name", b}, {"params", it == console.behavior_params.end() ? "" : it->second}});
  }
  json resources = json::array();
  for (std::size_t i = 0; i < robot.resources().size(); ++i) {
    const CResource& r = robot.resources().at(i);
    resources.push_back({{"name", r.name()}, {"age_s", r.has_reading() ? json(to_seconds(now - r.stamp())) : json(nullptr)}});
  }
  json status{{"robot", std::string(console.robot_name)},
              {"identity", console.identity.empty() ? json(nullptr) : json(std::string(console.identity))},
              {"time_s", t},
              {"paused", console.paused},
              {"pause_reason", console.paused ? std::string(console.pause_reason) : ""},
              {"task_state", std::string(to_string(robot.planner().state()))},
              {"task", robot.planner().report().command},
              {"behaviors", behaviors},
              {"winner", std::string(cycle.coordinator.winner)},
              {"velocity",
               {{"vx", cycle.coordinator.command.vx_m_s},
                {"vy", cycle.coordinator.command.vy_m_s},
                {"wz", cycle.coordinator.command.wz_rad_s}}},
              {"localized", nav.localized},
              {"estimate", {{"x", nav.map_from_base.x_m}, {"y", nav.map_from_base.y_m}, {"theta", nav.map_from_base.theta_rad}}},
              {"resources", resources},
              {"breakpoints", std::vector<std::string>(console.breakpoints.begin(), console.breakpoints.end())},
              {"driving", console.driving},
              {"battery", nullptr},
              {"coverage", extras.coverage ? json(*extras.coverage) : json(nullptr)}};
  if (const auto* battery = robot.resources().first<BatteryReading>(); battery != nullptr && battery->has_reading()) {
    status["battery"] = battery->latest().percentage;
  }
  // The link as the sequencing layer sees it (the resource snapshot): on the robot's own threads
  // the reactive loop's thread runs the link itself.
  if (const auto* link = robot.sequencing_resources().find<board::BoardLinkReading>("board_link");
      link != nullptr && link->has_reading()) {
    status["board"] = board_json(link->latest(), now);
  }
  status["hri"] = console.hri != nullptr ? hri_display_json(console.hri->display()) : json(nullptr);
  if (extras.true_pose)
    status["truth"] = {{"x", extras.true_pose->x_m}, {"y", extras.true_pose->y_m}, {"theta", extras.true_pose->theta_rad}};
  return status;
}

}  // namespace tripodal::monitor
