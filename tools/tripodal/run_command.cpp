// `tripodal run --robot ROBOT.yaml --world WORLD.yaml --task "clean the room 3211"`: the whole
// robot in the embedded simulator (app/cleaning_run.hpp): the task and process life cycle and a
// progress bar on the terminal, and at the end the map picture, the trajectory and the report.
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <memory>
#include <iostream>
#include <optional>
#include <ostream>
#include <sstream>

#include "cli_tool.hpp"
#include "run_task.hpp"
#include "visit.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/monitor/monitor_server.hpp"
#include "tripodal/robot/robot_profile.hpp"

#include <spdlog/spdlog.h>

namespace tripodal::tool {
namespace {

using namespace cli;

constexpr int kTaskFailed = 4;

constexpr std::string_view kDescription =
    "Runs the robot of a profile in the embedded simulator (the world file gives the map, the\n"
    "regions, the start pose and the faults) and gives it the task in plain words, e.g.\n"
    "\"clean the room 3211\". Prints the task and process life cycle and a progress bar (coverage\n"
    "of the room's reachable free area). With --out, DIR receives map.png (sections, cleaned\n"
    "cells, path), trajectory.csv (true and estimated pose at 10 Hz), report.json (coverage, path\n"
    "length, turns, duration, faults, recoveries, planned hybrid, balloon and boustrophedon paths) and\n"
    "lifecycle.txt. The same seed gives the same run. --faults adds localization losses (the\n"
    "laser dazzled), in seconds of simulated time: \"300-330; 900-905\" (or a file holding that text).\n"
    "Faster than real time unless --realtime: then the robot runs on its own threads (each loop at\n"
    "its period on the wall clock sped up SPEED times, default 1; the profile's loops: settings for\n"
    "SCHED_FIFO, CPU and mlockall; deadlines watched) and report.json gives each loop's period\n"
    "error and overruns (docs/robot.md). --pattern\n"
    "makes the cleaning behaviors follow another coverage path (balloon: the paper's wall-following\n"
    "rounds; boustrophedon: plough lanes) to measure it on the robot.\n"
    "--monitor [ADDR:]PORT serves the live monitor and operator console (docs/monitor.md) on\n"
    "127.0.0.1 unless ADDR is given, prints its address and token, paces the run to real time\n"
    "(--realtime SPEED changes the speed) and keeps the robot running after the task (a task may\n"
    "then come from the console instead of --task) until interrupted (Ctrl-C, SIGTERM).\n"
    "A robot whose profile has a dds: section is on DDS while it runs (docs/distribution.md): its\n"
    "odometry, pose, map, events and markings are published and it takes task commands; without\n"
    "--task (and dds: tasks on) it is paced to real time and waits for a task from a peer.\n"
    "--hardware dds runs the same robot against a simulator in another process (`tripodal sim-server`,\n"
    "docs/distribution.md), in lock-step with it; --hardware-param KEY=VALUE sets its namespace,\n"
    "domain_id, step_timeout_s ...\n"
    "--visit VISIT.yaml runs the guide robot's scripted visit instead of a task (docs/guide.md): the\n"
    "dialogue, the life cycle and the collisions; with --out, dialogue.txt, report.json and the\n"
    "answers' audio (audio/*.wav, when the build has voice). With --monitor (and a visit or not) the\n"
    "guide robot's monitor also serves its knowledge base (/rkms, administered with the token) and\n"
    "its touch screen (/touch), answered by the robot's own HRI.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 task succeeded, 1 bad profile/world/faults, 2 bad command line, 3 I/O error,\n"
    "            4 the task failed, was refused or timed out (with --monitor or dds: and no task given at all,\n"
    "            the run ends with 0 when stopped); with --visit: a collision, an outcome not as\n"
    "            expected, or the visit not completed;\n"
    "            130 (SIGINT, Ctrl-C) or 143 (SIGTERM): a task or visit was still running when the signal\n"
    "            stopped the run (it is cancelled, the base brought to rest, the outputs written).";

struct Args {
  app::RunOptions options;
  std::filesystem::path visit;  // --visit: the guide demo instead of a task
  bool no_voice = false;
  std::string audio;                   // --audio DEVICE: live microphone and speaker (ALSA)
  std::filesystem::path audio_config;  // --audio-config FILE
  std::optional<double> give_way_m;  // --visitors-give-way-m
  std::string faults;
  std::vector<std::string> hardware_params;  // --hardware-param KEY=VALUE
  CLI::Option* realtime = nullptr;  // given at all (with or without SPEED)
  double realtime_speed = 0.0;      // 0: --realtime without SPEED
};

// The signal that asked the run to stop (0: none). The first SIGINT or SIGTERM stops the run in
// order (the task cancelled, the base at rest, the report written); the handler then gives the
// signal back its default, so a second Ctrl-C ends a run that does not stop.
volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_stop_signal(int sig) {
  g_stop = sig;
  std::signal(sig, SIG_DFL);
}

void stop_on_signals() {
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
}

// A run a signal cut short (a task or visit not finished) exits as a shell reports the signal:
// 128 + N (130 for SIGINT, 143 for SIGTERM).
constexpr int interrupted_exit(int sig) { return 128 + sig; }

// A bad --monitor address or token file, refused as a command-line error before anything is
// built (the monitor's own std::invalid_argument; later ones are the robot's, not --monitor's).
std::optional<int> check_monitor(const app::RunOptions& o, std::ostream& err) {
  if (!o.monitor) return std::nullopt;
  try {
    (void)monitor::server_options(*o.monitor, o.monitor_token_file);
  } catch (const std::invalid_argument& e) {
    err << "tripodal run: --monitor: " << e.what() << '\n';
    return kUsage;
  } catch (const std::runtime_error& e) {
    err << "tripodal run: " << e.what() << '\n';
    return kIoError;
  }
  return std::nullopt;
}

// The guide robot's runs (docs/guide.md): `--visit FILE`, the scripted visit, and `--monitor` on a
// robot whose HRI is the guide's (type Hri), its RKMS and touch page served with or without a visit.
int run_guide(const Args& args, std::ostream& out, std::ostream& err) {
  const app::RunOptions& o = args.options;
  if (!o.task.empty()) {
    err << "tripodal run: the guide robot takes its requests from --visit or the monitor's touch page, not --task\n";
    return kUsage;
  }
  if (o.realtime && !o.monitor) {
    err << "tripodal run: --visit runs as fast as it can; --realtime goes with --monitor\n";
    return kUsage;
  }
  if (!o.record.empty()) {
    err << "tripodal run: --record records a task's run (--task or the monitor's console), not the guide robot's visit\n";
    return kUsage;
  }
  if (!o.monitor && (o.start_paused || o.monitor_read_open || !o.monitor_token_file.empty() || !o.monitor_allowed_hosts.empty() ||
                     !o.monitor_allowed_origins.empty())) {
    err << "tripodal run: --start-paused, --monitor-read-open, --monitor-token-file, --monitor-allow-host and "
           "--monitor-allow-origin need --monitor [ADDR:]PORT\n";
    return kUsage;
  }
  std::vector<std::filesystem::path> files{o.robot, o.world};
  if (!args.visit.empty()) files.push_back(args.visit);
  for (const auto& f : files) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f, ec)) {
      err << "tripodal run: cannot read '" << f.string() << "'\n";
      return kIoError;
    }
  }
  if (const auto rc = check_monitor(o, err)) return *rc;
  stop_on_signals();
  try {
    spdlog::set_level(spdlog::level::warn);
    app::VisitOptions vo;
    vo.robot = o.robot;
    vo.world = o.world;
    vo.plugins = o.plugins;
    vo.visit = args.visit;
    vo.seed = o.seed;
    vo.out = o.out;
    vo.voice = !args.no_voice;
    vo.audio_device = args.audio;
    vo.audio_config = args.audio_config;
    vo.visitors_give_way_m = args.give_way_m;
    vo.log = &out;
    vo.monitor = o.monitor;
    vo.monitor_token_file = o.monitor_token_file;
    vo.monitor_read_open = o.monitor_read_open;
    vo.monitor_allowed_hosts = o.monitor_allowed_hosts;
    vo.monitor_allowed_origins = o.monitor_allowed_origins;
    vo.start_paused = o.start_paused;
    vo.realtime_speed = o.realtime && args.realtime_speed > 0.0 ? args.realtime_speed : 1.0;
    vo.max_duration_s = o.max_duration_s;
    vo.stop = &g_stop;
    out << "tripodal run: robot " << o.robot.string() << ", world " << o.world.string()
        << (!args.visit.empty()  ? ", visit " + args.visit.string()
            : args.audio.empty() ? std::string(", no visit file: the monitor's visitors")
                                 : ", no visit file: the visitors at the microphone " + args.audio)
        << "\n";
    out.flush();
    const app::VisitResult r = app::run_visit(vo);
    out << (args.visit.empty() ? "run ended" : std::string("visit ") + (r.completed ? "completed" : "not completed")) << " (seed " << r.seed
        << "): " << r.exchanges.size() << " exchanges, " << r.mismatches << " not as expected; " << r.duration_s << " s simulated; path "
        << r.distance_m << " m; " << r.collisions << " collisions (" << r.visitor_collisions << " with visitors); closest to a visitor "
        << r.min_visitor_clearance_m << " m; visitors stopped " << r.visitor_waits << " times to let the robot pass, the robot waited "
        << r.robot_waited_s << " s for visitors\n";
    if (!o.out.empty()) out << "wrote " << (o.out / "dialogue.txt").string() << ", report.json" << (r.voice ? ", audio/*.wav" : "") << "\n";
    if (!r.stopped_by.empty()) out << "run " << r.stopped_by << "\n";
    // A visit cut short by a signal: 128 + N. A monitored run stopped by the operator after (or
    // without) its visit: nothing failed.
    if (g_stop != 0 && !args.visit.empty() && !r.completed) return interrupted_exit(g_stop);
    const bool visit_ok = args.visit.empty() || (r.completed && r.mismatches == 0);
    return visit_ok && r.collisions == 0 ? kOk : kTaskFailed;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const std::invalid_argument& e) {  // a value the robot's parts refused as they were built
    err << "tripodal run: " << e.what() << '\n';
    return kBadInput;
  } catch (const std::runtime_error& e) {
    err << "tripodal run: " << e.what() << '\n';
    return kIoError;
  }
}

