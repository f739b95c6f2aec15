// `tripodal run --visit`: Jinny's guided visit of the exhibit hall in the simulator (visit.hpp).
#include "visit.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <ostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "guide_hri.hpp"
#include "run_outputs.hpp"
#include "run_task.hpp"
#include "shutdown.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/hri/hri_module.hpp"
#include "tripodal/monitor/robot_monitor.hpp"
#include "tripodal/hri/speech.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"
#include "visit_audio.hpp"

namespace tripodal::app {

namespace {

// The voices: the visitor's (espeak-ng klatt, which pocketsphinx hears best, docs/hri.md) and the
// recognizer with a language model of what the robot knows; the robot's own (espeak-ng en-us) is
// the HRI's (GuideHri), which the touch page speaks with too.
struct Voice {
  std::unique_ptr<SpeechSynthesizer> visitor;
  std::unique_ptr<SpeechRecognizer> ears;
  std::string off_reason;
};

std::unique_ptr<SpeechSynthesizer> make_robot_voice(bool wanted, std::string& off_reason) {
  if (!wanted) {
    off_reason = "off (--no-voice)";
    return nullptr;
  }
  if (!voice_available()) {
    off_reason = "off: this build has no espeak-ng and pocketsphinx (TRIPODAL_VOICE)";
    return nullptr;
  }
  try {
    return make_espeak_synthesizer();
  } catch (const std::exception& e) {
    off_reason = std::string("off: ") + e.what();
    return nullptr;
  }
}

Voice make_voice(const KnowledgeBase& base, const TaskLibrary& tasks, const navi::RegionMap& regions) {
  Voice v;
  try {
    std::vector<std::string> nodes;
    for (const navi::MapNode& n : regions.nodes) {
      if (n.name.starts_with("node")) nodes.push_back(n.name.substr(4));
    }
    v.ears = make_pocketsphinx_recognizer(recognizer_options(speech_corpus(base, tasks.command_forms(), {{"node", nodes}})));
    v.visitor = make_espeak_synthesizer({"en-us+klatt", 170});
  } catch (const std::exception& e) {
    v = Voice{};
    v.off_reason = std::string("off: ") + e.what();
  }
  return v;
}

std::string in_quotes(std::string_view s) { return "\"" + std::string(s) + "\""; }

}  // namespace

VisitResult run_visit(const VisitOptions& o) {
  if (o.visit.empty() && !o.monitor && o.audio_device.empty()) {
    throw std::invalid_argument("run_visit: without a visit file there must be a monitor to serve or live audio");
  }
  Visit visit;
  if (!o.visit.empty()) {
    visit = load_visit(o.visit);
  } else {
    visit.name = "the monitor's visitors";
    visit.max_duration_s = o.max_duration_s;
  }
  // A bad monitor address or token file is refused before anything is built.
  std::optional<monitor::MonitorServerOptions> server_options;
  if (o.monitor) {
    server_options = monitor::server_options(*o.monitor, o.monitor_token_file);
    server_options->read_without_token = o.monitor_read_open;
    server_options->allowed_hosts = o.monitor_allowed_hosts;
    server_options->allowed_origins = o.monitor_allowed_origins;
  }
  const RobotProfile profile = load_robot_profile(o.robot);
  auto world = std::make_shared<sim::World>(sim::load_world(o.world));
  if (o.visitors_give_way_m) {
    for (sim::Visitor& v : world->visitors) v.give_way_m = *o.visitors_give_way_m;
  }
  if (!profile.hardware || profile.hardware->type != "sim") {
    throw ConfigError(profile.hardware ? profile.hardware->where : profile.where,
                      "`tripodal run --visit` runs the robot on the simulator: its profile needs hardware: {type: sim}");
  }
  VisitResult res;
  res.visit = visit.name.empty() ? o.visit.filename().string() : visit.name;
  res.seed = o.seed.value_or(world->seed);

  RobotPlugins plugins;
  register_tool_plugins(plugins, world, profile, o.plugins);
  RobotOptions ro;
  ro.parameters = simulation_overrides(profile, *world, res.seed);
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock, ro);
  auto& hw = dynamic_cast<sim::SimHardware&>(*robot->hardware());
  const sim::Simulator& sim = hw.simulator();
  CHri* const hri_module = robot->module<CHri>();
  if (hri_module == nullptr) throw ConfigError(profile.where, "`tripodal run --visit` needs the robot's HRI: hri: [{name, type: Hri, ...}]");
  if (profile.tasks.empty()) throw ConfigError(profile.where, "`tripodal run --visit` needs the robot's tasks (tasks: FILE)");
  if (CController* c = robot->behavior_loop().controller()) c->reset_odometry(world->start_pose);

