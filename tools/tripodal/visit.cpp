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
#include "tripodal/behaviors/gesture_behaviors.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/hri/answer_providers.hpp"
#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/speech.hpp"
#include "tripodal/planner/lifecycle_recorder.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::app {

namespace {

// The HRI's knowledge of the hall: the planner's functions as the robot's Hri module answers them
// from where the robot stands now.
class HallKnowledge final : public TaskKnowledge {
 public:
  HallKnowledge(const CHri& hri, Robot& robot) : hri_(hri), robot_(robot) {}
  [[nodiscard]] ListResult list(std::string_view function, std::string_view argument) const override {
    const auto a = hri_.answer(function, argument, robot_.navigation());
    if (!a) return {false, {}, "I know nothing of " + std::string(function) + "()"};
    return {a->ok, a->items, a->error};
  }

 private:
  const CHri& hri_;
  Robot& robot_;
};

// The words of the task's first command form with the slots the HRI understood: what the robot's
// planner is told ("guide me to node 1").
std::string command_text(const TaskLibrary& tasks, const Understanding& u) {
  for (const TaskTemplate& t : tasks.templates()) {
    if (t.name != u.task || t.commands.empty()) continue;
    std::string out;
    for (const PatternToken& tok : t.commands.front().tokens) {
      if (tok.kind == PatternToken::Kind::optional_word) continue;
      std::string word = tok.text;
      if (tok.kind != PatternToken::Kind::word) {
        const auto it = u.slots.find(tok.text);
        word = it != u.slots.end() ? it->second : std::string();
      }
      if (!word.empty()) out += (out.empty() ? "" : " ") + word;
    }
    return out;
  }
  return u.task;
}

std::string step_text(const ProcessStep& s) {
  std::string out = s.process + "(";
  for (std::size_t i = 0; i < s.params.size(); ++i) out += (i ? ", " : "") + s.params[i].name + "=" + s.params[i].value;
  return out + ")";
}

// Keeps the internal state the HRI displays, and the explanations PrExplain asks for.
class StateObserver final : public TaskObserver {
 public:
  InternalState state;
  std::deque<std::string> explain;  // topics of PrExplain runs started, for the HRI to speak
  std::vector<std::string> processes;
  std::string last_task_end;

  void on_task_started(const TaskReport& task, const Plan& /*plan*/, Time /*now*/) override {
    state = {task.task, "running", "", ""};
    last_task_end.clear();
  }
  void on_process_started(const ProcessRecord& p) override {
    state.process = step_text(p.step);
    if (p.step.process == "PrExplain") {
      for (const BindingParam& b : p.step.params) {
        if (b.name == "topic") explain.push_back(b.value);
      }
    }
  }
  void on_process_succeeded(const ProcessRecord& p) override { finished(p, "succeeded"); }
  void on_process_failed(const ProcessRecord& p) override {
    state.fault = p.message;
    finished(p, "failed: " + p.message);
  }
  void on_task_succeeded(const TaskReport& /*task*/) override { ended("succeeded"); }
  void on_task_failed(const TaskReport& task) override {
    if (!task.reason.empty()) state.fault = task.reason;
    ended("failed");
  }

 private:
  void finished(const ProcessRecord& p, const std::string& how) {
    processes.push_back(fixed(to_seconds(p.started), 3) + "-" + fixed(to_seconds(p.finished.value_or(p.started)), 3) + " " + p.run +
                        " " + step_text(p.step) + " " + how);
    state.process.clear();
  }
  void ended(const std::string& how) {
    state.task_state = how;
    state.process.clear();
    last_task_end = how;
  }
};

// The voices: the visitor's (espeak-ng klatt, which pocketsphinx hears best, docs/hri.md), the
// robot's (espeak-ng en-us) and the recognizer with a language model of what the robot knows.
struct Voice {
  std::unique_ptr<SpeechSynthesizer> visitor, robot;
  std::unique_ptr<SpeechRecognizer> ears;
  std::string off_reason;
};

Voice make_voice(bool wanted, const KnowledgeBase& base, const TaskLibrary& tasks, const navi::RegionMap& regions) {
  Voice v;
  if (!wanted) {
    v.off_reason = "off (--no-voice)";
    return v;
  }
  if (!voice_available()) {
    v.off_reason = "off: this build has no espeak-ng and pocketsphinx (TRIPODAL_VOICE)";
    return v;
  }
  try {
    std::vector<std::string> nodes;
    for (const navi::MapNode& n : regions.nodes) {
      if (n.name.starts_with("node")) nodes.push_back(n.name.substr(4));
    }
    const PocketsphinxOptions defaults;
    const std::vector<std::string> dict = pocketsphinx_dictionary_words(defaults.model_dir);
    PocketsphinxOptions options;
    options.language_model = arpa_bigram_model(speech_corpus(base, tasks.command_forms(), {{"node", nodes}}),
                                               [&](std::string_view w) { return std::binary_search(dict.begin(), dict.end(), w); });
    v.ears = make_pocketsphinx_recognizer(options);
    v.visitor = make_espeak_synthesizer({"en-us+klatt", 170});
    v.robot = make_espeak_synthesizer();
  } catch (const std::exception& e) {
    v = Voice{};
    v.off_reason = std::string("off: ") + e.what();
  }
  return v;
}

std::string in_quotes(std::string_view s) { return "\"" + std::string(s) + "\""; }

}  // namespace

