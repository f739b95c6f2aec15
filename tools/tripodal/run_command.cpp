// `tripodal run --robot ROBOT.yaml --world WORLD.yaml --task "clean the room 3211"`: the whole
// robot in the embedded simulator (app/cleaning_run.hpp): the task and process life cycle and a
// progress bar on the terminal, and at the end the map picture, the trajectory and the report.
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <ostream>
#include <sstream>

#include "command.hpp"
#include "tripodal/app/cleaning_run.hpp"
#include "tripodal/core/diagnostic.hpp"

#include <spdlog/spdlog.h>

namespace tripodal::tool {
namespace {

constexpr int kTaskFailed = 4;

constexpr std::string_view kRunUsage =
    "usage: tripodal run --robot ROBOT.yaml --world WORLD.yaml --task \"COMMAND\"\n"
    "                    [--seed N] [--out DIR] [--realtime [SPEED]] [--faults SCHEDULE|FILE]\n"
    "                    [--max-duration-s S] [--boustrophedon]\n\n"
    "Runs the robot of a profile in the embedded simulator (the world file gives the map, the\n"
    "regions, the start pose and the faults) and gives it the task in plain words, e.g.\n"
    "\"clean the room 3211\". Prints the task and process life cycle and a progress bar (coverage\n"
    "of the room's reachable free area). With --out, DIR receives map.png (sections, cleaned\n"
    "cells, path), trajectory.csv (true and estimated pose at 10 Hz), report.json (coverage, path\n"
    "length, turns, duration, faults, recoveries, planned balloon vs boustrophedon paths) and\n"
    "lifecycle.txt. The same seed gives the same run. --faults adds localization losses, in\n"
    "seconds of simulated time: \"300-330; 900-905\" (or a file holding that text).\n"
    "Faster than real time unless --realtime (SPEED times real time, default 1). --boustrophedon\n"
    "makes the cleaning behaviors follow the plough path instead of the wall-following balloon,\n"
    "to measure the baseline on the robot.\n\n"
    "exit codes: 0 task succeeded, 1 bad profile/world/faults, 2 bad command line, 3 I/O error,\n"
    "4 the task failed, was refused or timed out.\n";

int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  app::RunOptions o;
  std::string faults;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](std::string& into) {
      if (i + 1 >= args.size()) return false;
      into = args[++i];
      return true;
    };
    std::string v;
    bool ok = true;
    if (a == "--robot") {
      ok = value(v);
      o.robot = v;
    } else if (a == "--world") {
      ok = value(v);
      o.world = v;
    } else if (a == "--task") {
      ok = value(o.task);
    } else if (a == "--out") {
      ok = value(v);
      o.out = v;
    } else if (a == "--boustrophedon") {
      o.boustrophedon = true;
    } else if (a == "--faults") {
      ok = value(faults);
    } else if (a == "--seed" || a == "--max-duration-s") {
      ok = value(v);
      try {
        std::size_t used = 0;
        if (a == "--seed") {
          o.seed = std::stoull(v, &used);
        } else {
          o.max_duration_s = std::stod(v, &used);
          ok = ok && o.max_duration_s > 0.0;
        }
        ok = ok && used == v.size();
      } catch (const std::exception&) {
        ok = false;
      }
    } else if (a == "--realtime") {
      o.realtime = true;
      if (i + 1 < args.size() && !args[i + 1].empty() && args[i + 1][0] != '-') {
        try {
          std::size_t used = 0;
          o.realtime_speed = std::stod(args[i + 1], &used);
          ok = used == args[i + 1].size() && o.realtime_speed > 0.0;
          ++i;
        } catch (const std::exception&) {
          ok = false;
        }
      }
    } else {
      err << "tripodal run: unknown argument " << a << '\n' << kRunUsage;
      return kUsage;
    }
    if (!ok) {
      err << "tripodal run: " << a << " needs a valid value\n" << kRunUsage;
      return kUsage;
    }
  }
  if (o.robot.empty() || o.world.empty() || o.task.empty()) {
    err << "tripodal run: --robot, --world and --task are required\n" << kRunUsage;
    return kUsage;
  }
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
    out << "tripodal run: robot " << o.robot.string() << ", world " << o.world.string() << ", task \"" << o.task << "\"\n";
    const app::RunResult r = app::run_task(o);
    out << "task " << r.state << (r.reason.empty() ? "" : ": " + r.reason) << "; ";
    if (r.reachable_cells > 0) out << "coverage " << r.coverage * 100.0 << " % of " << r.reachable_area_m2 << " m2 reachable; ";
    else out << "no cleaning in this task; ";
    out << "path " << r.total.length_m << " m, " << r.total.turns << " turns; " << r.duration_s << " s simulated; "
        << r.recoveries.size() << " recoveries\n";
    if (!o.out.empty()) out << "wrote " << (o.out / "map.png").string() << ", trajectory.csv, report.json, lifecycle.txt\n";
    return r.succeeded ? kOk : kTaskFailed;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const std::runtime_error& e) {
    err << "tripodal run: " << e.what() << '\n';
    return kIoError;
  }
}

}  // namespace

TRIPODAL_COMMAND("", "run", "run a robot in the simulator on a task (clean the room 3211)", kRunUsage, run);

}  // namespace tripodal::tool
