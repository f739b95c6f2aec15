#!/usr/bin/env bash
# The instruction-count guard (docs/performance.md, "Instruction-count guard"): the key benchmarks'
# twins (bench/instructions.hpp) run under callgrind at a fixed small iteration count, and their
# instructions per iteration are compared with the baselines in bench/instructions.yaml. Instruction
# counts do not move with the machine's load, so a regression is caught where wall time is noise.
#
#   scripts/instructions.sh                 check: a rise beyond 10 % fails naming the benchmark
#   scripts/instructions.sh --update 'why'  write the counts that moved (or are new) as the baselines,
#                                           'why' and today's date as their comment, and regenerate
#                                           the table in docs/performance.md; commit both with the
#                                           change that moved them
#   scripts/instructions.sh --only REGEX    only the benchmarks whose name matches
#
# Builds the benchmark programs in the Release tree build/release (the one scripts/test.sh
# configures with -DTRIPODAL_BUILD_BENCH=ON; configured here the same way when absent). Needs
# valgrind (scripts/install-deps.sh perf).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_ROOT:-$(pwd)/build}/release
jobs=${JOBS:-$(nproc)}

if ! command -v valgrind >/dev/null; then
  echo "instructions: valgrind is missing (scripts/install-deps.sh perf)" >&2
  exit 2
fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  generator=()
  if command -v ninja >/dev/null; then generator=(-G Ninja); fi
  cmake -S . -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DTRIPODAL_WERROR=ON \
    -DTRIPODAL_BUILD_TESTS=ON -DTRIPODAL_BUILD_BENCH=ON -DTRIPODAL_TEST_CXX_FLAGS=-O1 >/dev/null
elif ! grep -q '^TRIPODAL_BUILD_BENCH:BOOL=ON' "$build/CMakeCache.txt"; then
  cmake -S . -B "$build" -DTRIPODAL_BUILD_BENCH=ON >/dev/null
fi
# The programs named in the baselines, built by their target names.
targets=$(sed -n 's|^  binary: *[^#]*/\([A-Za-z0-9_]*\).*|\1|p' bench/instructions.yaml | sort -u)
# shellcheck disable=SC2086
cmake --build "$build" -j "$jobs" --target $targets
exec python3 scripts/instructions.py --build "$build" --baselines bench/instructions.yaml \
  --doc docs/performance.md --jobs "$jobs" "$@"
