// The demo of `tripodal run` timed as a whole: the robot (planner, supervisor, nets, behaviors,
// localizer) on the embedded simulator cleaning a room, no output files. The counter sim_s_per_s
// is simulated seconds per wall second; coverage, path and turns are the run's (they do not
// depend on the machine). On a loaded machine compare the CPU time: sim_s / CPU seconds. Arguments: robot (0 PSR-2 omni, 1 differential), room (0 3211, 1 2111).
#include <benchmark/benchmark.h>

#include <spdlog/spdlog.h>

#include <string>

#include "run_task.hpp"

namespace {

void BM_DemoRun(benchmark::State& state) {
  using namespace tripodal;
  spdlog::set_level(spdlog::level::warn);
  const std::string src = TRIPODAL_SOURCE_DIR;
  app::RunOptions o;
  o.robot = src + (state.range(0) == 0 ? "/configs/robots/psr2.yaml" : "/configs/robots/jinny_differential.yaml");
  o.world = src + "/configs/worlds/workspace.yaml";
  o.task = state.range(1) == 0 ? "clean the room 3211" : "clean the room 2111";
  o.seed = 1;
  app::RunResult r;
  double simulated = 0.0;
  for (auto _ : state) {
    r = app::run_task(o);
    simulated += r.duration_s;
  }
  state.counters["sim_s_per_s"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
  state.counters["sim_s"] = r.duration_s;
  state.counters["coverage_pct"] = 100.0 * r.coverage;
  state.counters["reachable_cells"] = static_cast<double>(r.reachable_cells);
  state.counters["path_m"] = r.total.length_m;
  state.counters["turns"] = static_cast<double>(r.total.turns);
  state.counters["rotation_rad"] = r.total.rotation_rad;
  state.SetLabel(std::string(state.range(0) == 0 ? "psr2 " : "differential ") + o.task + (r.succeeded ? "" : " FAILED"));
}
BENCHMARK(BM_DemoRun)->ArgsProduct({{0, 1}, {0, 1}})->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
BENCHMARK_MAIN();
