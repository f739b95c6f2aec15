// `tripodal run --visit`: Jinny's guided visit of the exhibit hall in the simulator (visit.hpp).
#include "visit.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <numbers>
#include <ostream>
#include <sstream>

#include "guide_hri.hpp"
#include "run_outputs.hpp"
#include "run_task.hpp"
#include "shutdown.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/speech.hpp"
#include "tripodal/monitor/robot_monitor.hpp"
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

// "   12.3 s  ": the time column of the dialogue.
std::string time_column(Time t) {
  const std::string s = fixed(to_seconds(t), 1);
  return std::string(9 - std::min<std::size_t>(9, s.size()), ' ') + s + " s  ";
}

// Whether an exchange went as the visit file expects (x.as_expected, x.mismatch).
void check_exchange(const VisitStep& s, VisitExchange& x) {
  std::string m;
  if (!s.expect_outcome.empty() && s.expect_outcome != x.reply_kind)
    m += "outcome " + x.reply_kind + ", expected " + s.expect_outcome + "; ";
  if (!s.expect_entry.empty() && s.expect_entry != x.entry) m += "entry '" + x.entry + "', expected '" + s.expect_entry + "'; ";
  if (!s.expect_task.empty() && s.expect_task != x.task) m += "task '" + x.task + "', expected '" + s.expect_task + "'; ";
  if (!s.expect_task_end.empty() && s.expect_task_end != x.task_end)
    m += "task end '" + x.task_end + "', expected '" + s.expect_task_end + "'; ";
  x.as_expected = m.empty();
  x.mismatch = m;
}

// The robot's HRI module, which the visit talks to; the robot needs its tasks too.
CHri& checked_hri(Robot& robot, const RobotProfile& profile) {
  CHri* const hri_module = robot.module<CHri>();
  if (hri_module == nullptr)
    throw ConfigError(profile.where, "`tripodal run --visit` needs the robot's HRI: hri: [{name, type: Hri, ...}]");
  if (profile.tasks.empty()) throw ConfigError(profile.where, "`tripodal run --visit` needs the robot's tasks (tasks: FILE)");
  return *hri_module;
}

// One guided visit: Jinny on the simulator, its HRI, the visitors' steps in turn, the dialogue as
// it goes. run_visit drives it: start, drive, finish.
class GuidedVisit {
 public:
  GuidedVisit(const VisitOptions& o, const Visit& visit, const RobotProfile& profile, const std::shared_ptr<sim::World>& world,
              std::optional<monitor::MonitorServerOptions> server_options, VisitResult& res)
      : o_(o),
        visit_(visit),
        world_(*world),
        res_(res),
        plugins_(tool_plugins(o, profile, world)),
        robot_(Robot::assemble(profile, plugins_, clock_, robot_options(profile, *world, res.seed))),
        hw_(dynamic_cast<sim::SimHardware&>(*robot_->hardware())),
        sim_(hw_.simulator()),
        hri_module_(checked_hri(*robot_, profile)),
        giving_way_(sim_.visitors().size(), 0) {
    if (CController* c = robot_->behavior_loop().controller()) c->reset_odometry(world->start_pose);
    make_guide(profile);
    robot_->planner().add_observer(life_);
    robot_->supervisor().add_observer(life_);
    // The monitor (--monitor): its own thread serves the clients; this loop hands it the robot's
    // state and the operator's and visitors' requests between periods, paced to real time.
    if (server_options) {
      server_ = std::make_unique<monitor::MonitorServer>(std::move(*server_options));
      watch_ = std::make_unique<monitor::RobotMonitor>(*robot_, clock_, *server_,
                                                       monitor::RobotMonitorOptions{.start_paused = o.start_paused});
      watch_->set_hri(&guide_->service());
      server_->start();
      pacer_.emplace(wall_, o.realtime_speed);
    }
  }

  void start();
  void drive();
  void finish();

