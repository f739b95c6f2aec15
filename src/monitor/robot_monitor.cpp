#include "tripodal/monitor/robot_monitor.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <utility>
#include <variant>

#include "hri_ops.hpp"
#include "net_drawing.hpp"
#include "operator_request.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/behaviors/teleop.hpp"
#include "tripodal/board/board_hardware.hpp"
#include "tripodal/core/net_loader.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/mapping_module.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"

namespace tripodal::monitor {
namespace {

using nlohmann::json;

// JSON schemas of the topics (Foxglove reads them to name fields); the foxglove.* shapes are the
// ones its panels draw.
constexpr std::string_view kTimeSchema = R"({"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}})";

std::string pose_schema() {
  return std::string(R"({"type":"object","properties":{"timestamp":)") + std::string(kTimeSchema) +
         R"(,"frame_id":{"type":"string"},"pose":{"type":"object","properties":{"position":{"type":"object"},"orientation":{"type":"object"}}}}})";
}

json stamp(double t_s) {
  const double sec = std::floor(std::max(t_s, 0.0));
  return json{{"sec", static_cast<std::int64_t>(sec)}, {"nsec", static_cast<std::int64_t>((std::max(t_s, 0.0) - sec) * 1e9)}};
}

json pose_json(const Pose2D& p) {
  return json{{"position", {{"x", p.x_m}, {"y", p.y_m}, {"z", 0.0}}},
              {"orientation", {{"x", 0.0}, {"y", 0.0}, {"z", std::sin(p.theta_rad / 2.0)}, {"w", std::cos(p.theta_rad / 2.0)}}}};
}

std::string base64_bytes(const std::vector<std::uint8_t>& v) {
  return base64(std::string_view(reinterpret_cast<const char*>(v.data()), v.size()));
}

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
  json j{{"task", d.state.task},
         {"task_state", d.state.task_state},
         {"process", d.state.process},
         {"fault", d.state.fault},
         {"status", display_text(d.state)},
         {"last", nullptr}};
  if (d.last) {
    j["last"] = {{"source", d.last->source}, {"input", d.last->input}, {"kind", std::string(to_string(d.last->kind))},
                 {"reply", d.last->reply},   {"entry", d.last->entry}, {"task", d.last->task}};
  }
  return j;
}

struct NetView {
  std::string run;
  const PetriNet* net = nullptr;
  const Engine* engine = nullptr;
};

}  // namespace

struct RobotMonitor::Impl final : TaskObserver, SupervisorObserver {
  Robot& robot;
  const Clock& clock;
  MonitorServer& server;
  RobotMonitorOptions options;
  LifecycleRecorder life{true};
  NetDrawing drawing;
  std::size_t life_published = 0;

  std::uint32_t ch_pose = 0, ch_path = 0, ch_map = 0, ch_cleaned = 0, ch_laser = 0, ch_nets = 0, ch_markings = 0,
                ch_lifecycle = 0, ch_status = 0;

  bool paused = false;
  std::string pause_reason;
  std::set<std::string, std::less<>> breakpoints;  // at most OperatorBudgets::kMaxBreakpoints
  std::size_t ack_notes = 0;  // ack notes with a text kept in the life cycle
  std::map<std::string, std::string, std::less<>> last_firing;  // run -> transition id
  std::map<std::string, std::string, std::less<>> behavior_params;  // behavior -> "a=1, b=2"
  bool nets_changed = true;
  std::uint32_t path_id = ~0U;
  Time last_scan{Duration{-1}};
  bool map_sent = false;
  std::chrono::steady_clock::time_point last_publish{}, last_cleaned{};
  // A reload that was valid but came while its run was not quiet: retried between periods (the
  // supervisor's quiet points) until it goes through, fails otherwise, or its time is up.
  struct PendingReload {
    std::uint64_t request = 0;
    std::string run, text, source;
    std::chrono::steady_clock::time_point deadline{};
  };
  std::optional<PendingReload> pending_reload;
  // The operator's hand on the robot: the input of the behavior BhTeleop the robot runs on the
  // coordinator input "operator" (behaviors/teleop.hpp); nullptr for a robot without a loop.
  TeleopResource* teleop = nullptr;
  bool driving = false;
  std::chrono::steady_clock::time_point last_drive{};
  // The robot's HRI, found once: the modules do not change after assembly.
  HriService* hri = nullptr;

