// Simulator benchmarks on the demo workspace (configs/worlds/workspace.yaml: 10.8 m x 32.8 m at
// 5 cm, 216 x 656 cells): one laser scan by ray casting (RPLIDAR A1: 1,450 beams, 12 m; SICK 180:
// 361 beams), and the physics plus every sensor stepped at 100 Hz, reported as simulated seconds
// per wall second.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/sim/simulator.hpp"

using namespace tripodal;
using namespace tripodal::sim;

namespace {

const World& workspace() {
  static const World w = load_world(std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace.yaml");
  return w;
}

// Free poses spread over the workspace, so the beams see near walls and far open space.
std::vector<Pose2D> poses() {
  const World& w = workspace();
  const SolidMap m(w.grid);
  std::vector<Pose2D> out;
  for (double y = 1.0; y < 31.5; y += 1.7) {
    for (double x = 1.0; x < 9.5; x += 1.9) {
      if (!m.disc_overlaps({x, y}, 0.3)) out.push_back({x, y, 0.37 * static_cast<double>(out.size())});
    }
  }
  return out;
}

void scan_bench(benchmark::State& state, const LaserConfig& config) {
  const SolidMap m(workspace().grid);
  LaserModel laser(config, 1);
  const std::vector<Pose2D> ps = poses();
  LaserScan scan;
  std::size_t i = 0;
  for (auto _ : state) {
    laser.scan(m, ps[i], Time{}, scan);
    benchmark::DoNotOptimize(scan.ranges_m.data());
    i = (i + 1) % ps.size();
  }
  state.counters["beams_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()) * config.beams,
                                                     benchmark::Counter::kIsRate);
  state.counters["poses"] = static_cast<double>(ps.size());
}

void BM_LaserScanRplidarA1(benchmark::State& state) { scan_bench(state, LaserConfig::rplidar_a1()); }
BENCHMARK(BM_LaserScanRplidarA1);

void BM_LaserScanSick180(benchmark::State& state) { scan_bench(state, LaserConfig::sick_180()); }
BENCHMARK(BM_LaserScanSick180);

ControllerConfig omni() {
  ControllerConfig c;
  c.type = "omni";
  const std::vector<double> angles = {1.0471975511965976, 3.141592653589793, 5.235987755982989};
  c.holonomic = omni_base(0.05, 0.22, angles);
  return c;
}

// One iteration = one 10 ms step of the physics (two 5 ms substeps) and of every sensor due:
// the laser at 5.5 Hz, gyro and odometry at 100 Hz, bumpers and cliff at 50 Hz, battery at 1 Hz.
// The robot drives a 0.6 m circle in open floor.
void physics_bench(benchmark::State& state, bool laser) {
  World w = workspace();
  w.start_pose = {5.0, 5.6, 0.0};
  w.robot.laser.enabled = laser;
  Simulator sim(std::move(w), omni(), 1);
  sim.command_twist({0.3, 0.0, 0.5});
  for (auto _ : state) {
    sim.step(std::chrono::milliseconds(10));
  }
  state.counters["sim_s_per_wall_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * 0.01, benchmark::Counter::kIsRate);
  state.counters["collisions"] = static_cast<double>(sim.collisions());
}

void BM_Physics100HzAllSensors(benchmark::State& state) { physics_bench(state, true); }
BENCHMARK(BM_Physics100HzAllSensors);

void BM_Physics100HzNoLaser(benchmark::State& state) { physics_bench(state, false); }
BENCHMARK(BM_Physics100HzNoLaser);

// Start-up with N small obstacles (0.08 m boxes, 0.15 m apart, all present from the start) on the
// workspace: the simulator's construction and its first step, which lays them on the solid map.
// Linear in obstacles + cells since each obstacle is rasterised over its bounding box and those
// appearing together are laid once (before: every obstacle over the whole map, each appearance
// laying every present one again; 10^4 obstacles took 30 s).
void BM_StartupWithObstacles(benchmark::State& state) {
  World base = workspace();
  base.start_pose = {5.0, 5.6, 0.0};
  const auto n = static_cast<std::size_t>(state.range(0));
  for (std::size_t k = 0; base.obstacles.size() < n; ++k) {
    // 64 columns over the room's width, as many rows as it takes (rows wrap past its top)
    const double x = 0.3 + 0.15 * static_cast<double>(k % 64), y = 0.3 + 0.15 * static_cast<double>((k / 64) % 210);
    base.obstacles.push_back({"b" + std::to_string(k), {{x, y}, {x + 0.08, y}, {x + 0.08, y + 0.08}, {x, y + 0.08}}, Time{}, std::nullopt, {}});
  }
  for (auto _ : state) {
    state.PauseTiming();
    World w = base;
    state.ResumeTiming();
    Simulator sim(std::move(w), omni(), 1);
    sim.step(std::chrono::milliseconds(10));
    benchmark::DoNotOptimize(sim.solid_map().cells().data());
  }
  state.counters["obstacles"] = static_cast<double>(n);
}
BENCHMARK(BM_StartupWithObstacles)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