  // The HRI on the robot (GuideHri): the RKMS of its Hri module, its task templates, answers from
  // local providers (the hall has no internet), commands to the robot's planner. The same object
  // answers the visit's requests and the monitor's touch page.
  std::string voice_off;
  std::unique_ptr<SpeechSynthesizer> robot_voice = make_robot_voice(o.voice, voice_off);
  const bool robot_speaks = robot_voice != nullptr;
  GuideHri guide(*robot, *hri_module, clock, profile.tasks,
                 GuideHri::Options{[&sim] { return sim.battery_charge(); }, std::move(robot_voice)});
  Voice voice = robot_speaks ? make_voice(hri_module->knowledge_store().base(), guide.tasks(), world->regions) : Voice{{}, {}, voice_off};
  res.voice = voice.ears != nullptr;
  const std::unique_ptr<VisitAudio> live = open_visit_audio(o, guide.module(), voice.ears.get(), guide.service().voice());

  LifecycleRecorder life(false);
  robot->planner().add_observer(life);
  robot->supervisor().add_observer(life);

  // The monitor (--monitor): its own thread serves the clients; this loop hands it the robot's
  // state and the operator's and visitors' requests between periods, paced to real time.
  std::unique_ptr<monitor::MonitorServer> server;
  std::unique_ptr<monitor::RobotMonitor> watch;
  SteadyClock wall;
  std::optional<sim::RealtimePacer> pacer;
  if (server_options) {
    server = std::make_unique<monitor::MonitorServer>(std::move(*server_options));
    watch = std::make_unique<monitor::RobotMonitor>(*robot, clock, *server, monitor::RobotMonitorOptions{.start_paused = o.start_paused});
    watch->set_hri(&guide.service());
    server->start();
    pacer.emplace(wall, o.realtime_speed);
  }
  auto stopped = [&] { return o.stop != nullptr && *o.stop != 0; };

  std::ostream* log = o.log;
  std::ostringstream dialogue;
  auto say = [&](const std::string& line) {
    const std::string text = std::string(9 - std::min<std::size_t>(9, fixed(to_seconds(clock.now()), 1).size()), ' ') +
                             fixed(to_seconds(clock.now()), 1) + " s  " + line + "\n";
    dialogue << text;
    if (log != nullptr) {
      *log << text;
      log->flush();
    }
  };
  std::size_t printed = 0;
  auto flush_life = [&] {
    for (; printed < life.entries().size(); ++printed) {
      const LifecycleEntry& e = life.entries()[printed];
      const std::string text = std::string(9 - std::min<std::size_t>(9, fixed(to_seconds(e.time), 1).size()), ' ') +
                               fixed(to_seconds(e.time), 1) + " s  " + e.text + "\n";
      dialogue << text;
      if (log != nullptr) *log << text;
    }
  };
  std::filesystem::path audio_dir;
  if (!o.out.empty()) {
    audio_dir = o.out / "audio";
    std::filesystem::create_directories(audio_dir);
  }
  if (server) say("monitor: " + server->url() + "  (token " + server->token() + (o.start_paused ? "; paused until resumed" : "") +
                  "; RKMS at /rkms, touch screen at /touch)");
  say(std::string("voice ") + (res.voice ? "on: requests spoken by espeak-ng and heard by pocketsphinx, answers synthesised" : voice.off_reason) +
      (res.voice && audio_dir.empty() ? " (no --out: answers not written)" : ""));
  std::size_t clip = 0;
  auto speak = [&](const std::string& text) -> std::string {
    SpeechSynthesizer* robot_voice_now = guide.service().voice();
    if (!res.voice || robot_voice_now == nullptr || audio_dir.empty() || text.empty()) return {};
    char name[32];
    std::snprintf(name, sizeof name, "answer_%02zu.wav", ++clip);
    write_wav(audio_dir / name, robot_voice_now->synthesize(text));
    return (std::filesystem::path("audio") / name).string();
  };
  // The last exchange the HRI displays that this loop knows of: another one came from the touch page.
  std::optional<HriExchange> seen;
  auto record = [&](VisitExchange& x, const HriReply& r) {
    x.reply_kind = std::string(to_string(r.kind));
    x.entry = r.entry_id;
    // The task the planner started for this input (an entry's action too), or the one it refused.
    const std::string started = guide.take_started_task();
    x.task = !started.empty() ? started : r.task;
    x.reply = r.text;
    x.wav = speak(r.text);
    seen = guide.service().display().last;
    say("Jinny [" + x.reply_kind + (x.entry.empty() ? "" : " " + x.entry) + (x.task.empty() ? "" : ", task " + x.task) + "]: " + r.text +
        (x.wav.empty() ? "" : "  (" + x.wav + ")"));
  };
  auto check = [&](const VisitStep& s, VisitExchange& x) {
    std::string m;
    if (!s.expect_outcome.empty() && s.expect_outcome != x.reply_kind) m += "outcome " + x.reply_kind + ", expected " + s.expect_outcome + "; ";
    if (!s.expect_entry.empty() && s.expect_entry != x.entry) m += "entry '" + x.entry + "', expected '" + s.expect_entry + "'; ";
    if (!s.expect_task.empty() && s.expect_task != x.task) m += "task '" + x.task + "', expected '" + s.expect_task + "'; ";
    if (!s.expect_task_end.empty() && s.expect_task_end != x.task_end) m += "task end '" + x.task_end + "', expected '" + s.expect_task_end + "'; ";
    x.as_expected = m.empty();
    x.mismatch = m;
  };

