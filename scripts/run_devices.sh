#!/usr/bin/env bash
# Runs the disinfection robot against its devices in another process, as it would run on the
# navigation board: tripodal-board-sim serves the control board and the RPLIDAR A1 on two
# pseudo-terminals from one world (docs/board-protocol.md, docs/lidar.md), and
# `tripodal run --hardware-param port=... --hardware-param lidar_port=... --realtime` opens them
# as it would /dev/ttyUSB0 and /dev/ttyUSB1, at wall-clock time (room 2111: about 9 minutes).
#
# usage: scripts/run_devices.sh [BUILD_DIR] [-- EXTRA tripodal run OPTIONS]
#   BUILD_DIR   a build tree with the tools (default build/release)
#   TASK        environment: the task (default "disinfect the room 2111")
#   OUT         environment: where report.json, devices.json, map.png go (default out/devices)
#   ROBOT       environment: the robot profile (default configs/robots/disinfection_lidar.yaml)
#   SPEED       environment: the devices and the robot both at SPEED times the wall clock (default
#               1): tripodal-board-sim --speed SPEED, tripodal run --realtime SPEED; the line's byte
#               timing, the board's watchdog and the host's link timeouts scale alike (room 2111 at
#               4x: about 2.5 minutes on a loaded machine)
#   RESPONSE_TIMEOUT_S, MAX_MISSED  environment: the link's tolerance of late answers (default the
#               profile's, a Linux host's without real-time scheduling: 0.05 s and 4; a navigation
#               board with SCHED_FIFO may use 0.01 s and 1)
# Unplug and replug: kill the device simulator (its pid is printed) and start it again with the
# same command: the robot posts board.link_lost, stands still, reconnects and resumes.
# On the real robot: no simulator; give the ports the devices have, e.g.
#   tripodal run --robot configs/robots/disinfection_lidar.yaml --world configs/worlds/workspace.yaml \
#     --hardware-param port=/dev/ttyUSB0 --hardware-param lidar_port=/dev/ttyUSB1 --realtime \
#     --task "disinfect the room 2111"
set -euo pipefail
cd "$(dirname "$0")/.."
build=build/release
if [[ $# -gt 0 && $1 != -- ]]; then
  build=$1
  shift
fi
[[ ${1:-} == -- ]] && shift
task=${TASK:-disinfect the room 2111}
out=${OUT:-out/devices}
robot=${ROBOT:-configs/robots/disinfection_lidar.yaml}
world=configs/worlds/workspace.yaml
speed=${SPEED:-1}
tripodal=$build/tools/tripodal/tripodal
board_sim=$build/tools/tripodal-board-sim/tripodal-board-sim
for exe in "$tripodal" "$board_sim"; do
  [[ -x $exe ]] || { echo "run_devices.sh: $exe is not built (cmake --build $build --target tripodal tripodal-board-sim)" >&2; exit 2; }
done

dev=$(mktemp -d /tmp/tripodal-devices.XXXXXX)
sim_pid=""
cleanup() {
  if [[ -n $sim_pid ]]; then kill "$sim_pid" 2>/dev/null || true; wait "$sim_pid" 2>/dev/null || true; fi
  rm -rf "$dev"
}
trap cleanup EXIT
"$board_sim" --speed "$speed" --world "$world" --link "$dev/board" --lidar "$dev/lidar" --pose-file "$dev/pose.txt" >"$dev/board_sim.log" 2>&1 &
sim_pid=$!
for _ in $(seq 1 500); do
  [[ -e $dev/board && -e $dev/lidar ]] && break
  sleep 0.02
done
[[ -e $dev/board && -e $dev/lidar ]] || { echo "run_devices.sh: the device simulator made no ptys" >&2; cat "$dev/board_sim.log" >&2; exit 1; }
echo "run_devices.sh: device simulator pid $sim_pid: board on $dev/board, lidar on $dev/lidar"
echo "  (to replug: kill $sim_pid; $board_sim --speed $speed --world $world --link $dev/board --lidar $dev/lidar --pose-file $dev/pose.txt &)"
link=()
[[ -n ${RESPONSE_TIMEOUT_S:-} ]] && link+=(--hardware-param "response_timeout_s=$RESPONSE_TIMEOUT_S")
[[ -n ${MAX_MISSED:-} ]] && link+=(--hardware-param "max_missed=$MAX_MISSED")
echo "run_devices.sh: at ${speed}x; load average $(cut -d' ' -f1-3 /proc/loadavg) at the start"
rc=0
"$tripodal" run --robot "$robot" --world "$world" --hardware-param "port=$dev/board" --hardware-param "lidar_port=$dev/lidar" \
  "${link[@]}" --realtime "$speed" --task "$task" --out "$out" "$@" || rc=$?
echo "run_devices.sh: load average $(cut -d' ' -f1-3 /proc/loadavg) at the end"
kill -INT "$sim_pid" 2>/dev/null || true
wait "$sim_pid" 2>/dev/null || true
sim_pid=""
cat "$dev/board_sim.log"
exit "$rc"
