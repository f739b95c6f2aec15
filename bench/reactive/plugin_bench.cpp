// Load-time cost of the plugin model: reading the shipped reactive configurations (each
// controller checked against its type's manifest) and creating a behavior by name from the
// registry, including the error path of an unknown name (message with the known names and a
// suggestion). None of this runs in the control loop.
#include <benchmark/benchmark.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/reactive/reactive_config.hpp"

using namespace tripodal;

namespace {
std::string read_config(const char* name) {
  std::ifstream in(std::string(TRIPODAL_SOURCE_DIR) + "/configs/reactive/" + name);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

// Arg: 0 = jinny_differential.yaml, 1 = psr_omni.yaml.
static void BM_ParseReactiveConfig(benchmark::State& state) {
  const std::string text = read_config(state.range(0) == 0 ? "jinny_differential.yaml" : "psr_omni.yaml");
  ControllerRegistry controllers;
  register_builtin_controllers(controllers);
  for (auto _ : state) {
    ReactiveConfig c = parse_reactive_config(text, "reactive.yaml", controllers);
    benchmark::DoNotOptimize(c);
  }
}
BENCHMARK(BM_ParseReactiveConfig)->ArgName("omni")->Arg(0)->Arg(1);

static void BM_CreateBehaviorByName(benchmark::State& state) {
  BehaviorRegistry reg;
  register_behaviors(reg);
  for (auto _ : state) {
    auto b = reg.create("BhGoToPose");
    benchmark::DoNotOptimize(b);
  }
}
BENCHMARK(BM_CreateBehaviorByName);

static void BM_UnknownBehaviorName(benchmark::State& state) {
  BehaviorRegistry reg;
  register_behaviors(reg);
  for (auto _ : state) {
    try {
      auto b = reg.create("BhGoToPos");
      benchmark::DoNotOptimize(b);
    } catch (const std::exception& e) {
      benchmark::DoNotOptimize(e.what());
    }
  }
}
BENCHMARK(BM_UnknownBehaviorName);

BENCHMARK_MAIN();