 private:
  static RobotPlugins tool_plugins(const VisitOptions& o, const RobotProfile& profile, const std::shared_ptr<sim::World>& world) {
    RobotPlugins plugins;
    register_tool_plugins(plugins, world, profile, o.plugins);
    return plugins;
  }
  static RobotOptions robot_options(const RobotProfile& profile, const sim::World& world, std::uint64_t seed) {
    RobotOptions ro;
    ro.parameters = simulation_overrides(profile, world, seed);
    return ro;
  }
  [[nodiscard]] bool stopped() const { return o_.stop != nullptr && *o_.stop != 0; }
  [[nodiscard]] bool idle() const { return waiting_ == kNone && pending_button_ == 0; }

  void make_guide(const RobotProfile& profile);
  void say(const std::string& line);
  void flush_life();
  std::string speak(const std::string& text);
  void record(VisitExchange& x, const HriReply& r);
  void display();
  void monitor_update();
  void end_waiting_task();
  void take_presses();
  void next_step();
  void ask(const VisitStep& s);
  void watch_visitors();

  // The exchange whose task is running (a plain index: GCC 12 sees an optional here as maybe unset).
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  static constexpr Duration kPeriod = std::chrono::milliseconds(50);

  const VisitOptions& o_;
  const Visit& visit_;
  const sim::World& world_;
  VisitResult& res_;
  RobotPlugins plugins_;
  SimClock clock_;
  std::unique_ptr<Robot> robot_;
  sim::SimHardware& hw_;
  const sim::Simulator& sim_;
  CHri& hri_module_;
  std::unique_ptr<GuideHri> guide_;
  Voice voice_;
  std::unique_ptr<VisitAudio> live_;  // --audio DEVICE: the room heard and answered live
  LifecycleRecorder life_{false};
  std::unique_ptr<monitor::MonitorServer> server_;
  std::unique_ptr<monitor::RobotMonitor> watch_;
  SteadyClock wall_;
  std::optional<sim::RealtimePacer> pacer_;
  std::ostringstream dialogue_;
  std::size_t printed_ = 0;
  std::filesystem::path audio_dir_;
  std::size_t clip_ = 0;
  // The last exchange the HRI displays that this loop knows of: another one came from the touch page.
  std::optional<HriExchange> seen_;
  // The display shows the internal state when it changes; the joints are shown where they stop.
  std::optional<InternalState> shown_;
  std::vector<double> joints_shown_;
  std::size_t next_ = 0;
  Time ready_at_{};
  std::size_t waiting_ = kNone;
  std::size_t pending_button_ = 0;  // button presses on their way to the HRI
  std::vector<char> giving_way_;
};

// The HRI on the robot (GuideHri): the RKMS of its Hri module, its task templates, answers from
// local providers (the hall has no internet), commands to the robot's planner. The same object
// answers the visit's requests and the monitor's touch page.
void GuidedVisit::make_guide(const RobotProfile& profile) {
  std::string voice_off;
  std::unique_ptr<SpeechSynthesizer> robot_voice = make_robot_voice(o_.voice, voice_off);
  const bool robot_speaks = robot_voice != nullptr;
  const sim::Simulator& sim = sim_;
  guide_ = std::make_unique<GuideHri>(*robot_, hri_module_, clock_, profile.tasks,
                                      GuideHri::Options{[&sim] { return sim.battery_charge(); }, std::move(robot_voice)});
  voice_ =
      robot_speaks ? make_voice(hri_module_.knowledge_store().base(), guide_->tasks(), world_.regions) : Voice{{}, {}, voice_off};
  res_.voice = voice_.ears != nullptr;
  live_ = open_visit_audio(o_, guide_->module(), voice_.ears.get(), guide_->service().voice());
}

void GuidedVisit::say(const std::string& line) {
  const std::string text = time_column(clock_.now()) + line + "\n";
  dialogue_ << text;
  if (o_.log != nullptr) {
    *o_.log << text;
    o_.log->flush();
  }
}

void GuidedVisit::flush_life() {
  for (; printed_ < life_.entries().size(); ++printed_) {
    const LifecycleEntry& e = life_.entries()[printed_];
    const std::string text = time_column(e.time) + e.text + "\n";
    dialogue_ << text;
    if (o_.log != nullptr) *o_.log << text;
  }
}