  // The display shows the internal state when it changes; the joints are shown where they stop;
  // the HRI speaks the explanation of an exhibit when PrExplain starts.
  std::optional<InternalState> shown;
  std::vector<double> joints_shown;
  for (const sim::JointState& j : sim.joints()) joints_shown.push_back(j.position_rad);
  auto display = [&] {
    for (const HriReply& r : guide.update()) {
      const std::string wav = speak(r.text);
      seen = guide.service().display().last;
      say("Jinny [explaining" + (r.entry_id.empty() ? std::string() : " " + r.entry_id) + "]: " + r.text + (wav.empty() ? "" : "  (" + wav + ")"));
    }
    if (!shown || *shown != guide.state()) {
      shown = guide.state();
      say("display: " + display_text(guide.state()));
    }
    for (std::size_t i = 0; i < sim.joints().size(); ++i) {
      const sim::JointState& j = sim.joints()[i];
      if (j.velocity_rad_s != 0.0 || j.position_rad == joints_shown[i]) continue;
      joints_shown[i] = j.position_rad;
      say("gesture: " + world->robot.joints[i].name + " at " + fixed(j.position_rad * 180.0 / std::numbers::pi, 0) + " deg");
    }
  };
  // Between periods: the monitor's requests (an input typed on the touch page is answered there
  // and shown here), then its topics.
  auto monitor_update = [&] {
    if (!watch) return;
    watch->update(monitor::MonitorExtras{.true_pose = sim.pose()});
    const std::optional<HriExchange> last = guide.service().display().last;
    if (last && last != seen) {
      seen = last;
      const std::string started = guide.take_started_task();
      say("touch screen: " + in_quotes(last->input) + " -> Jinny [" + std::string(to_string(last->kind)) +
          (last->entry.empty() ? "" : " " + last->entry) + (started.empty() ? "" : ", task " + started) + "]: " + last->reply);
    }
  };

