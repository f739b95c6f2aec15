#!/usr/bin/env bash
# Runs clang-tidy with the project's .clang-tidy on every source under src/ and tools/ (the
# compile commands of a Release configure in $BUILD_ROOT/tidy). Fails on any warning of an
# enabled check; .clang-tidy says which checks are off and why.
#
#   scripts/tidy.sh                 every translation unit (about 150; 30-60 min of CPU: clang-tidy
#                                   walks the whole AST of each, the standard library's included)
#   scripts/tidy.sh --since REV     only those that differ from REV: a changed source, or one that
#                                   includes (directly or not) a changed header, or one whose
#                                   compile command differs from REV's (.ci/tidy-flags.json); every
#                                   unit when .clang-tidy or cmake/ changed, or REV is not an
#                                   ancestor of HEAD. CI passes the commit of .ci/tidy-clean, the
#                                   last one whose whole tree was clean (see that file).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
build="${BUILD_ROOT:-$root/build}/tidy"
jobs=${JOBS:-$(nproc)}
since=""
if [[ ${1:-} == --since ]]; then
  since=${2:?"tidy.sh: --since needs a commit"}
fi

scripts/install-deps.sh tidy

# Only the compile commands are needed: nothing is built but generated headers (below).
# No precompiled headers: clang cannot read g++'s, and each unit must compile from its own includes.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTRIPODAL_BUILD_TESTS=OFF \
  -DTRIPODAL_BUILD_BENCH=OFF -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON >/dev/null
# Headers generated at build time (the dds area's idlc output) must exist for the sources that
# include them. The target list is read whole first: `ninja ... | grep -q` under pipefail fails
# whenever grep exits before ninja has written everything (SIGPIPE), and the headers were then
# silently not generated.
targets=$(ninja -C "$build" -t targets all)
if grep -q '^tripodal_dds_idl:' <<<"$targets"; then
  cmake --build "$build" --target tripodal_dds_idl >/dev/null
fi
# The units to check: run-clang-tidy takes regular expressions of file names.
units=("$root/src/" "$root/tools/")
if [[ -n $since ]]; then
  # Read whole first, so that a failure of the script fails this one (set -e).
  list=$(scripts/tidy_units.py --build "$build" --since "$since")
  units=()
  if [[ -n $list ]]; then mapfile -t units <<<"$list"; fi
  if [[ ${#units[@]} -eq 0 ]]; then
    echo "tidy: clean (no translation unit differs from $since; ${SECONDS} s)"
    exit 0
  fi
  echo "tidy: ${#units[@]} translation units differ from $since"
fi
log="$build/tidy.log"
# -Wno-unknown-warning-option: the commands are g++'s, whose -Wno-restrict clang does not know.
run-clang-tidy -quiet -j "$jobs" -p "$build" -extra-arg=-Wno-unknown-warning-option \
  "${units[@]}" 2>&1 | sed 's/\x1b\[[0-9;]*m//g' >"$log" || true
warnings=$(grep -cE '^/.*: (warning|error): ' "$log" || true)
if [[ $warnings -ne 0 ]]; then
  grep -E '^/.*: (warning|error): ' "$log" | sort -u
  echo "tidy: $warnings findings (full output: $log; ${SECONDS} s)" >&2
  exit 1
fi
if [[ -n $since ]]; then
  echo "tidy: clean (${#units[@]} translation units that differ from $since, ${SECONDS} s)"
else
  echo "tidy: clean ($(grep -c '"file"' "$build/compile_commands.json") translation units, ${SECONDS} s)"
fi
