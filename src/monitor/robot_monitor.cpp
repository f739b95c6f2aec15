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
#include "operator_request.hpp"
#include "robot_topics.hpp"
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

}  // namespace

struct RobotMonitor::Impl final : TaskObserver, SupervisorObserver {
  Robot& robot;
  const Clock& clock;
  MonitorServer& server;
  RobotMonitorOptions options;
  LifecycleRecorder life{true};
  RobotTopics topics;

  bool paused = false;
  std::string pause_reason;
  std::set<std::string, std::less<>> breakpoints;  // at most OperatorBudgets::kMaxBreakpoints
  std::size_t ack_notes = 0;  // ack notes with a text kept in the life cycle
  std::map<std::string, std::string, std::less<>> last_firing;  // run -> transition id
  std::map<std::string, std::string, std::less<>> behavior_params;  // behavior -> "a=1, b=2"
  bool nets_changed = true;
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

  Impl(Robot& r, const Clock& c, MonitorServer& s, RobotMonitorOptions o)
      : robot(r), clock(c), server(s), options(std::move(o)), topics(r, c, s) {
    hri = options.hri != nullptr ? options.hri : robot.module<HriService>();
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

  // Live mapping (navi::CMapBuilder): begin, end, status, save NAME into options.map_dir.
  void map_request(std::uint64_t id, const MapRequest& m) {
    auto* mapper = robot.module<navi::CMapBuilder>();
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
    topics.publish_map_once();
    topics.publish_lifecycle(life);
    if (nets_changed) {
      nets_changed = false;
      topics.publish_nets();
    }
    const auto wall = std::chrono::steady_clock::now();
    if (wall - last_publish >= std::chrono::duration<double>(options.min_interval_s)) {
      last_publish = wall;
      topics.publish_periodic(extras, ConsoleState{paused, pause_reason, breakpoints, driving, behavior_params, last_firing, hri,
                                                   options.robot_name, options.identity});
    }
    if (extras.cleaned_mask != nullptr && wall - last_cleaned >= std::chrono::duration<double>(options.cleaned_interval_s)) {
      last_cleaned = wall;
      topics.publish_cleaned(*extras.cleaned_mask);
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