std::string GuidedVisit::speak(const std::string& text) {
  SpeechSynthesizer* robot_voice_now = guide_->service().voice();
  if (!res_.voice || robot_voice_now == nullptr || audio_dir_.empty() || text.empty()) return {};
  char name[32];
  std::snprintf(name, sizeof name, "answer_%02zu.wav", ++clip_);
  write_wav(audio_dir_ / name, robot_voice_now->synthesize(text));
  return (std::filesystem::path("audio") / name).string();
}

void GuidedVisit::record(VisitExchange& x, const HriReply& r) {
  x.reply_kind = std::string(to_string(r.kind));
  x.entry = r.entry_id;
  // The task the planner started for this input (an entry's action too), or the one it refused.
  const std::string started = guide_->take_started_task();
  x.task = !started.empty() ? started : r.task;
  x.reply = r.text;
  x.wav = speak(r.text);
  seen_ = guide_->service().display().last;
  say("Jinny [" + x.reply_kind + (x.entry.empty() ? "" : " " + x.entry) + (x.task.empty() ? "" : ", task " + x.task) +
      "]: " + r.text + (x.wav.empty() ? "" : "  (" + x.wav + ")"));
}

// The HRI speaks the explanation of an exhibit when PrExplain starts; the display shows the
// internal state when it changes; the joints are shown where they stop.
void GuidedVisit::display() {
  for (const HriReply& r : guide_->update()) {
    const std::string wav = speak(r.text);
    seen_ = guide_->service().display().last;
    say("Jinny [explaining" + (r.entry_id.empty() ? std::string() : " " + r.entry_id) + "]: " + r.text +
        (wav.empty() ? "" : "  (" + wav + ")"));
  }
  if (!shown_ || *shown_ != guide_->state()) {
    shown_ = guide_->state();
    say("display: " + display_text(guide_->state()));
  }
  for (std::size_t i = 0; i < sim_.joints().size(); ++i) {
    const sim::JointState& j = sim_.joints()[i];
    if (j.velocity_rad_s != 0.0 || j.position_rad == joints_shown_[i]) continue;
    joints_shown_[i] = j.position_rad;
    say("gesture: " + world_.robot.joints[i].name + " at " + fixed(j.position_rad * 180.0 / std::numbers::pi, 0) + " deg");
  }
}

// Between periods: the monitor's requests (an input typed on the touch page is answered there
// and shown here), then its topics.
void GuidedVisit::monitor_update() {
  if (!watch_) return;
  watch_->update(monitor::MonitorExtras{.true_pose = sim_.pose()});
  const std::optional<HriExchange> last = guide_->service().display().last;
  if (last && last != seen_) {
    seen_ = last;
    const std::string started = guide_->take_started_task();
    say("touch screen: " + in_quotes(last->input) + " -> Jinny [" + std::string(to_string(last->kind)) +
        (last->entry.empty() ? "" : " " + last->entry) + (started.empty() ? "" : ", task " + started) + "]: " + last->reply);
  }
}

void GuidedVisit::start() {
  for (const sim::JointState& j : sim_.joints()) joints_shown_.push_back(j.position_rad);
  if (!o_.out.empty()) {
    audio_dir_ = o_.out / "audio";
    std::filesystem::create_directories(audio_dir_);
  }
  if (server_)
    say("monitor: " + server_->url() + "  (token " + server_->token() + (o_.start_paused ? "; paused until resumed" : "") +
        "; RKMS at /rkms, touch screen at /touch)");
  say(std::string("voice ") +
      (res_.voice ? "on: requests spoken by espeak-ng and heard by pocketsphinx, answers synthesised" : voice_.off_reason) +
      (res_.voice && audio_dir_.empty() ? " (no --out: answers not written)" : ""));
  robot_->run_until(clock_.now());
  ready_at_ = clock_.now();
  display();
}

