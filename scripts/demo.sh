#!/usr/bin/env bash
# The README's demo command: installs dependencies, builds tripodal (Release) and runs the demo.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build/release}
scripts/install-deps.sh
generator=()
if command -v ninja >/dev/null; then generator=(-G Ninja); fi
cmake -S . -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DTRIPODAL_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target tripodal-net
"$build/tools/tripodal-net/tripodal-net" --help