VisitResult run_visit(const VisitOptions& o) {
  const Visit visit = load_visit(o.visit);
  const RobotProfile profile = load_robot_profile(o.robot);
  auto world = std::make_shared<sim::World>(sim::load_world(o.world));
  if (!profile.hardware || profile.hardware->type != "sim") {
    throw ConfigError(profile.hardware ? profile.hardware->where : profile.where,
                      "`tripodal run --visit` runs the robot on the simulator: its profile needs hardware: {type: sim}");
  }
  VisitResult res;
  res.visit = visit.name.empty() ? o.visit.filename().string() : visit.name;
  res.seed = o.seed.value_or(world->seed);

  RobotPlugins plugins = RobotPlugins::with_builtins();
  sim::register_sim_hardware(plugins.hardware, world);
  register_gesture_behaviors(plugins.behaviors);
  register_guide_modules(plugins.modules);
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

  // The HRI on the robot: the RKMS of its Hri module, its task templates, answers from local
  // providers (the hall has no internet), commands to the robot's planner.
  const TaskLibrary tasks = TaskLibrary::load(profile.tasks);
  const HallKnowledge hall(*hri_module, *robot);
  AnswerProviders providers;
  providers.add("time", std::make_unique<ClockTimeProvider>(clock, std::chrono::hours(14)));
  providers.add("battery", std::make_unique<BatteryProvider>([&sim] { return sim.battery_charge(); }));
  providers.add("weather", std::make_unique<WeatherTableProvider>(
                               clock, std::chrono::hours(14), std::vector<std::string>{"sunny and mild, 22 degrees", "cloudy, 18 degrees"}));
  std::string started_task;
  const TaskStarter starter = [&](const Understanding& u) -> std::string {
    const CommandAnswer a = robot->command(command_text(tasks, u));
    if (a.accepted) started_task = u.task;
    return a.accepted ? std::string() : a.text;
  };
  HriOptions hri_options;
  hri_options.buttons = hri_module->buttons();
  HriModule hri(hri_module->knowledge(), tasks, hall, providers, starter, hri_options);
  Voice voice = make_voice(o.voice, hri_module->knowledge(), tasks, world->regions);
  res.voice = voice.ears != nullptr;

  LifecycleRecorder life(false);
  StateObserver observer;
  robot->planner().add_observer(life);
  robot->supervisor().add_observer(life);
  robot->planner().add_observer(observer);

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
  say(std::string("voice ") + (res.voice ? "on: requests spoken by espeak-ng and heard by pocketsphinx, answers synthesised" : voice.off_reason) +
      (res.voice && audio_dir.empty() ? " (no --out: answers not written)" : ""));
  std::size_t clip = 0;
  auto speak = [&](const std::string& text) -> std::string {
    if (!res.voice || audio_dir.empty() || text.empty()) return {};
    char name[32];
    std::snprintf(name, sizeof name, "answer_%02zu.wav", ++clip);
    write_wav(audio_dir / name, voice.robot->synthesize(text));
    return (std::filesystem::path("audio") / name).string();
  };
  auto record = [&](VisitExchange& x, const HriReply& r) {
    x.reply_kind = std::string(to_string(r.kind));
    x.entry = r.entry_id;
    // The task the planner started for this input (an entry's action too), or the one it refused.
    x.task = !started_task.empty() ? started_task : r.task;
    x.reply = r.text;
    x.wav = speak(r.text);
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

  // The display shows the internal state when it changes; the joints are shown where they stop.
  std::optional<InternalState> shown;
  std::vector<double> joints_shown;
  for (const sim::JointState& j : sim.joints()) joints_shown.push_back(j.position_rad);
  auto display = [&] {
    hri.set_internal_state(observer.state);
    if (!shown || *shown != hri.internal_state()) {
      shown = hri.internal_state();
      say("display: " + hri.status());
    }
    for (std::size_t i = 0; i < sim.joints().size(); ++i) {
      const sim::JointState& j = sim.joints()[i];
      if (j.velocity_rad_s != 0.0 || j.position_rad == joints_shown[i]) continue;
      joints_shown[i] = j.position_rad;
      say("gesture: " + world->robot.joints[i].name + " at " + fixed(j.position_rad * 180.0 / std::numbers::pi, 0) + " deg");
    }
  };

  robot->run_until(clock.now());
  const Duration period = std::chrono::milliseconds(50);
  const Time deadline = time_from_seconds(visit.max_duration_s);
  std::size_t next = 0;
  Time ready_at = clock.now();
  std::optional<std::size_t> waiting;  // the exchange whose task is running
  std::size_t pending_button = 0;      // button presses on their way to the HRI
  std::vector<char> giving_way(sim.visitors().size(), 0);
  display();
  while (clock.now() < deadline) {
    // The task of the last request ended: its outcome, and the next step's time.
    if (waiting && !robot->planner().busy() && !observer.last_task_end.empty()) {
      VisitExchange& x = res.exchanges[*waiting];
      x.task_end = observer.last_task_end;
      for (std::size_t i = 0; i < sim.visitors().size(); ++i) {
        if (!world->visitors[i].follow_robot) continue;
        const navi::Point2D p = sim.visitors()[i].position;
        x.follower_distance_m = std::hypot(p.x_m - sim.pose().x_m, p.y_m - sim.pose().y_m);
        say(world->visitors[i].name + ", following Jinny, stands " + fixed(x.follower_distance_m, 2) + " m from it");
      }
      check(visit.steps[x.step], x);
      waiting.reset();
      ready_at = clock.now() + from_seconds(visit.steps[next - 1].after_s);
    }
    // The HRI speaks the explanation of an exhibit when PrExplain starts.
    while (!observer.explain.empty()) {
      const HriReply r = hri.handle(observer.explain.front());
      observer.explain.pop_front();
      const std::string wav = speak(r.text);
      say("Jinny [explaining" + (r.entry_id.empty() ? std::string() : " " + r.entry_id) + "]: " + r.text + (wav.empty() ? "" : "  (" + wav + ")"));
    }
    for (const std::string& b : hri_module->take_presses()) {
      VisitExchange x;
      x.step = next - 1;
      x.time_s = to_seconds(clock.now());
      x.kind = "button";
      x.request = b;
      say("visitor presses the LED button " + in_quotes(b) + " (event button." + b + ")");
      started_task.clear();
      observer.last_task_end.clear();
      record(x, hri.handle_button(b));
      res.exchanges.push_back(x);
      if (pending_button > 0) --pending_button;
      const VisitStep& s = visit.steps[next - 1];
      check(s, res.exchanges.back());
      if (!x.task.empty()) waiting = res.exchanges.size() - 1;
      else ready_at = clock.now() + from_seconds(s.after_s);
    }
    const bool idle = !waiting && pending_button == 0;
    if (idle && next < visit.steps.size()) {
      const VisitStep& s = visit.steps[next];
      const Time at = s.at_s ? std::max(ready_at, time_from_seconds(*s.at_s)) : ready_at;
      if (clock.now() >= at) {
        ++next;
        started_task.clear();
        observer.last_task_end.clear();
        if (s.kind == VisitStep::Kind::button) {
          if (hri_module->simulator() != nullptr && hri_module->simulator()->press_button(s.text)) {
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
            r = hri.handle_heard(heard);
          } else {
            say(std::string("visitor (") + (s.kind == VisitStep::Kind::spoken ? "spoken, voice off: read as typed" : "typed") +
                "): " + in_quotes(s.text));
            r = hri.handle(s.text);
          }
          record(x, r);
          res.exchanges.push_back(x);
          check(s, res.exchanges.back());
          if (robot->planner().busy()) waiting = res.exchanges.size() - 1;
          else ready_at = clock.now() + from_seconds(s.after_s);
        }
      }
    }
    if (next >= visit.steps.size() && !waiting && pending_button == 0 && !robot->planner().busy()) {
      res.completed = true;
      break;
    }
    robot->run_for(period);
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
  }
  flush_life();
  for (const sim::SimEvent& e : sim.events()) {
    if (e.kind == sim::SimEvent::Kind::collision) say("simulator: collision " + e.detail + " at " + fixed(to_seconds(e.stamp), 1) + " s");
  }
  res.duration_s = to_seconds(clock.now());
  res.distance_m = sim.distance_m();
  res.collisions = sim.collisions();
  res.visitor_collisions = sim.visitor_collisions();
  res.min_visitor_clearance_m = sim.min_visitor_clearance_m();
  res.processes = observer.processes;
  for (const VisitExchange& x : res.exchanges) res.mismatches += x.as_expected ? 0 : 1;
  if (!res.completed) say("the visit did not end within " + fixed(visit.max_duration_s, 0) + " s");
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
  return j.dump(2) + "\n";
}

}  // namespace tripodal::app