  Impl(Robot& r, const Clock& c, MonitorServer& s, RobotMonitorOptions o) : robot(r), clock(c), server(s), options(std::move(o)) {
    hri = options.hri != nullptr ? options.hri : robot.module<HriService>();
    ch_pose = server.advertise("/pose", "foxglove.PoseInFrame", pose_schema(), Delivery::bulk);
    ch_path = server.advertise("/path", "foxglove.PosesInFrame",
                               R"({"type":"object","properties":{"frame_id":{"type":"string"},"poses":{"type":"array"}}})", Delivery::state);
    ch_map = server.advertise("/map", "tripodal.Map",
                              R"({"type":"object","properties":{"width":{"type":"integer"},"height":{"type":"integer"},"resolution":{"type":"number"},"cells":{"type":"string","contentEncoding":"base64"},"section_of_cell":{"type":"string","contentEncoding":"base64"},"sections":{"type":"array"}}})",
                              Delivery::state);
    ch_cleaned = server.advertise("/cleaned", "tripodal.CleanedCells",
                                  R"({"type":"object","properties":{"width":{"type":"integer"},"height":{"type":"integer"},"mask":{"type":"string","contentEncoding":"base64"}}})",
                                  Delivery::bulk);
    ch_laser = server.advertise("/laser", "foxglove.LaserScan",
                                R"({"type":"object","properties":{"frame_id":{"type":"string"},"pose":{"type":"object"},"start_angle":{"type":"number"},"end_angle":{"type":"number"},"ranges":{"type":"array","items":{"type":"number"}},"intensities":{"type":"array","items":{"type":"number"}}}})",
                                Delivery::bulk);
    ch_nets = server.advertise("/nets", "tripodal.Nets",
                               R"({"type":"object","properties":{"nets":{"type":"array","items":{"type":"object","properties":{"run":{"type":"string"},"net":{"type":"string"},"places":{"type":"array"},"transitions":{"type":"array"},"svg":{"type":"string","description":"Graphviz dot layout"}}}}}})",
                               Delivery::state);
    ch_markings = server.advertise("/markings", "tripodal.Markings",
                                   R"({"type":"object","properties":{"nets":{"type":"array","items":{"type":"object","properties":{"run":{"type":"string"},"marked":{"type":"array"},"last_firing":{"type":"string"}}}}}})",
                                   Delivery::bulk);
    ch_lifecycle = server.advertise("/lifecycle", "tripodal.LifecycleEntry",
                                    R"({"type":"object","properties":{"time_s":{"type":"number"},"kind":{"type":"string"},"text":{"type":"string"}}})",
                                    Delivery::event);
    ch_status = server.advertise("/status", "tripodal.Status",
                                 R"({"type":"object","properties":{"time_s":{"type":"number"},"paused":{"type":"boolean"},"task_state":{"type":"string"},"velocity":{"type":"object"},"battery":{"type":["number","null"]},"coverage":{"type":["number","null"]},"behaviors":{"type":"array"},"winner":{"type":"string"},"board":{"type":"object","description":"the control board's link as the host sees it; only on hardware board"},"hri":{"type":["object","null"],"description":"what the robot's HRI displays: task, task_state, process, fault, status, and the last input with its answer (last); null without an HRI"}}})",
                                 Delivery::bulk);
    teleop = dynamic_cast<TeleopResource*>(robot.behavior_loop().resources().find(kTeleopResource));
    paused = options.start_paused;
    if (paused) pause_reason = "started paused";
    robot.planner().add_observer(*this);
    robot.planner().add_observer(life);
    robot.supervisor().add_observer(*this);
    robot.supervisor().add_observer(life);
  }

