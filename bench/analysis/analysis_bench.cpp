// State-space exploration speed: states per second and bytes per stored state on Kanban (N
// kanbans per stage), token rings and dining philosophers, under interleaving semantics (all of
// these are plain P/T nets, as the published state counts assume); and check/analyze time
// against the size of a net with a linear state space (chains of 1,000 to 100,000 places). Bounds from the place
// invariants are given, as `tripodal-net analyze` does, so markings are packed to the bit.
#include <benchmark/benchmark.h>

#include "../../tests/analysis/analysis_test_nets.hpp"
#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/analysis/invariants.hpp"
#include "tripodal/analysis/state_space.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

namespace {

void run(benchmark::State& state, const PetriNet& net, std::size_t expected_states) {
  ExploreOptions options;
  options.semantics = Semantics::interleaving;
  options.place_bounds = structural_bounds(net, place_invariants(net));
  std::size_t states = 0;
  double bytes_per_state = 0;
  std::size_t bytes_per_marking = 0;
  std::size_t edges = 0;
  for (auto _ : state) {
    const StateSpace s = explore(net, options);
    states = s.states();
    edges = s.edges();
    bytes_per_state = s.bytes_per_state();
    bytes_per_marking = s.bytes_per_marking();
    benchmark::DoNotOptimize(states);
  }
  if (expected_states != 0 && states != expected_states) state.SkipWithError("unexpected state count");
  state.SetItemsProcessed(static_cast<std::int64_t>(states) * state.iterations());
  state.counters["states"] = static_cast<double>(states);
  state.counters["edges"] = static_cast<double>(edges);
  state.counters["bytes_per_state"] = bytes_per_state;
  state.counters["marking_bytes"] = static_cast<double>(bytes_per_marking);
  state.counters["states_per_s"] =
      benchmark::Counter(static_cast<double>(states) * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_Kanban(benchmark::State& state) {
  static constexpr std::size_t kStates[] = {0, 160, 4600, 58400, 454475, 2546432};
  const auto n = static_cast<Tokens>(state.range(0));
  run(state, test::kanban_net(n), kStates[n]);
}
BENCHMARK(BM_Kanban)->Arg(2)->Arg(3)->Arg(4)->Arg(5)->Unit(benchmark::kMillisecond);

void BM_Ring(benchmark::State& state) {
  // 16 places, 8 tokens: C(23, 8) = 490,314 states; 20 places, 7 tokens: C(26, 7) = 657,800.
  const auto places = static_cast<std::size_t>(state.range(0));
  const auto tokens = static_cast<Tokens>(state.range(1));
  const std::size_t expected = places == 16 ? 490'314 : 657'800;
  run(state, test::ring_of_tokens(places, tokens), expected);
}
BENCHMARK(BM_Ring)->Args({16, 8})->Args({20, 7})->Unit(benchmark::kMillisecond);

void BM_Philosophers(benchmark::State& state) {
  run(state, test::philosophers_net(static_cast<std::size_t>(state.range(0))), 0);
}
BENCHMARK(BM_Philosophers)->Arg(10)->Arg(13)->Unit(benchmark::kMillisecond);

// What `tripodal-net check` runs on a loaded net (check_behaviour: Karp–Miller where the net is
// small enough, exploration with edges, the outcome check), on chains of n places: n states, so
// the time should grow linearly with n (issue 32: 10,000 places in well under a second).
void BM_CheckChain(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const PetriNet net = test::chain_net(n);
  BehaviourCheckOptions options;
  options.max_states = n;  // above the default of 200,000 for the largest size
  for (auto _ : state) {
    Diagnostics d;
    if (!check_behaviour(net, d, options)) state.SkipWithError("the chain did not pass the check");
    benchmark::DoNotOptimize(d);
  }
  state.SetComplexityN(state.range(0));
  state.counters["places"] = static_cast<double>(n);
  state.counters["us_per_place"] = benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert,
                                                      benchmark::Counter::kIs1000);
}
BENCHMARK(BM_CheckChain)->Arg(1'000)->Arg(10'000)->Arg(100'000)->Unit(benchmark::kMillisecond)->Complexity();

// The full analysis (report included) of the same chains: invariants and Karp–Miller run up to
// AnalysisOptions::max_structural_size places + transitions, then are skipped.
void BM_AnalyzeChain(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  const PetriNet net = test::chain_net(n);
  for (auto _ : state) {
    const AnalysisReport r = analyze(net);
    if (!r.ok() || r.states != n) state.SkipWithError("unexpected analysis of the chain");
    benchmark::DoNotOptimize(r.states);
  }
  state.counters["places"] = static_cast<double>(n);
}
BENCHMARK(BM_AnalyzeChain)->Arg(1'000)->Arg(10'000)->Arg(100'000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
