// Fixed-iteration twins of the key benchmarks, for the instruction-count guard: scripts/instructions.sh
// runs each twin under callgrind at two iteration counts and compares the instructions per iteration
// with bench/instructions.yaml (docs/performance.md, "Instruction-count guard").
#pragma once

#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

namespace tripodal::bench {

// Registers "instructions/<name>" (fn with args) to run exactly $TRIPODAL_INSTRUCTION_ITERATIONS
// iterations, once. Only when that variable is set, so that ordinary benchmark runs never see the
// twins. Google Benchmark 1.7 (Debian) has no command-line iteration count (--benchmark_min_time=Nx
// came in 1.8), hence a registration of its own. Returns whether the twin was registered.
inline bool register_instruction_twin(const std::string& name, void (*fn)(benchmark::State&),
                                      const std::vector<std::int64_t>& args = {}) {
  const char* iterations = std::getenv("TRIPODAL_INSTRUCTION_ITERATIONS");
  if (iterations == nullptr) return false;
  const long long n = std::strtoll(iterations, nullptr, 10);
  if (n <= 0) return false;
  benchmark::internal::Benchmark* b = benchmark::RegisterBenchmark(("instructions/" + name).c_str(), fn);
  if (!args.empty()) b->Args(args);
  b->Iterations(static_cast<benchmark::IterationCount>(n));
  return true;
}

}  // namespace tripodal::bench