// Whether the robot takes its task over DDS (its profile's dds: tasks), so --task may be left out.
// A profile that does not load counts as yes: the run reports its errors, located.
bool takes_dds_tasks(const std::filesystem::path& robot) {
  try {
    const RobotProfile p = load_robot_profile(robot);
    return p.dds && p.dds->tasks;
  } catch (const std::exception&) {
    return true;
  }
}

// Whether the profile's HRI is the guide robot's (a module of type Hri): its monitor runs serve the
// robot's RKMS and touch page (run_guide). A profile that does not load is left to run_task's errors.
bool is_guide_robot(const std::filesystem::path& robot) {
  try {
    const RobotProfile profile = load_robot_profile(robot);
    return std::any_of(profile.hri.begin(), profile.hri.end(), [](const ModuleEntry& e) { return e.type == "Hri"; });
  } catch (const std::exception&) {
    return false;
  }
}

int run(Args& args, std::ostream& out, std::ostream& err) {
  app::RunOptions& o = args.options;
  const std::string& faults = args.faults;
  o.realtime = args.realtime->count() > 0;
  if (args.realtime_speed > 0.0) o.realtime_speed = args.realtime_speed;
  if (!args.visit.empty() || !args.audio.empty() || (o.monitor && o.task.empty() && is_guide_robot(o.robot))) {
    return run_guide(args, out, err);
  }
  if (args.give_way_m || args.no_voice || !args.audio_config.empty()) {
    err << "tripodal run: --no-voice and --visitors-give-way-m go with the guide robot's runs (--visit, or --monitor on a robot with an Hri module)\n";
    return kUsage;
  }
  for (const std::string& kv : args.hardware_params) {
    const std::size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) {
      err << "tripodal run: --hardware-param " << kv << ": expected KEY=VALUE (namespace=psr2)\n";
      return kUsage;
    }
    o.hardware_parameters.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
  }
  if (o.task.empty() && !o.monitor && !takes_dds_tasks(o.robot)) {
    err << "tripodal run: --task is required (without --monitor, where the console may give it, or a profile "
           "with dds: {tasks: true}, where a DDS peer may)\n";
    return kUsage;
  }
  if (!o.monitor && (o.start_paused || o.monitor_read_open || !o.monitor_token_file.empty() || !o.monitor_allowed_hosts.empty() ||
                     !o.monitor_allowed_origins.empty())) {
    err << "tripodal run: --start-paused, --monitor-read-open, --monitor-token-file, --monitor-allow-host and "
           "--monitor-allow-origin need --monitor [ADDR:]PORT\n";
    return kUsage;
  }
  if (const auto rc = check_monitor(o, err)) return *rc;
  // Every run stops in order on a signal; one that serves (--monitor, dds: tasks) runs until one.
  stop_on_signals();
  o.stop = &g_stop;
  for (const auto& f : {o.robot, o.world}) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f, ec)) {
      err << "tripodal run: cannot read '" << f.string() << "'\n";
      return kIoError;
    }
  }
  try {
    if (!faults.empty()) {
      std::string text = faults;
      SourceLocation where{"--faults", 1, 1};
      std::error_code ec;
      if (std::filesystem::is_regular_file(faults, ec)) {
        std::ifstream f(faults);
        std::ostringstream s;
        s << f.rdbuf();
        text = s.str();
        where = SourceLocation{faults, 1, 1};
      }
      o.faults = navi::parse_fault_schedule(text, where);
    }
    spdlog::set_level(spdlog::level::warn);  // the life cycle is printed below, once
    o.log = &out;
    o.progress = &err;
    o.progress_is_terminal = ::isatty(2) != 0;
    out << "tripodal run: robot " << o.robot.string() << ", world " << o.world.string() << ", task \"" << o.task << "\""
        << (o.hardware.empty() ? std::string() : ", hardware " + o.hardware) << "\n";
    out.flush();
    const app::RunResult r = app::run_task(o);
    out << "task " << r.state << (r.reason.empty() ? "" : ": " + r.reason) << "; ";
    if (r.reachable_cells > 0) out << "coverage " << r.coverage * 100.0 << " % of " << r.reachable_area_m2 << " m2 reachable; ";
    else out << "no cleaning in this task; ";
    out << "path " << r.total.length_m << " m, " << r.total.turns << " turns; " << r.duration_s
        << (r.wall_clock ? " s wall clock; " : " s simulated; ") << r.recoveries.size() << " recoveries\n";
    if (!r.charging.empty()) out << r.charging << "\n";
    if (const auto& d = r.disinfection) {
      out << "disinfection: " << d->dose_coverage * 100.0 << " % of the reachable floor dosed >= " << d->uv_target_dose_j_m2
          << " J/m2 (median " << d->median_dose_j_m2 << " J/m2, lamp on " << d->lamp_on_s << " s); disinfectant used "
          << d->disinfectant_used_l << " l; link over " << d->line << ": " << d->link.requests << " requests, "
          << d->link.missed << " missed, " << d->decoder_errors << " decoder errors, " << d->link.link_losses << " link losses\n";
      if (d->plan) {
        out << "dose reached: " << d->lamp_floor_dose_coverage * 100.0 << " % of the " << d->lamp_floor_m2
            << " m2 the lamp can dose (within " << d->plan->reach_m
            << " m of where the robot stands) >= " << d->uv_target_dose_j_m2 << " J/m2, planned lanes " << d->plan->spacing_m
            << " m apart at up to " << d->plan->speed_m_s << " m/s, " << d->plan->passes << " pass"
            << (d->plan->passes > 1 ? "es" : "") << " (estimated " << d->estimate_s << " s, " << d->estimate_ah
            << " Ah); battery used " << d->battery_used_ah << " Ah, lamp " << d->lamp_energy_wh << " Wh (" << d->uvc_energy_j
            << " J of UVC)\n";
      }
    }
    if (!r.stopped_by.empty()) out << "run " << r.stopped_by << (r.base_at_rest ? ", the base at rest" : ", the base NOT at rest") << "\n";
    if (!o.out.empty()) {
      out << "wrote " << (o.out / "map.png").string() << (r.disinfection ? ", dose.png" : "")
          << ", trajectory.csv, report.json, lifecycle.txt\n";
    }
    if (r.state == "interrupted") return interrupted_exit(g_stop);
    // A monitored robot the operator never gave a task: nothing failed.
    const bool idle_monitor = (o.monitor.has_value() || o.task.empty()) && r.state == "idle";
    return r.succeeded || idle_monitor ? kOk : kTaskFailed;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const std::invalid_argument& e) {  // a value the robot's parts refused as they were built
    err << "tripodal run: " << e.what() << '\n';
    return kBadInput;
  } catch (const std::runtime_error& e) {
    err << "tripodal run: " << e.what() << '\n';
    return kIoError;
  }
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  app::RunOptions& o = a->options;
  cmd.add_option("--robot", o.robot, "ROBOT.yaml: the robot profile")->required();
  cmd.add_option("--world", o.world, "WORLD.yaml: map, regions, start pose and faults")->required();
  cmd.add_option("--plugin", o.plugins,
                 "LIB.so: a shared-library plugin with the profile's own types (repeatable; docs/plugins.md)")
      ->allow_extra_args(false);
  cmd.add_option("--task", o.task, "\"COMMAND\": the task in plain words (optional with --monitor)");
  cmd.add_option("--visit", a->visit,
                 "VISIT.yaml: the guide robot's scripted visit (typed and spoken requests, buttons; docs/guide.md) instead of a task");
  cmd.add_flag("--no-voice", a->no_voice, "with --visit: read spoken requests as typed, write no audio");
  cmd.add_option("--audio", a->audio,
                 "DEVICE: the guide robot hears the room through this ALSA device and answers on it (\"default\"; docs/hri.md "
                 "\"Live audio\"); without --visit it runs until --max-duration-s or a signal");
  cmd.add_option("--audio-config", a->audio_config, "FILE: an ALSA configuration file defining the --audio device");
  cmd.add_option("--visitors-give-way-m", a->give_way_m,
                 "M: the guide robot's runs: every visitor keeps M from the robot (the world's give_way_m); 0: walkers that do "
                 "not yield")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--seed", o.seed, "N: the simulator's seed (default: the world's)")->check(cli::whole_number());
  cmd.add_option("--hardware", o.hardware,
                 "TYPE: instead of the profile's hardware: dds, the simulator in another process (tripodal sim-server; "
                 "docs/distribution.md), the world still giving the map and regions");
  cmd.add_option("--hardware-param", a->hardware_params,
                 "KEY=VALUE: a parameter of the hardware slot (repeatable): namespace=NS, domain_id=N, step_timeout_s=S");
  cmd.add_option("--out", o.out, "DIR: where map.png, trajectory.csv, report.json and lifecycle.txt go")
      ->check(cli::writable_folder());
  cmd.add_option("--record", o.record,
                 "FILE.mcap: record the run (sensor readings, commands, the life cycle with every firing) as MCAP "
                 "(docs/rosbag.md); `tripodal trace convert` turns it into a trace")
      ->check(cli::writable_file());
  // Without SPEED CLI11 hands the option an empty value, which leaves realtime_speed at 0.
  a->realtime = cmd.add_option("--realtime", a->realtime_speed, "[SPEED]: SPEED times real time (default 1)")
                    ->expected(0, 1)
                    ->check(cli::positive_number() | CLI::IsMember({"", "true"}));
  cmd.add_option("--faults", a->faults, "SCHEDULE|FILE: localization losses, \"300-330; 900-905\" (s)");
  cmd.add_option("--max-duration-s", o.max_duration_s, "S: simulated time limit")
      ->check(cli::positive_number())
      ->capture_default_str();
  cmd.add_option("--pattern", o.pattern, "hybrid|balloon|boustrophedon: the coverage pattern (default: the profile's)")
      ->check(CLI::IsMember({"hybrid", "balloon", "boustrophedon"}));
  cmd.add_option("--board", o.board_line,
                 "in_process|pty: on the control board (hardware: {type: board}), what carries the bytes; pty: a "
                 "kernel pseudo-terminal, the host opening its slave device as it would the board's UART")
      ->check(CLI::IsMember({"in_process", "pty"}));
  cmd.add_option("--uv-target-dose", o.uv_target_dose_j_m2,
                 "J/m2: on the control board, the dose a cell must receive to count as disinfected, and the dose the lanes "
                 "are planned for (default: the CoveragePlanner's dose_target_j_m2, else 10)")
      ->check(cli::positive_number());
  cmd.add_flag(
      "--no-dose-plan", [&o](std::int64_t) { o.dose_plan = false; },
      "lanes as without a dose target (the CoveragePlanner's dose_target_j_m2 off); the dose is still measured");
  cmd.add_option("--time-limit", o.time_limit_s,
                 "S: a disinfection planned for a dose (the CoveragePlanner's dose_target_j_m2) that needs longer is "
                 "refused before it starts")
      ->check(cli::positive_number());
  cmd.add_option("--monitor", o.monitor, "[ADDR:]PORT: serve the live monitor and console (docs/monitor.md); 0: a free port");
  cmd.add_option("--monitor-token-file", o.monitor_token_file, "FILE: the console's token (first line; default: generated)");
  cmd.add_flag("--monitor-read-open", o.monitor_read_open, "let clients without the token watch (not command)");
  cmd.add_option("--monitor-allow-host", o.monitor_allowed_hosts,
                 "NAME: also serve requests that name this host (the robot's DNS name; loopback and addresses always are)");
  cmd.add_option("--monitor-allow-origin", o.monitor_allowed_origins,
                 "ORIGIN: also take streams and commands from pages of this origin (https://app.foxglove.dev)");
  cmd.add_flag("--start-paused", o.start_paused, "with --monitor: hold the run until the operator resumes it");
  return [a](std::ostream& out, std::ostream& err) { return run(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "run", "run a robot in the simulator on a task (clean the room 3211)", kDescription, kExitCodes,
                     &setup);

}  // namespace tripodal::tool