  ~Impl() override {
    stop_driving("monitor detached");
    robot.supervisor().remove_observer(life);
    robot.supervisor().remove_observer(*this);
    robot.planner().remove_observer(life);
    robot.planner().remove_observer(*this);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  double now_s() const { return to_seconds(clock.now()); }

  void stop_driving(std::string_view why) {
    if (!driving) return;
    driving = false;
    teleop->set(false, Twist2D{}, clock.now());
    robot.behavior_loop().set_lock(kTeleopInput, false, clock.now());
    note("operator: manual drive ended (" + std::string(why) + ")");
  }

  void drive_with(double vx, double vy, double wz) {
    if (teleop == nullptr) throw std::runtime_error("this robot has no behavior loop to drive by hand");
    teleop->set(true, Twist2D{vx, vy, wz}, clock.now());
    last_drive = std::chrono::steady_clock::now();
    if (driving) return;
    robot.behavior_loop().set_lock(kTeleopInput, true, clock.now());
    driving = true;
    note("operator: manual drive (the task's motion masked)");
  }

  void note(std::string text) { life.note(clock.now(), std::move(text)); }

  // --- observers --------------------------------------------------------------------------------
  void on_task_started(const TaskReport&, const Plan&, Time) override { nets_changed = true; }
  void on_task_succeeded(const TaskReport&) override { nets_changed = true; }
  void on_task_failed(const TaskReport&) override { nets_changed = true; }
  void on_run_started(std::string_view, const CProcess&, const ParameterValues&, Time) override { nets_changed = true; }
  void on_run_finished(const ProcessResult&) override { nets_changed = true; }
  void on_net_reloaded(std::string_view, const CProcess&, std::string_view, Time) override { nets_changed = true; }
  void on_behavior_activated(std::string_view, std::string_view behavior, const ParameterValues& params, Time) override {
    std::string text;
    for (const auto& [k, v] : params) text += (text.empty() ? "" : ", ") + k + "=" + to_string(v);
    behavior_params[std::string(behavior)] = text;
  }
  void on_behavior_deactivated(std::string_view, std::string_view behavior, Time) override {
    if (const auto it = behavior_params.find(behavior); it != behavior_params.end()) behavior_params.erase(it);
  }
  void on_firing(std::string_view run, const PetriNet& net, const Firing& firing) override {
    last_firing[std::string(run)] = std::string(firing.transition_id);
    if (breakpoints.empty()) return;
    for (const PlaceChange& c : firing.changes) {
      if (c.produced == 0) continue;
      const Place& p = net.place(c.place);
      if (breakpoints.contains(p.id) || breakpoints.contains(p.name) || breakpoints.contains(net.id + "." + p.id)) {
        pause_now("breakpoint: place " + p.id + (p.name != p.id ? " (" + p.name + ")" : "") + " of " + net.id + " (run " +
                  std::string(run) + ") marked");
      }
    }
  }

  void pause_now(const std::string& reason) {
    paused = true;
    pause_reason = reason;
    note("monitor: paused, " + reason);
  }

  // --- reloading an edited net ----------------------------------------------------------------------
  static json diagnostics_json(const Diagnostics& d) {
    json out = json::array();
    for (const Diagnostic& x : d.all()) {
      out.push_back({{"severity", x.severity == Severity::error ? "error" : x.severity == Severity::warning ? "warning" : "note"},
                     {"where", x.where.str()},
                     {"message", x.message},
                     {"text", x.str()}});
    }
    return out;
  }

  // One attempt; true when the request is answered (accepted, or refused for good).
  bool try_reload(std::uint64_t request, const std::string& run, const std::string& text, const std::string& source, bool last_chance) {
    const ReloadResult res = robot.supervisor().reload(run, text, source);
    if (!res.accepted && res.not_quiet && !last_chance) return false;
    if (res.accepted) {
      note("operator: net of " + run + " reloaded (" + source + ")");
    } else {
      const std::string first = res.diagnostics.all().empty() ? std::string() : res.diagnostics.all().front().str();
      note("operator: reload of " + run + " refused: " + first);
    }
    server.answer(request, 200,
                  json{{"accepted", res.accepted}, {"run", run}, {"marking", res.marking}, {"diagnostics", diagnostics_json(res.diagnostics)}}
                      .dump());
    return true;
  }

  void retry_pending_reload() {
    if (!pending_reload) return;
    const bool last = paused || std::chrono::steady_clock::now() >= pending_reload->deadline;
    if (try_reload(pending_reload->request, pending_reload->run, pending_reload->text, pending_reload->source, last)) pending_reload.reset();
  }

  // Live mapping (navi::CMappingModule): begin, end, status, save NAME into options.map_dir.
  void map_request(std::uint64_t id, const MapRequest& m) {
    auto* mapper = robot.module<navi::CMappingModule>();
    if (mapper == nullptr) return reply(id, 404, {{"error", "map: the robot has no MapBuilder module (add one to its profile's navigation)"}});
    const auto status = [&] {
      return json{{"mapping", mapper->mapping()}, {"scans", mapper->scans()}, {"quality", mapper->last_quality()}};
    };
    switch (m.action) {
      case MapRequest::Action::begin:
        // in the frame of the robot's current estimate, so a new map overlays the one it runs on
        mapper->begin(robot.navigation().map_from_base);
        note("operator: mapping begun");
        return reply(id, 200, status());
      case MapRequest::Action::end:
        mapper->end();
        note("operator: mapping ended after " + std::to_string(mapper->scans()) + " scans");
        return reply(id, 200, status());
      case MapRequest::Action::status: return reply(id, 200, status());
      case MapRequest::Action::save: break;
    }
    if (options.map_dir.empty()) return reply(id, 403, {{"error", "map: saving is off (the application sets the monitor's map folder)"}});
    // a bare file name (checked by the request layer): the operator chooses the name, never the folder
    const std::filesystem::path file = options.map_dir / (m.name + ".yaml");
    try {
      std::filesystem::create_directories(options.map_dir);
      mapper->save(file);
    } catch (const std::exception& e) {
      return reply(id, 409, {{"error", std::string("map: ") + e.what()}});
    }
    note("operator: map saved to " + file.string());
    json j = status();
    j["saved"] = file.string();
    reply(id, 200, j);
  }

  void reload(std::uint64_t id, const ReloadRequest& r) {
    if (r.run == "task") {
      return reply(id, 409, {{"error", "reload: the task's net is composed by the planner from the process modules; reload a process net"}});
    }
    if (pending_reload) {
      return reply(id, 409, {{"error", "reload: the reload of " + pending_reload->run + " is waiting for a quiet marking"}});
    }
    const CProcess* process = robot.supervisor().process(r.run);
    // The name diagnostics give the edited text: the process's own file name, marked as edited.
    const std::string source = (process != nullptr ? process->name() : r.run) + ".edited.xml";
    // Paused, nothing steps: a run that is not quiet now will not become quiet, so no waiting.
    if (try_reload(id, r.run, r.xml, source, paused)) return;
    pending_reload = PendingReload{id, r.run, r.xml, source,
                                   std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                                          std::chrono::duration<double>(options.reload_wait_s))};
  }