  robot->run_until(clock.now());
  const Duration period = std::chrono::milliseconds(50);
  const Time deadline = time_from_seconds(visit.max_duration_s);
  std::size_t next = 0;
  Time ready_at = clock.now();
  // The exchange whose task is running (a plain index: GCC 12 sees an optional here as maybe unset).
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t waiting = kNone;
  std::size_t pending_button = 0;      // button presses on their way to the HRI
  std::vector<char> giving_way(sim.visitors().size(), 0);
  display();
  while (clock.now() < deadline && !stopped()) {
    monitor_update();
    if (watch && watch->paused()) {
      wall.sleep_until(wall.now() + std::chrono::milliseconds(20));
      pacer.emplace(wall, o.realtime_speed);  // no catching up after a pause
      continue;
    }
    // The task of the last request ended: its outcome, and the next step's time.
    if (waiting != kNone && !robot->planner().busy() && !guide.last_task_end().empty()) {
      VisitExchange& x = res.exchanges[waiting];
      x.task_end = guide.last_task_end();
      for (std::size_t i = 0; i < sim.visitors().size(); ++i) {
        if (!world->visitors[i].follow_robot) continue;
        const navi::Point2D p = sim.visitors()[i].position;
        x.follower_distance_m = std::hypot(p.x_m - sim.pose().x_m, p.y_m - sim.pose().y_m);
        say(world->visitors[i].name + ", following Jinny, stands " + fixed(x.follower_distance_m, 2) + " m from it");
      }
      check(visit.steps[x.step], x);
      waiting = kNone;
      ready_at = clock.now() + from_seconds(visit.steps[next - 1].after_s);
    }
    for (const std::string& b : hri_module->take_presses()) {
      VisitExchange x;
      x.step = next - 1;
      x.time_s = to_seconds(clock.now());
      x.kind = "button";
      x.request = b;
      say("visitor presses the LED button " + in_quotes(b) + " (event button." + b + ")");
      (void)guide.take_started_task();
      guide.clear_task_end();
      record(x, guide.module().handle_button(b));
      res.exchanges.push_back(x);
      if (pending_button > 0) --pending_button;
      if (next == 0) continue;  // pressed on the simulator, not by the visit
      const VisitStep& s = visit.steps[next - 1];
      check(s, res.exchanges.back());
      if (!x.task.empty()) waiting = res.exchanges.size() - 1;
      else ready_at = clock.now() + from_seconds(s.after_s);
    }
    const bool idle = waiting == kNone && pending_button == 0;
    if (idle && next < visit.steps.size()) {
      const VisitStep& s = visit.steps[next];
      const Time at = s.at_s ? std::max(ready_at, time_from_seconds(*s.at_s)) : ready_at;
      if (clock.now() >= at) {
        ++next;
        (void)guide.take_started_task();
        guide.clear_task_end();
        if (s.kind == VisitStep::Kind::button) {
          if (hw.simulator().press_button(s.text)) {
            ++pending_button;
          } else {
            say("visitor presses " + in_quotes(s.text) + ": the robot has no such button");
            ready_at = clock.now() + from_seconds(s.after_s);
          }
        } else {
          VisitExchange x;
          x.step = next - 1;
          x.time_s = to_seconds(clock.now());
          x.kind = std::string(to_string(s.kind));
          x.request = s.text;
          HriReply r;
          if (s.kind == VisitStep::Kind::spoken && res.voice) {
            const AudioClip audio = voice.visitor->synthesize(s.text);
            const SpeechRecognizer::Result heard = voice.ears->recognize(resample(audio, voice.ears->sample_rate_hz()));
            x.heard = heard.words;
            say("visitor (spoken): " + in_quotes(s.text) + "  heard: " + in_quotes(heard.words));
            r = guide.module().handle_heard(heard);
          } else {
            say(std::string("visitor (") + (s.kind == VisitStep::Kind::spoken ? "spoken, voice off: read as typed" : "typed") +
                "): " + in_quotes(s.text));
            r = guide.module().handle(s.text);
          }
          record(x, r);
          res.exchanges.push_back(x);
          check(s, res.exchanges.back());
          if (robot->planner().busy()) waiting = res.exchanges.size() - 1;
          else ready_at = clock.now() + from_seconds(s.after_s);
        }
      }
    }
    if (next >= visit.steps.size() && waiting == kNone && pending_button == 0 && !robot->planner().busy() &&
        (live == nullptr || !o.visit.empty())) {
      // The visit is over; a monitored robot goes on serving its pages until stopped.
      if (!res.completed && !o.visit.empty()) say("the visit is over" + std::string(watch ? "; the monitor goes on serving until stopped" : ""));
      res.completed = true;
      if (!watch) break;
    }
    robot->run_for(period);
    if (live) live->step(to_seconds(period), say, res.exchanges, to_seconds(clock.now()));
    bool visitor_near = false;
    for (std::size_t i = 0; i < sim.visitors().size(); ++i) {
      const navi::Point2D v = sim.visitors()[i].position;
      visitor_near = visitor_near || std::hypot(v.x_m - sim.pose().x_m, v.y_m - sim.pose().y_m) < 1.2;
      const bool waits = sim.visitors()[i].giving_way;
      if (waits && giving_way[i] == 0) ++res.visitor_waits;
      giving_way[i] = waits ? 1 : 0;
    }
    if (visitor_near && robot->behavior_active("BhAutoMove") && std::hypot(sim.velocity().vx_m_s, sim.velocity().vy_m_s) < 0.02 &&
        std::abs(sim.velocity().wz_rad_s) < 0.05) {
      res.robot_waited_s += to_seconds(period);
    }
    flush_life();
    display();
    if (pacer) pacer->pace(clock.now());
  }
  monitor_update();
  res.stopped_by = stop_reason(stop_signal(o.stop));
  if (robot->planner().busy()) {
    robot->planner().cancel(!res.stopped_by.empty() ? res.stopped_by : "the visit did not end within " + fixed(visit.max_duration_s, 0) + " s");
    robot->step_sequencing();
  }
  // Whatever ended the run, the base is left at rest before the devices close.
  const BaseStop rest =
      stop_base(*robot, [&sim] { return std::vector<double>(sim.wheel_commands().begin(), sim.wheel_commands().end()); }, period);
  res.base_command_at_end_rad_s = rest.command_rad_s;
  res.base_at_rest = rest.at_rest;
  flush_life();
  for (const sim::SimEvent& e : sim.events()) {
    if (e.kind == sim::SimEvent::Kind::collision) say("simulator: collision " + e.detail + " at " + fixed(to_seconds(e.stamp), 1) + " s");
  }
  res.duration_s = to_seconds(clock.now());
  res.distance_m = sim.distance_m();
  res.collisions = sim.collisions();
  res.visitor_collisions = sim.visitor_collisions();
  res.min_visitor_clearance_m = sim.min_visitor_clearance_m();
  res.processes = guide.processes();
  for (const VisitExchange& x : res.exchanges) res.mismatches += x.as_expected ? 0 : 1;
  if (!res.completed) say(stopped() ? "the run was " + res.stopped_by : "the visit did not end within " + fixed(visit.max_duration_s, 0) + " s");
  if (!o.out.empty()) {
    write_text(o.out / "dialogue.txt", dialogue.str());
    write_text(o.out / "report.json", res.json());
  }
  return res;
}

