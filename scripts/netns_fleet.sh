#!/usr/bin/env bash
# A fleet across hosts, the hosts being Linux network namespaces on this machine
# (docs/distribution.md, "A fleet across hosts"): one namespace for the fleet tool, one for the
# shared world's `tripodal sim-server`, one per robot, joined by veth pairs to a bridge in a hub
# namespace, with multicast discovery as on a LAN (Cyclone DDS on each host's eth0, 10.231.0.0/24).
# Nothing is added to the host's own network: every address is inside the namespaces, which the
# script removes when it ends.
#
# Faults per robot host, on the fleet's DDS domain only (the simulator's domain is the robots'
# bodies, not a network): --loss PCT drops that share of its packets both ways (nftables
# `numgen random`), --partition K:AT:FOR drops all of robot K's packets from AT to AT+FOR seconds
# after the robots started, then heals. --delay-ms needs `tc netem`; without it (these machines'
# kernel) it is skipped with a note. --secure puts DDS Security on the fleet's domain: keys made by
# `tripodal fleet-keys` in OUT/keys (robot1..N and the fleet tool's identity `fleet`), every
# robot's commands and events authenticated and encrypted across the veth network.
#
#   sudo scripts/netns_fleet.sh [--robots 4] [--loss 10] [--partition 2:10:30] [--grace-s 10]
#        [--task "clean the room 3211"] [--speed 50] [--domain 70] [--out DIR] [--build build/release]
#        [--secure] [--ci]   (CI: not root or no ip/nft: print SKIPPED and exit 0)
# Exit code: the fleet's (0 every unit done), 77 skipped, 2 bad arguments.
set -euo pipefail
cd "$(dirname "$0")/.."

robots=4 loss=0 partition="" delay_ms=0 grace_s=10 lease_s=5 speed=50 domain=70 ci=0
task="clean the room 3211" world=configs/worlds/workspace.yaml robot=configs/robots/psr2.yaml
build=build/release out="" timeout_s=600 keep=0 secure=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --robots) robots=$2; shift 2 ;;
    --loss) loss=$2; shift 2 ;;
    --partition) partition=$2; shift 2 ;;
    --delay-ms) delay_ms=$2; shift 2 ;;
    --grace-s) grace_s=$2; shift 2 ;;
    --lease-s) lease_s=$2; shift 2 ;;
    --task) task=$2; shift 2 ;;
    --world) world=$2; shift 2 ;;
    --robot) robot=$2; shift 2 ;;
    --speed) speed=$2; shift 2 ;;
    --domain) domain=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --timeout-s) timeout_s=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    --secure) secure=1; shift ;;
    --ci) ci=1; shift ;;
    *) echo "netns_fleet.sh: unknown argument '$1' (see the script's head)" >&2; exit 2 ;;
  esac
done

skip() {
  echo "SKIPPED: netns_fleet.sh: $*"
  exit 77
}
if [[ $(id -u) -ne 0 ]]; then
  [[ $ci -eq 1 ]] && skip "needs root to make network namespaces (ip netns); run as root"
  echo "netns_fleet.sh: needs root (network namespaces, nftables)" >&2; exit 2
fi
command -v ip >/dev/null || skip "no 'ip' (iproute2)"
command -v nft >/dev/null || skip "no 'nft' (Debian's nftables; scripts/install-deps.sh netns)"
tool=$(realpath "$build/tools/tripodal/tripodal")
[[ -x $tool ]] || { echo "netns_fleet.sh: no $tool (build the tripodal target)" >&2; exit 2; }
if ! ip netns add tfprobe_$$ 2>/dev/null; then skip "this kernel or container refuses network namespaces"; fi
ip netns del tfprobe_$$
[[ -n $out ]] || out=$(mktemp -d /tmp/tripodal-netns-XXXXXX)
mkdir -p "$out"
out=$(realpath "$out")