  // --- operator requests --------------------------------------------------------------------------
  // Read and checked by one layer (operator_request.hpp): what reaches the ops below has the right
  // types, ranges and lengths; a request that does not is answered 400 naming the field.
  void handle(const OperatorRequest& r) {
    const ParsedRequest parsed = parse_operator_request(r.body);
    if (!parsed.command) return server.answer(r.id, 400, refusal_json(parsed).dump());
    const OperatorCommand& command = *parsed.command;
    if (is_hri_op(command)) {
      const HriOpResult result = handle_hri_op(hri, parsed.op, command, [this](std::string text) { note(std::move(text)); });
      return server.answer(r.id, result.status, result.body.dump());
    }
    std::visit([&](const auto& request) { op(r.id, request); }, command);
  }

  void reply(std::uint64_t id, int status, const json& j) { server.answer(id, status, j.dump()); }

  void op(std::uint64_t id, const TaskRequest& t) {
    const CommandAnswer a = robot.command(t.text);
    note(std::string("operator: \"") + t.text + "\": " + (a.accepted ? "accepted" : "refused") + ": " + a.text);
    reply(id, 200, {{"accepted", a.accepted}, {"text", a.text}});
  }
  void op(std::uint64_t id, const PauseRequest&) {
    pause_now("by the operator");
    reply(id, 200, {{"paused", true}});
  }
  void op(std::uint64_t id, const ResumeRequest&) {
    paused = false;
    note("monitor: resumed by the operator");
    reply(id, 200, {{"paused", false}});
  }
  void op(std::uint64_t id, const CancelRequest&) {
    if (!robot.planner().busy()) return reply(id, 409, {{"error", "no task is running"}});
    robot.planner().cancel("cancelled by the operator");
    reply(id, 200, {{"cancelled", true}});
  }
  void op(std::uint64_t id, const DriveRequest& d) {
    if (d.stop) {
      stop_driving("stopped by the operator");
      return reply(id, 200, {{"driving", false}});
    }
    drive_with(d.vx_m_s, d.vy_m_s, d.wz_rad_s);
    reply(id, 200, {{"driving", true}, {"deadman_s", options.drive_deadman_s}});
  }
  void op(std::uint64_t id, const AckRequest& a) {
    // An acknowledgement is never refused; its note is kept while the run's budget of notes lasts.
    const bool keep = !a.text.empty() && ack_notes < OperatorBudgets::kMaxAckNotesKept;
    if (keep) ++ack_notes;
    note("operator: fault acknowledged" + (keep ? ": " + a.text : a.text.empty() ? std::string() : std::string(" (its note is not kept: ") +
                                                                                       std::to_string(OperatorBudgets::kMaxAckNotesKept) +
                                                                                       " notes were kept already)"));
    reply(id, 200, {{"acknowledged", true}, {"note_kept", keep}});
  }
  void op(std::uint64_t id, const NetRequest& n) {
    if (n.run == "task") return reply(id, 409, {{"error", "net: the task's net is composed by the planner; only process nets are edited"}});
    const CProcess* process = robot.supervisor().process(n.run);
    if (process == nullptr) return reply(id, 404, {{"error", "net: no process is running as '" + n.run + "'"}});
    reply(id, 200, {{"run", n.run}, {"process", process->name()}, {"xml", net_to_string(process->net(), NetFormat::native_xml)}});
  }
  void op(std::uint64_t id, const ReloadRequest& r) { reload(id, r); }
  void op(std::uint64_t id, const MapRequest& m) { map_request(id, m); }
  void op(std::uint64_t id, const BreakpointRequest& b) {
    if (b.on && !breakpoints.contains(b.place) && breakpoints.size() >= OperatorBudgets::kMaxBreakpoints) {
      return reply(id, 409, {{"error", "breakpoint: " + std::to_string(breakpoints.size()) + " breakpoints are set, the most the monitor keeps; clear one first"},
                             {"field", "place"}});
    }
    if (b.on) breakpoints.insert(b.place);
    else breakpoints.erase(b.place);
    note("monitor: breakpoint " + std::string(b.on ? "set" : "cleared") + " on place " + b.place);
    reply(id, 200, {{"breakpoints", std::vector<std::string>(breakpoints.begin(), breakpoints.end())}});
  }
  template <class HriRequest>
  void op(std::uint64_t id, const HriRequest&) {
    reply(id, 500, {{"error", "not a console op"}});  // the HRI's, handled above
  }

