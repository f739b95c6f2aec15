#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (.ci/run runs it after the
# README's scripts/test.sh). Build tree: $BUILD_ROOT/sanitize (default build/sanitize).
set -euo pipefail
cd "$(dirname "$0")/.."
stage() { echo "== $* [$(date -u +%T), ${SECONDS} s]"; }
root=$(pwd)
build_root=${BUILD_ROOT:-$root/build}
jobs=${JOBS:-$(nproc)}

scripts/install-deps.sh

generator=()
if command -v ninja >/dev/null; then generator=(-G Ninja); fi

stage "AddressSanitizer + UndefinedBehaviorSanitizer build"
# -O1 -g1 (line tables): the sanitizers' reports keep their file:line, and the tree compiles in half
# the time of -O2 -g (27 s against 13 s for robot_monitor.cpp), which CI's budget needs. The tests'
# own sources at -O0 halve their share again (TRIPODAL_TEST_CXX_FLAGS in CMakeLists.txt).
cmake -S . -B "$build_root/sanitize" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  -DTRIPODAL_WERROR=ON -DTRIPODAL_SANITIZE=ON -DTRIPODAL_BUILD_TESTS=ON -DTRIPODAL_BUILD_BENCH=OFF \
  -DTRIPODAL_TEST_CXX_FLAGS=-O0
cmake --build "$build_root/sanitize" -j "$jobs"
stage "Sanitizer tests"
# -LE long: the whole-workspace runs that repeat code another run drives (tests/app/CMakeLists.txt).
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$build_root/sanitize" --output-on-failure -j "$jobs" -LE long
