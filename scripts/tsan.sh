#!/usr/bin/env bash
# Builds the test suites whose tests use threads with ThreadSanitizer (-DTRIPODAL_TSAN=ON, g++) and
# runs the tests tagged [threads]: LoopRunner, the process supervisor's inbox fed from module
# threads, Robot::start/stop with a command from another thread, SourceFile interning, the monitor's
# server thread against the robot's, the RKMS store written from two threads, the wall-clock
# runtime (PeriodicRunner, the lock-free resource snapshot and seqlock, PSR-2 cleaning on its own
# threads at 20x, a starved loop's deadline fault, Jinny answering a visitor and guiding at 10x), and
# the disinfection robot on its threads against its board and lidar in a forked process over ptys,
# unplugged mid-run (BoardMonitor reading the link through the snapshot) and with the lidar's motor
# stopped (the laser's fault within its timeout). A data race
# or a lock-order inversion fails the run (halt_on_error). Build tree: $BUILD_ROOT/tsan.
#
# A new threaded component (a DDS transport) joins by tagging its tests
# [threads] and adding its suite to `suites` below.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build="${BUILD_ROOT:-$root/build}/tsan"
jobs=${JOBS:-$(nproc)}
suites=(tripodal_core_tests tripodal_reactive_tests tripodal_processes_tests tripodal_robot_tests tripodal_monitor_tests tripodal_hri_tests
        tripodal_board_devices_tests)

scripts/install-deps.sh

# -O1 -g1 as in the ASan+UBSan build of scripts/test.sh: reports with file:line, half the compile time.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  -DTRIPODAL_TSAN=ON -DTRIPODAL_WERROR=ON -DTRIPODAL_TEST_CXX_FLAGS=-O0 \
  -DTRIPODAL_BUILD_TESTS=ON -DTRIPODAL_BUILD_TOOLS=OFF -DTRIPODAL_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "$jobs" --target "${suites[@]}"
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$root/scripts/tsan.supp"
for suite in "${suites[@]}"; do
  exe=$(find "$build/tests" -type f -name "$suite" -perm -u+x | head -n 1)
  echo "== $suite [threads] under ThreadSanitizer"
  "$exe" "[threads]"
done
echo "tsan: no data race in the [threads] tests of ${#suites[@]} suites"