  // --- topics -------------------------------------------------------------------------------------
  std::vector<NetView> running_nets() const {
    std::vector<NetView> out;
    if (const Engine* e = robot.planner().net_engine()) out.push_back({"task", &e->net(), e});
    for (const std::string& run : robot.supervisor().running_runs()) {
      if (const Engine* e = robot.supervisor().engine(run)) out.push_back({run, &e->net(), e});
    }
    return out;
  }

  void publish_nets(const std::vector<NetView>& nets) {
    json j{{"nets", json::array()}};
    for (const NetView& v : nets) {
      json places = json::array(), transitions = json::array();
      for (const Place& p : v.net->places()) {
        json jp{{"id", p.id}, {"name", p.name}, {"initial", p.initial_tokens}};
        if (p.behavior) jp["behavior"] = p.behavior->behavior;
        if (p.process) jp["process"] = true;
        if (p.outcome != Outcome::none) jp["outcome"] = p.outcome == Outcome::success ? "success" : "fault";
        places.push_back(std::move(jp));
      }
      for (const Transition& t : v.net->transitions()) {
        json in = json::array(), out = json::array();
        for (const ArcRef& a : t.inputs) in.push_back(a.place);
        for (const ArcRef& a : t.reads) in.push_back(a.place);
        for (const ArcRef& a : t.outputs) out.push_back(a.place);
        transitions.push_back({{"id", t.id}, {"name", t.name}, {"event", t.event}, {"in", in}, {"out", out}});
      }
      j["nets"].push_back({{"run", v.run}, {"net", v.net->id}, {"places", places}, {"transitions", transitions}, {"svg", drawing.svg(*v.net)}});
    }
    server.publish(ch_nets, now_s(), j.dump());
  }