// The task of the last request ended: its outcome, and the next step's time.
void GuidedVisit::end_waiting_task() {
  if (waiting_ == kNone || robot_->planner().busy() || guide_->last_task_end().empty()) return;
  VisitExchange& x = res_.exchanges[waiting_];
  x.task_end = guide_->last_task_end();
  for (std::size_t i = 0; i < sim_.visitors().size(); ++i) {
    if (!world_.visitors[i].follow_robot) continue;
    const navi::Point2D p = sim_.visitors()[i].position;
    x.follower_distance_m = std::hypot(p.x_m - sim_.pose().x_m, p.y_m - sim_.pose().y_m);
    say(world_.visitors[i].name + ", following Jinny, stands " + fixed(x.follower_distance_m, 2) + " m from it");
  }
  check_exchange(visit_.steps[x.step], x);
  waiting_ = kNone;
  ready_at_ = clock_.now() + from_seconds(visit_.steps[next_ - 1].after_s);
}

// The LED buttons pressed on the simulator, each an exchange with the HRI.
void GuidedVisit::take_presses() {
  for (const std::string& b : hri_module_.take_presses()) {
    VisitExchange x;
    x.step = next_ - 1;
    x.time_s = to_seconds(clock_.now());
    x.kind = "button";
    x.request = b;
    say("visitor presses the LED button " + in_quotes(b) + " (event button." + b + ")");
    (void)guide_->take_started_task();
    guide_->clear_task_end();
    record(x, guide_->module().handle_button(b));
    res_.exchanges.push_back(x);
    if (pending_button_ > 0) --pending_button_;
    if (next_ == 0) continue;  // pressed on the simulator, not by the visit
    const VisitStep& s = visit_.steps[next_ - 1];
    check_exchange(s, res_.exchanges.back());
    if (!x.task.empty())
      waiting_ = res_.exchanges.size() - 1;
    else
      ready_at_ = clock_.now() + from_seconds(s.after_s);
  }
}

// The visit's next step when the last one is over and its time has come.
void GuidedVisit::next_step() {
  if (!idle() || next_ >= visit_.steps.size()) return;
  const VisitStep& s = visit_.steps[next_];
  const Time at = s.at_s ? std::max(ready_at_, time_from_seconds(*s.at_s)) : ready_at_;
  if (clock_.now() < at) return;
  ++next_;
  (void)guide_->take_started_task();
  guide_->clear_task_end();
  if (s.kind != VisitStep::Kind::button) {
    ask(s);
  } else if (hw_.simulator().press_button(s.text)) {
    ++pending_button_;
  } else {
    say("visitor presses " + in_quotes(s.text) + ": the robot has no such button");
    ready_at_ = clock_.now() + from_seconds(s.after_s);
  }
}

// A request typed or spoken (heard by the recognizer when the build has voice).
void GuidedVisit::ask(const VisitStep& s) {
  VisitExchange x;
  x.step = next_ - 1;
  x.time_s = to_seconds(clock_.now());
  x.kind = std::string(to_string(s.kind));
  x.request = s.text;
  HriReply r;
  if (s.kind == VisitStep::Kind::spoken && res_.voice) {
    const AudioClip audio = voice_.visitor->synthesize(s.text);
    const SpeechRecognizer::Result heard = voice_.ears->recognize(resample(audio, voice_.ears->sample_rate_hz()));
    x.heard = heard.words;
    say("visitor (spoken): " + in_quotes(s.text) + "  heard: " + in_quotes(heard.words));
    r = guide_->module().handle_heard(heard);
  } else {
    say(std::string("visitor (") + (s.kind == VisitStep::Kind::spoken ? "spoken, voice off: read as typed" : "typed") +
        "): " + in_quotes(s.text));
    r = guide_->module().handle(s.text);
  }
  record(x, r);
  res_.exchanges.push_back(x);
  check_exchange(s, res_.exchanges.back());
  if (robot_->planner().busy())
    waiting_ = res_.exchanges.size() - 1;
  else
    ready_at_ = clock_.now() + from_seconds(s.after_s);
}

