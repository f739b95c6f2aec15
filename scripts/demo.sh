#!/usr/bin/env bash
# The README's demo command: installs dependencies, builds tripodal (Release) and runs the demo.
# Until the simulator lands, the demo is the paper's process PrCleaning (configs/petri/PrCleaning.xml,
# Fig. 3 / Table 2) run by `tripodal-net simulate` through three narratives: a normal run, a
# temporary localization loss with a recovery, and a persistent loss that ends in the fault place.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build/release}
scripts/install-deps.sh
generator=()
if command -v ninja >/dev/null; then generator=(-G Ninja); fi
cmake -S . -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DTRIPODAL_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target tripodal-net
net_tool="$build/tools/tripodal-net/tripodal-net"
nets=configs/petri
scenarios=$nets/scenarios

echo
echo "== tripodal-net check $nets/*"
"$net_tool" check "$nets"/*

run() {
  local title=$1 wheel=$2 script=$3
  echo
  echo "== $title (wheel_type=$wheel)"
  grep '^#' "$scenarios/$script" | sed 's/^# \{0,1\}/   /'
  echo "   script:"
  grep -v '^#' "$scenarios/$script" | sed '/^[[:space:]]*$/d; s/^/     /'
  echo
  "$net_tool" simulate "$nets/PrCleaning.xml" --param "wheel_type=$wheel" --events "$scenarios/$script"
}

run "PrCleaning: normal completion" omni PrCleaning-omni-normal.events
run "PrCleaning: temporary localization loss, the robot pauses, then recovers" omni \
  PrCleaning-omni-temporary-loss.events
run "PrCleaning: persistent localization loss ends in the fault place" omni \
  PrCleaning-omni-persistent-loss.events
run "PrCleaning on a differential base: persistent localization loss" differential \
  PrCleaning-differential-persistent-loss.events

echo
echo "Draw a net like the paper's Fig. 3:  $net_tool dot $nets/PrCleaning.xml | dot -Tsvg > PrCleaning.svg"
