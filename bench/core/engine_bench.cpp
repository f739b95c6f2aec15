// Engine throughput: firings per second on rings of 10 and 10,000 places (one token circulating;
// the first transition is delayed by 1 ns so each step fires one full round), and events per
// second on a ring whose every transition waits for an event.
#include <benchmark/benchmark.h>

#include "instructions.hpp"
#include "../../tests/core/engine_test_nets.hpp"
#include "tripodal/core/engine.hpp"

using namespace tripodal;

namespace {

void BM_RingFirings(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  EngineOptions options;
  options.max_firings_per_instant = n + 1;
  Engine engine(test::ring_net(n, Duration{1}), {}, options);
  Time now{};
  std::size_t firings = 0;
  for (auto _ : state) {
    now += Duration{1};
    const StepResult& r = engine.step(now);
    firings += r.firings;
    benchmark::DoNotOptimize(r.firings);
  }
  if (firings != static_cast<std::size_t>(state.iterations()) * n) state.SkipWithError("unexpected firing count");
  state.SetItemsProcessed(static_cast<std::int64_t>(firings));
}
BENCHMARK(BM_RingFirings)->Arg(10)->Arg(10'000);
// The instruction-count guard's twins (bench/instructions.yaml).
[[maybe_unused]] const bool kRingTwin = tripodal::bench::register_instruction_twin("BM_RingFirings/10", BM_RingFirings, {10});

void BM_EventDispatch(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  PetriNet net = test::ring_net(n);
  for (TransitionIndex t = 0; t < net.transitions().size(); ++t) net.transition(t).event = "tick";
  Engine engine(net);
  const EventId tick = *engine.event_id("tick");
  Time now{};
  std::size_t firings = 0;
  for (auto _ : state) {
    now += Duration{1};
    const StepResult& r = engine.step(now, std::span<const EventId>(&tick, 1));
    firings += r.firings;
  }
  if (firings != static_cast<std::size_t>(state.iterations())) state.SkipWithError("an event was not consumed");
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_EventDispatch)->Arg(10)->Arg(10'000);
[[maybe_unused]] const bool kDispatchTwin = tripodal::bench::register_instruction_twin("BM_EventDispatch/10", BM_EventDispatch, {10});

// One firing per call, a supervisor's shape (issue 42: PNP's fireAll takes 128 ns per call of this
// shape; target <= 25 ns): a ring of 10 whose every transition waits 1 ns, stepped by 1 ns, so each
// step pops one timer and fires one transition. The per-call fixed cost of step() is most of it.
void BM_OneFiringStep(benchmark::State& state) {
  PetriNet net = test::ring_net(10);
  for (TransitionIndex t = 0; t < net.transitions().size(); ++t) net.transition(t).delay = Duration{1};
  Engine engine(net);
  Time now{};
  std::size_t firings = 0;
  for (auto _ : state) {
    now += Duration{1};
    const StepResult& r = engine.step(now);
    firings += r.firings;
    benchmark::DoNotOptimize(r.firings);
  }
  if (firings != static_cast<std::size_t>(state.iterations())) state.SkipWithError("not one firing per step");
  state.SetItemsProcessed(static_cast<std::int64_t>(firings));
}
BENCHMARK(BM_OneFiringStep);
[[maybe_unused]] const bool kOneFiringTwin = tripodal::bench::register_instruction_twin("BM_OneFiringStep", BM_OneFiringStep);

// Nothing enabled to fire: a step that only advances the time (most periods of a supervisor).
void BM_IdleStep(benchmark::State& state) {
  Engine engine(test::ring_net(10, Duration{std::chrono::hours(1)}));
  Time now{};
  for (auto _ : state) {
    now += Duration{1};
    benchmark::DoNotOptimize(engine.step(now).firings);
  }
}
BENCHMARK(BM_IdleStep);
[[maybe_unused]] const bool kIdleTwin = tripodal::bench::register_instruction_twin("BM_IdleStep", BM_IdleStep);

void BM_EventDispatchByName(benchmark::State& state) {
  PetriNet net = test::ring_net(10);
  for (TransitionIndex t = 0; t < net.transitions().size(); ++t) net.transition(t).event = "localizer.lost";
  Engine engine(net);
  Time now{};
  for (auto _ : state) {
    now += Duration{1};
    benchmark::DoNotOptimize(engine.step(now, {"localizer.lost"}).firings);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_EventDispatchByName);
[[maybe_unused]] const bool kByNameTwin = tripodal::bench::register_instruction_twin("BM_EventDispatchByName", BM_EventDispatchByName);

}  // namespace

BENCHMARK_MAIN();