  void publish_map() {
    const auto* maps = robot.module<navi::CGridMaps>();
    if (maps == nullptr) return;
    const navi::OccupancyGrid& g = maps->grid();
    if (g.size() == 0) return;
    std::vector<std::uint8_t> cells(g.size()), section_of(g.size(), 0);
    for (std::size_t i = 0; i < g.size(); ++i) {
      const auto s = g.state(i);
      cells[i] = s == navi::Occupancy::free ? 0 : s == navi::Occupancy::occupied ? 1 : 2;
    }
    json sections = json::array();
    if (const auto* splitter = robot.module<navi::CSectionSplitter>()) {
      for (const navi::Section& s : splitter->sections().sections) {
        for (const std::size_t i : s.cells) section_of[i] = static_cast<std::uint8_t>(1 + s.id % 250);
        sections.push_back({{"name", s.name}, {"index", 1 + s.id % 250}, {"x", s.centroid.x_m}, {"y", s.centroid.y_m}, {"area_m2", s.area_m2}});
      }
    }
    const json j{{"width", g.width()},      {"height", g.height()},       {"resolution", g.resolution_m()},
                 {"origin", {{"x", g.origin().x_m}, {"y", g.origin().y_m}}}, {"cells", base64_bytes(cells)},
                 {"section_of_cell", base64_bytes(section_of)}, {"sections", sections}};
    server.publish(ch_map, now_s(), j.dump());
    map_sent = true;
  }

