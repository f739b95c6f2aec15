#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, -DTRIPODAL_FUZZ=ON: clang, ASan + UBSan) and runs each one
# for SECONDS seconds, one after another, on a working corpus seeded from the project's own files
# (fuzz/seeds.txt). Prints one line per target: executions, coverage (cov, ft), corpus size.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]     default 20 s each (CI), every target
#   FUZZ_SECONDS=600 scripts/fuzz.sh          the same, by environment
#   FUZZ_SEED=1 scripts/fuzz.sh               libFuzzer's -seed (default 0: a new one each run)
#   FUZZ_RUNS=40000 FUZZ_SEED=1 scripts/fuzz.sh 30
#                                             CI: each target runs FUZZ_RUNS inputs from a fresh
#                                             corpus of the seeds (SECONDS only caps it); the same
#                                             seed replays the same inputs on one machine and
#                                             binary only (docs/fuzzing.md "Fuzzing in CI")
#
# Stops at the first target that finds a crash, a leak, a timeout or a failed property: the input
# is kept as build/fuzz/findings/<target>/crash-* (reproduce: build/fuzz/fuzz/fuzz_<target> FILE).
# The working corpus (build/fuzz/corpus/<target>) is kept between runs, so longer local runs build
# on shorter ones. Build tree: $BUILD_ROOT/fuzz (default build/fuzz).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build_root=${BUILD_ROOT:-$root/build}
build="$build_root/fuzz"
seconds=${FUZZ_SECONDS:-20}
if [[ $# -gt 0 && $1 =~ ^[0-9]+$ ]]; then seconds=$1; shift; fi
jobs=${JOBS:-$(nproc)}

scripts/install-deps.sh fuzz

cmake -S . -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Fuzz \
  "-DCMAKE_CXX_FLAGS_FUZZ=-O1 -gline-tables-only" -DTRIPODAL_FUZZ=ON \
  -DTRIPODAL_BUILD_TESTS=OFF -DTRIPODAL_BUILD_TOOLS=OFF -DTRIPODAL_BUILD_BENCH=OFF >/dev/null
# -Werror is left to the g++ builds: clang 14 warns differently, and this build checks inputs.
cmake --build "$build" -j "$jobs" --target fuzz_all

targets=("$@")
if [[ ${#targets[@]} -eq 0 ]]; then
  mapfile -t targets < <(sed -n 's/^\([a-z0-9_]*\):.*/\1/p' fuzz/seeds.txt)
fi

summary=()
for t in "${targets[@]}"; do
  exe="$build/fuzz/fuzz_$t"
  [[ -x $exe ]] || { echo "fuzz.sh: no target '$t' (see fuzz/seeds.txt)" >&2; exit 2; }
  corpus="$build/corpus/$t"
  runs_option=()
  if [[ -n ${FUZZ_RUNS:-} ]]; then
    # A bounded run: fresh corpus, given seed and count. A time cap can only cut it short.
    corpus="$build/fixed-corpus/$t"
    rm -rf "$corpus"
    # FUZZ_RUNS_<target> overrides the count for one slow target (CI: carmen, whose seed is a 9 MB
    # log), so that the whole sequence runs within the cap on a developer's machine too.
    runs_var="FUZZ_RUNS_$t"
    runs_option=(-runs="${!runs_var:-$FUZZ_RUNS}")
  fi
  findings="$build/findings/$t"
  mkdir -p "$corpus" "$findings"
  # Seeds: the files fuzz/seeds.txt lists for the target (missing optional ones are skipped).
  globs=$(sed -n "s/^$t:\(.*\)/\1/p" fuzz/seeds.txt)
  for g in $globs; do
    for f in $g; do [[ -f $f ]] && cp "$f" "$corpus/seed-$(basename "$f")"; done
  done
  echo "== fuzz_$t: ${FUZZ_RUNS:+$FUZZ_RUNS runs, at most }${seconds} s on $(ls "$corpus" | wc -l) inputs"
  log="$findings/last-run.log"
  # -malloc_limit_mb: any single allocation past 512 MiB is a finding (limits before allocation);
  # -timeout: one input taking 10 s is a finding (quadratic parsing, endless loops).
  if ! ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
      "$exe" "$corpus" -max_total_time="$seconds" "${runs_option[@]}" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=512 \
      -seed="${FUZZ_SEED:-0}" -artifact_prefix="$findings/" -print_final_stats=1 >"$log" 2>&1; then
    tail -n 60 "$log"
    echo "fuzz.sh: fuzz_$t found a problem; input kept in $findings/" >&2
    exit 1
  fi
  stats=$(grep -E '^#[0-9]+.*(DONE|pulse|NEW|REDUCE|INITED)' "$log" | tail -n 1 || true)
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  line=$(printf '%-16s %10s execs  %s' "$t" "$runs" "$(grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+/[0-9a-zA-Z]+' <<<"$stats")")
  echo "$line"
  summary+=("$line")
done

echo "== fuzz summary (${FUZZ_RUNS:+$FUZZ_RUNS runs, at most }${seconds} s per target)"
printf '%s\n' "${summary[@]}"