std::string VisitResult::json() const {
  using Json = nlohmann::ordered_json;
  Json j;
  j["visit"] = visit;
  j["seed"] = seed;
  j["voice"] = voice;
  j["completed"] = completed;
  j["stopped_by"] = stopped_by;
  j["duration_s"] = std::round(duration_s * 10.0) / 10.0;
  j["distance_m"] = std::round(distance_m * 100.0) / 100.0;
  j["collisions"] = collisions;
  j["visitor_collisions"] = visitor_collisions;
  j["min_visitor_clearance_m"] = std::isfinite(min_visitor_clearance_m) ? Json(std::round(min_visitor_clearance_m * 1000.0) / 1000.0) : Json();
  j["visitor_waits"] = visitor_waits;
  j["robot_waited_s"] = std::round(robot_waited_s * 100.0) / 100.0;
  j["mismatches"] = mismatches;
  Json xs = Json::array();
  for (const VisitExchange& x : exchanges) {
    xs.push_back({{"time_s", std::round(x.time_s * 10.0) / 10.0}, {"kind", x.kind}, {"request", x.request}, {"heard", x.heard},
                  {"reply_kind", x.reply_kind}, {"entry", x.entry}, {"task", x.task}, {"task_end", x.task_end}, {"reply", x.reply},
                  {"wav", x.wav}, {"follower_distance_m", std::round(x.follower_distance_m * 100.0) / 100.0},
                  {"as_expected", x.as_expected}, {"mismatch", x.mismatch}});
  }
  j["dialogue"] = xs;
  j["processes"] = processes;
  j["base_at_rest"] = base_at_rest;
  j["base_command_at_end_rad_s"] = base_command_at_end_rad_s;
  return j.dump(2) + "\n";
}

}  // namespace tripodal::app
