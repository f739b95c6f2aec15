#!/usr/bin/env bash
# Runs clang-tidy with the project's .clang-tidy on every source under src/ and tools/ (the
# compile commands of a Release configure in $BUILD_ROOT/tidy). Fails on any warning of an
# enabled check; .clang-tidy says which checks are off and why.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build="${BUILD_ROOT:-$root/build}/tidy"
jobs=${JOBS:-$(nproc)}

scripts/install-deps.sh tidy

# Only the compile commands are needed: nothing is built but generated headers (below).
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTRIPODAL_BUILD_TESTS=OFF \
  -DTRIPODAL_BUILD_BENCH=OFF >/dev/null
# Headers generated at build time (the dds area's idlc output) must exist for the sources that
# include them. The target list is read whole first: `ninja ... | grep -q` under pipefail fails
# whenever grep exits before ninja has written everything (SIGPIPE), and the headers were then
# silently not generated.
targets=$(ninja -C "$build" -t targets all)
if grep -q '^tripodal_dds_idl:' <<<"$targets"; then
  cmake --build "$build" --target tripodal_dds_idl >/dev/null
fi
log="$build/tidy.log"
# -Wno-unknown-warning-option: the commands are g++'s, whose -Wno-restrict clang does not know.
run-clang-tidy -quiet -j "$jobs" -p "$build" -extra-arg=-Wno-unknown-warning-option \
  "$root/src/" "$root/tools/" 2>&1 | sed 's/\x1b\[[0-9;]*m//g' >"$log" || true
warnings=$(grep -cE '^/.*: (warning|error): ' "$log" || true)
if [[ $warnings -ne 0 ]]; then
  grep -E '^/.*: (warning|error): ' "$log" | sort -u
  echo "tidy: $warnings findings (full output: $log; ${SECONDS} s)" >&2
  exit 1
fi
echo "tidy: clean ($(grep -c '"file"' "$build/compile_commands.json") translation units, ${SECONDS} s)"
