// Time of one full reactive cycle: two resources (a 360-beam laser republished every cycle and
// odometry), eight active behaviors, the coordinator and a controller on ideal wheels; and the
// coordinator alone. Allocations per cycle are counted with a replaced operator new.
#include <benchmark/benchmark.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "instructions.hpp"
#include "reactive_rig.hpp"

namespace {
std::atomic<std::size_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace tripodal;

// Args: weighted (0 = priority, 1 = weighted sum), omni (0 = differential, 1 = 3-wheel omni).
static void BM_ReactiveCycle(benchmark::State& state) {
  const auto mode = state.range(0) != 0 ? CoordinationMode::weighted_sum : CoordinationMode::priority;
  test::ReactiveRig rig(state.range(1) != 0 ? test::omni_base_psr() : test::differential_base(), mode);
  rig.activate_eight();
  for (int i = 0; i < 10; ++i) rig.cycle();
  if (rig.loop->last_cycle().active_behaviors != 8) state.SkipWithError("expected 8 active behaviors");
  const std::size_t before = g_allocations.load();
  for (auto _ : state) {
    benchmark::DoNotOptimize(rig.cycle());
  }
  state.counters["allocs_per_cycle"] =
      static_cast<double>(g_allocations.load() - before) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_ReactiveCycle)->ArgNames({"weighted", "omni"})->Args({0, 0})->Args({1, 0})->Args({0, 1})->Args({1, 1});
// The instruction-count guard's twins (bench/instructions.yaml).
[[maybe_unused]] static const bool kTwins[] = {
    tripodal::bench::register_instruction_twin("BM_ReactiveCycle/priority/differential", BM_ReactiveCycle, {0, 0}),
    tripodal::bench::register_instruction_twin("BM_ReactiveCycle/weighted/differential", BM_ReactiveCycle, {1, 0}),
    tripodal::bench::register_instruction_twin("BM_ReactiveCycle/priority/omni", BM_ReactiveCycle, {0, 1}),
    tripodal::bench::register_instruction_twin("BM_ReactiveCycle/weighted/omni", BM_ReactiveCycle, {1, 1}),
};

static void BM_CoordinatorFuse(benchmark::State& state) {
  const auto mode = state.range(0) != 0 ? CoordinationMode::weighted_sum : CoordinationMode::priority;
  CBehaviorCoordinator co(test::eight_inputs(mode));
  VelocityEnvelope env;
  env.vx_hi_m_s = 0.3;
  Time now{};
  for (auto _ : state) {
    now += std::chrono::milliseconds(10);
    co.submit_envelope(0, env, now);
    co.submit_envelope(1, env, now);
    for (InputId i = 2; i < 8; ++i) co.submit(i, {0.1 * i, 0.05, 0.2}, now);
    co.set_lock(0, false, now);
    benchmark::DoNotOptimize(co.update(now));
  }
}
BENCHMARK(BM_CoordinatorFuse)->ArgName("weighted")->Arg(0)->Arg(1);
[[maybe_unused]] static const bool kFuseTwin =
    tripodal::bench::register_instruction_twin("BM_CoordinatorFuse/weighted", BM_CoordinatorFuse, {1});

static void BM_ControllerUpdate(benchmark::State& state) {
  const ControllerConfig config = state.range(0) != 0 ? test::omni_base_psr() : test::differential_base();
  IdealWheelHardware hw(config.type == "differential" ? 2 : 3, config.period);
  ControllerRegistry controllers;
  register_builtin_controllers(controllers);
  auto ctl = controllers.create(config, hw);
  Time now{};
  for (auto _ : state) {
    now += config.period;
    ctl->set_command({0.5, 0.2, 0.7}, now);
    benchmark::DoNotOptimize(ctl->update(now));
  }
}
BENCHMARK(BM_ControllerUpdate)->ArgName("omni")->Arg(0)->Arg(1);
[[maybe_unused]] static const bool kControllerTwin =
    tripodal::bench::register_instruction_twin("BM_ControllerUpdate/omni", BM_ControllerUpdate, {1});

BENCHMARK_MAIN();