# Namespaces: tf_hub (the bridge), tf_fleet, tf_sim-server, tf_robot1..N; names the fleet's
# --launcher builds from its processes' names.
hosts=(fleet sim-server)
for ((k = 1; k <= robots; k++)); do hosts+=("robot$k"); done
cleanup() {
  [[ -n ${partition_pid:-} ]] && kill "$partition_pid" 2>/dev/null || true
  for h in "${hosts[@]}"; do ip netns del "tf_$h" 2>/dev/null || true; done
  ip netns del tf_hub 2>/dev/null || true
}
trap cleanup EXIT
cleanup
ip netns add tf_hub
ip -n tf_hub link add br0 type bridge mcast_snooping 0
ip -n tf_hub link set br0 up
addr=1
declare -A ip_of
for h in "${hosts[@]}"; do
  ip netns add "tf_$h"
  ip -n "tf_$h" link set lo up
  ip link add "v_$h" netns tf_hub type veth peer name eth0 netns "tf_$h"
  ip -n tf_hub link set "v_$h" master br0 up
  case $h in fleet) a=1 ;; sim-server) a=2 ;; *) a=$((10 + ${h#robot})) ;; esac
  ip_of[$h]=10.231.0.$a
  ip -n "tf_$h" addr add "10.231.0.$a/24" dev eth0
  ip -n "tf_$h" link set eth0 up
  ip -n "tf_$h" route add 224.0.0.0/4 dev eth0
done

# The fleet domain's UDP ports (7400 + 250 * domain ... + 249): discovery and, with participant
# indices, every participant's unicast data. The faults touch only these.
lo_port=$((7400 + 250 * domain)) hi_port=$((7400 + 250 * domain + 249))
faults="fleet domain $domain (UDP $lo_port-$hi_port)"
for ((k = 1; k <= robots; k++)); do
  ns=tf_robot$k
  ip netns exec "$ns" nft -f - <<EOF
table inet tripodal_faults {
  chain cut_in { }
  chain cut_out { }
  chain in { type filter hook input priority 0; policy accept;
    udp dport $lo_port-$hi_port numgen random mod 100 < $loss counter drop
    udp dport $lo_port-$hi_port jump cut_in
  }
  chain out { type filter hook output priority 0; policy accept;
    udp dport $lo_port-$hi_port numgen random mod 100 < $loss counter drop
    udp dport $lo_port-$hi_port jump cut_out
  }
}
EOF
done
if [[ $delay_ms -gt 0 ]]; then
  if ip netns exec tf_robot1 tc qdisc add dev eth0 root netem delay "${delay_ms}ms" 2>/dev/null; then
    for ((k = 2; k <= robots; k++)); do ip netns exec "tf_robot$k" tc qdisc add dev eth0 root netem delay "${delay_ms}ms"; done
    faults+=", ${delay_ms} ms delay on every robot host"
  else
    echo "note: no tc netem in this kernel: --delay-ms $delay_ms skipped"
  fi
fi
[[ $loss != 0 ]] && faults+=", ${loss} % loss each way on every robot host"

# Cyclone DDS on eth0 with multicast, as on a LAN; participant indices so that the fleet domain's
# ports are known; a 5 s lease: a silent host is seen within it.
export CYCLONEDDS_URI="<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"eth0\" multicast=\"true\"/></Interfaces><AllowMulticast>true</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>40</MaxAutoParticipantIndex><LeaseDuration>${lease_s} s</LeaseDuration></Discovery></Domain></CycloneDDS>"

# A partition: every packet of robot K on the fleet domain dropped (a drop rule in the `cut_in` / `cut_out`
# chains of its own host's rules), from AT to AT+FOR seconds, then healed.
if [[ -n $partition ]]; then
  IFS=: read -r pk pat pfor <<<"$partition"
  [[ $pk -ge 1 && $pk -le $robots ]] || { echo "netns_fleet.sh: --partition $partition: no robot $pk" >&2; exit 2; }
  faults+=", robot$pk cut off at $pat s for $pfor s"
  (
    sleep "$pat"
    ip netns exec "tf_robot$pk" nft add rule inet tripodal_faults cut_in drop
    ip netns exec "tf_robot$pk" nft add rule inet tripodal_faults cut_out drop
    echo "$(date +%T) partition: robot$pk cut off from the fleet" >>"$out/faults.log"
    sleep "$pfor"
    ip netns exec "tf_robot$pk" nft flush chain inet tripodal_faults cut_in
    ip netns exec "tf_robot$pk" nft flush chain inet tripodal_faults cut_out
    echo "$(date +%T) partition: robot$pk healed" >>"$out/faults.log"
  ) &
  partition_pid=$!
fi

# DDS Security: a fleet CA, an identity per robot and one for the fleet tool (an operator).
secure_args=()
if [[ $secure -eq 1 ]]; then
  rm -rf "$out/keys"
  fleet_keys=(--out "$out/keys" --operator fleet --domain "$domain")
  for ((k = 1; k <= robots; k++)); do fleet_keys+=(--robot "robot$k"); done
  "$tool" fleet-keys "${fleet_keys[@]}" >"$out/fleet_keys.log" || { cat "$out/fleet_keys.log" >&2; exit 2; }
  secure_args=(--keys "$out/keys")
  faults+=", DDS Security on the fleet domain"
fi

echo "netns_fleet: $robots robots in ${#hosts[@]} namespaces on bridge br0 (10.231.0.0/24); faults: $faults; out $out"
set +e
ip netns exec tf_fleet "$tool" fleet --robots "$robots" --world "$(realpath "$world")" --robot "$(realpath "$robot")" \
  --task "$task" --domain "$domain" --speed "$speed" --lease-s "$lease_s" --grace-s "$grace_s" --timeout-s "$timeout_s" \
  --shared-world --system-network --sim-system-network --launcher "ip netns exec tf_{name}" --out "$out" "${secure_args[@]}" | tee "$out/fleet.out"
rc=${PIPESTATUS[0]}
set -e
[[ -f $out/faults.log ]] && cat "$out/faults.log"
# What the loss rules dropped, per robot host (both ways): the loss is real, not a setting.
if [[ $loss != 0 ]]; then
  for ((k = 1; k <= robots; k++)); do
    n=$(ip netns exec "tf_robot$k" nft list table inet tripodal_faults | grep -o 'counter packets [0-9]*' | awk '{s += $3} END {print s + 0}')
    echo "loss: robot$k dropped $n packets of the fleet domain"
  done
fi
exit "$rc"
