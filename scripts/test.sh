#!/usr/bin/env bash
# The README's test command, the quick path a newcomer runs: installs dependencies, then
#   1. a Release build with -Werror and the whole test suite (ctest; the tests' own sources at -O1,
#      36 % less compile time than -O3 for no run time: the library keeps -O3),
#   2. the example consumer, the behavior tutorial's tests (examples/behavior_test) and the
#      application robot (examples/custom_robot) built against the *installed* package
#      (find_package(tripodal)), and the DDS consumer (examples/dds_consumer) when the package has dds.
# The slower passes are their own scripts, which .ci/run runs after this one: scripts/sanitize.sh
# (the suite under AddressSanitizer + UndefinedBehaviorSanitizer), scripts/fuzz.sh, scripts/tsan.sh
# and scripts/tidy.sh. Every tree compiles through ccache when it is installed (CMakeLists.txt).
# Build trees go to build/release, build/consumer, build/behavior_test, build/custom_robot,
# build/dds_consumer (override with BUILD_ROOT).
set -euo pipefail
cd "$(dirname "$0")/.."
# Each step prints the wall time since the start: CI's budget is read from these lines.
stage() { echo "== $* [$(date -u +%T), ${SECONDS} s]"; }
root=$(pwd)
build_root=${BUILD_ROOT:-$root/build}
jobs=${JOBS:-$(nproc)}

scripts/install-deps.sh

generator=()
if command -v ninja >/dev/null; then generator=(-G Ninja); fi

stage "Release build (-Werror)"
cmake -S . -B "$build_root/release" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DTRIPODAL_WERROR=ON -DTRIPODAL_BUILD_TESTS=ON -DTRIPODAL_BUILD_BENCH=ON \
  -DTRIPODAL_TEST_CXX_FLAGS=-O1 -DCMAKE_INSTALL_PREFIX="$build_root/install"
cmake --build "$build_root/release" -j "$jobs"
stage "Release tests"
ctest --test-dir "$build_root/release" --output-on-failure -j "$jobs"

stage "Install and build the example consumer against the installed package"
rm -rf "$build_root/install"
cmake --install "$build_root/release" >/dev/null
cmake -S examples/consumer -B "$build_root/consumer" "${generator[@]}" \
  -DCMAKE_PREFIX_PATH="$build_root/install" -DCMAKE_COMPILE_WARNING_AS_ERROR=ON
cmake --build "$build_root/consumer" -j "$jobs"
"$build_root/consumer/tripodal_consumer"
stage "Build and run the behavior tutorial's tests (trace replay, closed loop) against the installed package"
cmake -S examples/behavior_test -B "$build_root/behavior_test" "${generator[@]}" \
  -DCMAKE_PREFIX_PATH="$build_root/install" -DCMAKE_COMPILE_WARNING_AS_ERROR=ON
cmake --build "$build_root/behavior_test" -j "$jobs"
"$build_root/behavior_test/bh_approach_test"
"$build_root/behavior_test/bh_approach_robot_test"
stage "Build and run the application robot (examples/custom_robot) against the installed package"
cmake -S examples/custom_robot -B "$build_root/custom_robot" "${generator[@]}" \
  -DCMAKE_PREFIX_PATH="$build_root/install" -DCMAKE_COMPILE_WARNING_AS_ERROR=ON
cmake --build "$build_root/custom_robot" -j "$jobs"
# The application's program, and its plugin through the installed `tripodal run` (report, map).
ctest --test-dir "$build_root/custom_robot" --output-on-failure

if [ -d "$build_root/install/include/tripodal/dds" ]; then
  stage "Build and run the DDS consumer (find_package(tripodal COMPONENTS dds)) against the installed package"
  cmake -S examples/dds_consumer -B "$build_root/dds_consumer" "${generator[@]}" \
    -DCMAKE_PREFIX_PATH="$build_root/install" -DCMAKE_COMPILE_WARNING_AS_ERROR=ON
  cmake --build "$build_root/dds_consumer" -j "$jobs"
  "$build_root/dds_consumer/tripodal_dds_consumer"
fi