// The visitors round the robot: those giving way, and the time the robot waited for them.
void GuidedVisit::watch_visitors() {
  bool visitor_near = false;
  for (std::size_t i = 0; i < sim_.visitors().size(); ++i) {
    const navi::Point2D v = sim_.visitors()[i].position;
    visitor_near = visitor_near || std::hypot(v.x_m - sim_.pose().x_m, v.y_m - sim_.pose().y_m) < 1.2;
    const bool waits = sim_.visitors()[i].giving_way;
    if (waits && giving_way_[i] == 0) ++res_.visitor_waits;
    giving_way_[i] = waits ? 1 : 0;
  }
  if (visitor_near && robot_->behavior_active("BhAutoMove") &&
      std::hypot(sim_.velocity().vx_m_s, sim_.velocity().vy_m_s) < 0.02 && std::abs(sim_.velocity().wz_rad_s) < 0.05) {
    res_.robot_waited_s += to_seconds(kPeriod);
  }
}

void GuidedVisit::drive() {
  const Time deadline = time_from_seconds(visit_.max_duration_s);
  while (clock_.now() < deadline && !stopped()) {
    monitor_update();
    if (watch_ && watch_->paused()) {
      wall_.sleep_until(wall_.now() + std::chrono::milliseconds(20));
      pacer_.emplace(wall_, o_.realtime_speed);  // no catching up after a pause
      continue;
    }
    end_waiting_task();
    take_presses();
    next_step();
    if (next_ >= visit_.steps.size() && idle() && !robot_->planner().busy() && (live_ == nullptr || !o_.visit.empty())) {
      // The visit is over; a monitored robot goes on serving its pages until stopped.
      if (!res_.completed && !o_.visit.empty())
        say("the visit is over" + std::string(watch_ ? "; the monitor goes on serving until stopped" : ""));
      res_.completed = true;
      if (!watch_) break;
    }
    robot_->run_for(kPeriod);
    if (live_)
      live_->step(
          to_seconds(kPeriod), [this](const std::string& line) { say(line); }, res_.exchanges, to_seconds(clock_.now()));
    watch_visitors();
    flush_life();
    display();
    if (pacer_) pacer_->pace(clock_.now());
  }
  monitor_update();
}

// The task cancelled if it still runs, the base at rest, the figures and the outputs.
void GuidedVisit::finish() {
  res_.stopped_by = stop_reason(stop_signal(o_.stop));
  if (robot_->planner().busy()) {
    robot_->planner().cancel(!res_.stopped_by.empty() ? res_.stopped_by
                                                      : "the visit did not end within " + fixed(visit_.max_duration_s, 0) + " s");
    robot_->step_sequencing();
  }
  // Whatever ended the run, the base is left at rest before the devices close.
  const sim::Simulator& sim = sim_;
  const BaseStop rest = stop_base(
      *robot_, clock_, [&sim] { return std::vector<double>(sim.wheel_commands().begin(), sim.wheel_commands().end()); }, kPeriod);
  res_.base_command_at_end_rad_s = rest.command_rad_s;
  res_.base_at_rest = rest.at_rest;
  flush_life();
  for (const sim::SimEvent& e : sim_.events()) {
    if (e.kind == sim::SimEvent::Kind::collision)
      say("simulator: collision " + e.detail + " at " + fixed(to_seconds(e.stamp), 1) + " s");
  }
  res_.duration_s = to_seconds(clock_.now());
  res_.distance_m = sim_.distance_m();
  res_.collisions = sim_.collisions();
  res_.visitor_collisions = sim_.visitor_collisions();
  res_.min_visitor_clearance_m = sim_.min_visitor_clearance_m();
  res_.processes = guide_->processes();
  for (const VisitExchange& x : res_.exchanges) res_.mismatches += x.as_expected ? 0 : 1;
  if (!res_.completed)
    say(stopped() ? "the run was " + res_.stopped_by : "the visit did not end within " + fixed(visit_.max_duration_s, 0) + " s");
  if (!o_.out.empty()) {
    write_text(o_.out / "dialogue.txt", dialogue_.str());
    write_text(o_.out / "report.json", res_.json());
  }
}

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
  GuidedVisit guided(o, visit, profile, world, std::move(server_options), res);
  guided.start();
  guided.drive();
  guided.finish();
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
