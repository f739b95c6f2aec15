// Engine throughput: firings per second on rings of 10 and 10,000 places (one token circulating;
// the first transition is delayed by 1 ns so each step fires one full round), and events per
// second on a ring whose every transition waits for an event.
#include <benchmark/benchmark.h>

#ifdef TRIPODAL_HAVE_PNP
#include <pnp/petrinet.h>
#endif

#include <vector>

#include "../../tests/core/engine_test_nets.hpp"
#include "instructions.hpp"
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

// The peer's side of the one-firing comparison (issue 42 item 2): Petri Net Plans' PetriNet::fireAll
// on the same ring of 10 places with one token, so each call fires one transition. PNP's net is a
// header-only template (not in Debian): bench/core/CMakeLists.txt uses it when PNP_INCLUDE_DIR holds
// pnp/petrinet.h (e.g. -DPNP_INCLUDE_DIR=PetriNetPlans/PNP/include), else the bench is skipped.
#ifdef TRIPODAL_HAVE_PNP
// PNP fills a net's place set through its XML instantiator only (a friend); a subclass builds the
// ring in code.
class PnpRing final : public PetriNetPlans::PetriNet<PetriNetPlans::Place, PetriNetPlans::Transition> {
 public:
  explicit PnpRing(std::size_t n) {
    std::vector<PetriNetPlans::Place*> ring;
    for (std::size_t i = 0; i < n; ++i) {
      // PNP's net owns its nodes as raw pointers (deleted by clearAll).
      ring.push_back(new PetriNetPlans::Place(i == 0 ? 1U : 0U));  // NOLINT(cppcoreguidelines-owning-memory)
      places.insert(ring.back());
    }
    for (std::size_t i = 0; i < n; ++i) {
      auto* t = new PetriNetPlans::Transition();  // NOLINT(cppcoreguidelines-owning-memory)
      transitions.insert(t);
      addEdge(ring[i], t);
      addEdge(t, ring[(i + 1) % n]);
    }
    resetInitialMarking();
  }
};
#endif

void BM_PnpFireAll(benchmark::State& state) {
#ifdef TRIPODAL_HAVE_PNP
  PnpRing net(10);
  std::size_t calls = 0;
  for (auto _ : state) {
    calls += net.fireAll() ? 1 : 0;
  }
  if (calls != static_cast<std::size_t>(state.iterations())) state.SkipWithError("a call fired nothing");
  state.SetItemsProcessed(static_cast<std::int64_t>(calls));
#else
  state.SkipWithError(
      "Petri Net Plans not found at configure time (not in Debian; -DPNP_INCLUDE_DIR=PetriNetPlans/PNP/include); "
      "issue 42's figure: 128 ns per one-firing fireAll");
#endif
}
BENCHMARK(BM_PnpFireAll);

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
