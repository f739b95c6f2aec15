// Fleet throughput: `tripodal fleet --robots N` on loopback DDS (docs/distribution.md, "A fleet"),
// run as the user runs it, over the eight rooms of fleet_world.yaml (each of the workspace's four
// sections twice), at a speed far above what a robot simulates per CPU second so that the CPU, not
// the pacing, is the limit. Reports the simulated seconds of the robots' tasks (from their logs),
// the wall and CPU seconds of the whole command (robots' start and stop included), and their ratio.
//   tripodal_fleet_bench [--domain BASE] [benchmark options]
//   (BM_FleetThroughput/N on DDS domain BASE + N; BASE 210 unless given). A fleet that does not
//   exit 0 is an error of its benchmark, and the program exits 1.
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

extern char** environ;

namespace {

std::uint32_t domain_base = 210;
bool failed = false;  // a fleet that did not succeed: the program's exit code says so too

// The robots run paced at this many times real time: a robot simulates about 60 s per CPU
// second (docs/distribution.md), so the pacing never waits.
constexpr const char* kSpeed = "10000";

constexpr const char* kTask = "clean the rooms 11, 12, 21, 22, 31, 32, 41 and 42";

// What the robots' logs (robotK.log, the `tripodal run` life cycle, in simulated seconds) say of
// the tasks they ran: "    513.6 s  task clean succeeded" after "      0.0 s  task clean started (...)".
struct RobotTasks {
  double simulated_s = 0.0;  // summed over the tasks that ended (succeeded or failed)
  int ended = 0;
  int started = 0;
};

RobotTasks read_robot_log(const std::filesystem::path& log) {
  static const std::regex line(R"(^\s*([0-9]+(?:\.[0-9]+)?) s  task \S+ (started|succeeded|failed)\b)");
  RobotTasks out;
  std::ifstream f(log);
  double since_s = -1.0;  // the task in hand's start; < 0: none
  for (std::string l; std::getline(f, l);) {
    std::smatch m;
    if (!std::regex_search(l, m, line)) continue;
    const double t = std::stod(m[1].str());
    if (m[2] == "started") {
      since_s = t;
      ++out.started;
    } else if (since_s >= 0.0) {
      out.simulated_s += t - since_s;
      ++out.ended;
      since_s = -1.0;
    }
  }
  return out;
}

// The last non-empty line holding `what` ("": any).
std::string last_line_with(const std::filesystem::path& file, const std::string& what) {
  std::ifstream f(file);
  std::string found;
  for (std::string l; std::getline(f, l);) {
    if (!l.empty() && l.find(what) != std::string::npos) found = l;
  }
  return found;
}

void BM_FleetThroughput(benchmark::State& state) {
  const int robots = static_cast<int>(state.range(0));
  std::string tmpl = (std::filesystem::temp_directory_path() / "tripodal-fleet-bench-XXXXXX").string();
  if (::mkdtemp(tmpl.data()) == nullptr) {
    failed = true;
    state.SkipWithError("cannot create a temporary folder");
    return;
  }
  const std::filesystem::path dir = tmpl;
  const std::filesystem::path out = dir / "fleet.out";
  for (auto _ : state) {
    const std::vector<std::string> argv{
        TRIPODAL_TOOL_EXE, "fleet",
        "--robots",        std::to_string(robots),
        "--world",         TRIPODAL_FLEET_WORLD,
        "--robot",         TRIPODAL_FLEET_ROBOT,
        "--task",          kTask,
        "--speed",         kSpeed,
        "--domain",        std::to_string(domain_base + static_cast<std::uint32_t>(robots)),
        "--out",           dir.string()};
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    const auto start = std::chrono::steady_clock::now();
    pid_t pid = -1;
    const int rc = posix_spawn(&pid, args[0], &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) {
      failed = true;
      state.SkipWithError(
          (std::string("cannot start ") + TRIPODAL_TOOL_EXE + ": " + std::strerror(rc)).c_str());
      return;
    }
    int status = 0;
    rusage usage{};  // of the fleet and of the robots it reaped
    ::wait4(pid, &status, 0, &usage);
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(wall_s);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      failed = true;
      const std::string how = WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                                : "status " + std::to_string(status);
      state.SkipWithError(("tripodal fleet --robots " + std::to_string(robots) + " ended with " + how +
                           ": \"" + last_line_with(out, "") + "\" (its output and the robots' logs are in " +
                           dir.string() + ")")
                              .c_str());
      return;
    }
    RobotTasks all;
    int idle = 0;
    for (int k = 1; k <= robots; ++k) {
      const RobotTasks r = read_robot_log(dir / ("robot" + std::to_string(k) + ".log"));
      all.simulated_s += r.simulated_s;
      all.ended += r.ended;
      idle += r.started == 0 ? 1 : 0;
    }
    const auto seconds = [](const timeval& t) {
      return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6;
    };
    const double cpu_s = seconds(usage.ru_utime) + seconds(usage.ru_stime);
    state.counters["robots"] = robots;
    state.counters["idle_robots"] = idle;
    state.counters["tasks_ended"] = all.ended;
    state.counters["simulated_s"] = all.simulated_s;
    state.counters["wall_s"] = wall_s;
    state.counters["cpu_s"] = cpu_s;
    state.counters["sim_s_per_wall_s"] = all.simulated_s / wall_s;
    state.counters["sim_s_per_cpu_s"] = cpu_s > 0.0 ? all.simulated_s / cpu_s : 0.0;
    state.SetLabel(last_line_with(out, "fleet succeeded"));
  }
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--domain") == 0 && i + 1 < argc) {
      domain_base = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    } else {
      args.push_back(argv[i]);
    }
  }
  if (domain_base + 8 > 232) {
    std::fprintf(stderr, "tripodal_fleet_bench: --domain %u: BASE + 8 must be at most 232\n", domain_base);
    return 1;
  }
  benchmark::RegisterBenchmark("BM_FleetThroughput", BM_FleetThroughput)
      ->Arg(4)
      ->Arg(8)
      ->UseManualTime()
      ->Unit(benchmark::kSecond)
      ->Iterations(1);
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return failed ? 1 : 0;
}
