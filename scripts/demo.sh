#!/usr/bin/env bash
# The README's demo command: installs dependencies, builds tripodal (Release) and runs the paper's
# cleaning task end to end in the embedded simulator: PSR-2 (omni-directional base) cleans room
# 3211 (10 m x 32 m, four sections) with `tripodal run`; then the same task in the faults world: the
# cleaning behavior detours around a cart on its path, and after a localization loss the planner
# inserts PrGlobalLocalization and the task still completes.
# Pictures, trajectories and reports go to demo-out/ (DEMO_OUT to change). DEMO_ALL=1 also runs
# the two-wheel differential robot; DEMO_NETS=1 also replays the PrCleaning net narratives.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build/release}
out=${DEMO_OUT:-demo-out}
scripts/install-deps.sh
generator=()
if command -v ninja >/dev/null; then generator=(-G Ninja); fi
cmake -S . -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DTRIPODAL_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target tripodal tripodal-net
tool="$build/tools/tripodal/tripodal"
world=configs/worlds/workspace.yaml

echo
echo "== PSR-2 (omni): clean the room 3211"
"$tool" run --robot configs/robots/psr2.yaml --world "$world" --task "clean the room 3211" --seed 1 --out "$out/psr2"

echo
echo "== PSR-2 in the faults world: a cart on its path, the laser dazzled at 60-64 s and dead at 90-92 s, the robot kidnapped at 150 s"
"$tool" run --robot configs/robots/psr2.yaml --world configs/worlds/workspace_faults.yaml --task "clean the room 3211" \
  --seed 1 --out "$out/psr2-faults"

if [ "${DEMO_ALL:-0}" = 1 ]; then
  echo
  echo "== Two-wheel differential robot (BhCleaningTwoWheel by the net's wheel_type): clean the room 3211"
  "$tool" run --robot configs/robots/jinny_differential.yaml --world "$world" --task "clean the room 3211" --seed 1 \
    --out "$out/differential"
fi

if [ "${DEMO_NETS:-0}" = 1 ]; then
  net_tool="$build/tools/tripodal-net/tripodal-net"
  nets=configs/petri
  for s in PrCleaning-omni-normal PrCleaning-omni-temporary-loss PrCleaning-omni-persistent-loss; do
    echo
    echo "== tripodal-net simulate PrCleaning.xml --events $s.events"
    "$net_tool" simulate "$nets/PrCleaning.xml" --param wheel_type=omni --events "$nets/scenarios/$s.events"
  done
fi

echo
echo "Pictures: $out/*/map.png (sections tinted, cleaned cells green, missed reachable cells red, path blue)."
echo "Reports:  $out/*/report.json; trajectories: $out/*/trajectory.csv; life cycles: $out/*/lifecycle.txt."
echo "Watch one in real time (10x):  $tool run --robot configs/robots/psr2.yaml --world $world --task \"clean the room 3211\" --realtime 10"