  void publish_periodic(const MonitorExtras& extras) {
    const double t = now_s();
    const NavigationData& nav = robot.navigation();
    server.publish(ch_pose, t, json{{"timestamp", stamp(t)}, {"frame_id", "map"}, {"pose", pose_json(nav.map_from_base)}}.dump());
    if (nav.path_id != path_id) {
      path_id = nav.path_id;
      json poses = json::array();
      for (const Pose2D& p : nav.path) poses.push_back({{"timestamp", stamp(t)}, {"frame_id", "map"}, {"pose", pose_json(p)}});
      server.publish(ch_path, t, json{{"timestamp", stamp(t)}, {"frame_id", "map"}, {"poses", poses}}.dump());
    }
    // A scan once, when it is new (a scanner turns slower than the monitor publishes).
    if (const auto* laser = robot.resources().first<LaserScan>(); laser != nullptr && laser->has_reading() && laser->stamp() != last_scan) {
      last_scan = laser->stamp();
      const LaserScan& s = laser->latest();
      json ranges = json::array();
      // Millimetres are all a drawing needs, and the scan is the largest message (shortest decimals).
      for (const float r : s.ranges_m) {
        ranges.push_back(std::isfinite(r) && r >= s.range_min_m && r <= s.range_max_m ? std::round(static_cast<double>(r) * 1000.0) / 1000.0 : 0.0);
      }
      server.publish(ch_laser, t,
                     json{{"timestamp", stamp(to_seconds(s.stamp))}, {"frame_id", "map"}, {"pose", pose_json(nav.map_from_base)},
                          {"start_angle", s.angle_min_rad}, {"end_angle", s.angle_max_rad}, {"ranges", ranges}, {"intensities", json::array()}}
                         .dump());
    }
    json marked = json::array();
    for (const NetView& v : running_nets()) {
      json places = json::array();
      const auto m = v.engine->marking();
      for (std::size_t i = 0; i < m.size(); ++i) {
        if (m[i] > 0) places.push_back({{"place", v.net->places()[i].id}, {"tokens", m[i]}});
      }
      const auto lf = last_firing.find(v.run);
      marked.push_back({{"run", v.run}, {"net", v.net->id}, {"marked", places}, {"last_firing", lf == last_firing.end() ? "" : lf->second}});
    }
    server.publish(ch_markings, t, json{{"timestamp", stamp(t)}, {"nets", marked}}.dump());

    const CycleReport& cycle = robot.behavior_loop().last_cycle();
    json behaviors = json::array();
    for (const std::string& b : robot.supervisor().active_behaviors()) {
      const auto it = behavior_params.find(b);
      behaviors.push_back({{"name", b}, {"params", it == behavior_params.end() ? "" : it->second}});
    }
    json resources = json::array();
    const Time now = clock.now();
    for (std::size_t i = 0; i < robot.resources().size(); ++i) {
      const CResource& r = robot.resources().at(i);
      resources.push_back({{"name", r.name()}, {"age_s", r.has_reading() ? json(to_seconds(now - r.stamp())) : json(nullptr)}});
    }
    json status{{"time_s", t},
                {"paused", paused},
                {"pause_reason", paused ? pause_reason : ""},
                {"task_state", std::string(to_string(robot.planner().state()))},
                {"task", robot.planner().report().command},
                {"behaviors", behaviors},
                {"winner", std::string(cycle.coordinator.winner)},
                {"velocity", {{"vx", cycle.coordinator.command.vx_m_s}, {"vy", cycle.coordinator.command.vy_m_s}, {"wz", cycle.coordinator.command.wz_rad_s}}},
                {"localized", nav.localized},
                {"estimate", {{"x", nav.map_from_base.x_m}, {"y", nav.map_from_base.y_m}, {"theta", nav.map_from_base.theta_rad}}},
                {"resources", resources},
                {"breakpoints", std::vector<std::string>(breakpoints.begin(), breakpoints.end())},
                {"driving", driving},
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
    status["hri"] = hri != nullptr ? hri_display_json(hri->display()) : json(nullptr);
    if (extras.true_pose) status["truth"] = {{"x", extras.true_pose->x_m}, {"y", extras.true_pose->y_m}, {"theta", extras.true_pose->theta_rad}};
    server.publish(ch_status, t, status.dump());
  }

  void update(const MonitorExtras& extras) {
    retry_pending_reload();
    for (const OperatorRequest& r : server.take_requests()) {
      // The last resort: whatever a request sets off, the robot's thread goes on (the layer in
      // operator_request.hpp means nothing should get here).
      try {
        handle(r);
      } catch (const std::exception& e) {
        spdlog::error("monitor: request {} failed: {}", r.id, e.what());
        note(std::string("monitor: an operator request failed: ") + e.what());
        server.answer(r.id, 500, json{{"error", std::string("the request failed on the robot: ") + e.what()}}.dump(-1, ' ', false, json::error_handler_t::replace));
      }
    }
    // The dead-man switch: the console repeats the command while a key is held.
    if (driving && std::chrono::steady_clock::now() - last_drive > std::chrono::duration<double>(options.drive_deadman_s)) {
      stop_driving("no command for " + std::to_string(static_cast<int>(options.drive_deadman_s * 1000)) + " ms");
    }
    if (!map_sent) publish_map();
    const double t = now_s();
    const auto& entries = life.entries();
    for (; life_published < entries.size(); ++life_published) {
      const LifecycleEntry& e = entries[life_published];
      const bool firing = e.text.find(" fire ") != std::string::npos;
      if (firing) continue;  // firings travel as markings (last_firing), not as timeline entries
      const std::string kind = e.text.starts_with("task") ? "task"
                               : e.text.starts_with("process") ? "process"
                               : e.text.find("fault") != std::string::npos || e.text.find("failed") != std::string::npos ? "fault"
                               : e.text.find("recover") != std::string::npos ? "recovery"
                                                                             : "note";
      server.publish(ch_lifecycle, to_seconds(e.time), json{{"time_s", to_seconds(e.time)}, {"kind", kind}, {"text", e.text}}.dump());
    }
    if (nets_changed) {
      nets_changed = false;
      publish_nets(running_nets());
    }
    const auto wall = std::chrono::steady_clock::now();
    if (wall - last_publish >= std::chrono::duration<double>(options.min_interval_s)) {
      last_publish = wall;
      publish_periodic(extras);
    }
    if (extras.cleaned_mask != nullptr && wall - last_cleaned >= std::chrono::duration<double>(options.cleaned_interval_s)) {
      last_cleaned = wall;
      const std::vector<std::uint8_t>& m = *extras.cleaned_mask;
      std::vector<std::uint8_t> bits((m.size() + 7) / 8, 0);
      for (std::size_t i = 0; i < m.size(); ++i) {
        if (m[i] != 0) bits[i / 8] = static_cast<std::uint8_t>(bits[i / 8] | (1U << (i % 8)));
      }
      server.publish(ch_cleaned, t, json{{"cells", m.size()}, {"mask", base64_bytes(bits)}}.dump());
    }
  }
};

RobotMonitor::RobotMonitor(Robot& robot, const Clock& clock, MonitorServer& server, RobotMonitorOptions options)
    : impl_(std::make_unique<Impl>(robot, clock, server, std::move(options))) {}
RobotMonitor::~RobotMonitor() = default;

void RobotMonitor::update(const MonitorExtras& extras) { impl_->update(extras); }
bool RobotMonitor::paused() const noexcept { return impl_->paused; }
void RobotMonitor::pause(const std::string& reason) { impl_->pause_now(reason); }
void RobotMonitor::resume() {
  impl_->paused = false;
  impl_->note("monitor: resumed");
}
void RobotMonitor::set_breakpoint(std::string place, bool on) {
  if (!on) {
    impl_->breakpoints.erase(place);
    return;
  }
  if (place.empty() || place.size() > OperatorBudgets::kMaxBreakpointBytes) {
    throw std::invalid_argument("breakpoint: a place of " + std::to_string(place.size()) + " bytes; expected 1 to " +
                                std::to_string(OperatorBudgets::kMaxBreakpointBytes));
  }
  if (!impl_->breakpoints.contains(place) && impl_->breakpoints.size() >= OperatorBudgets::kMaxBreakpoints) {
    throw std::invalid_argument("breakpoint: " + std::to_string(OperatorBudgets::kMaxBreakpoints) + " breakpoints are set, the most the monitor keeps");
  }
  impl_->breakpoints.insert(std::move(place));
}
void RobotMonitor::set_hri(HriService* hri) noexcept { impl_->hri = hri; }
std::vector<std::string> RobotMonitor::breakpoints() const {
  return {impl_->breakpoints.begin(), impl_->breakpoints.end()};
}

}  // namespace tripodal::monitor
