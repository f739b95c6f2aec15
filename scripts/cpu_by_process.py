#!/usr/bin/env python3
"""Runs a command and reports the CPU time of it and each of its descendants (docs/distribution.md,
"Where the fleet's CPU goes"): the speed-up a fleet would have on a machine with enough cores.

Usage: scripts/cpu_by_process.py [--label-arg OPTION] -- COMMAND [ARGS...]

Every 0.1 s it reads /proc/PID/stat (utime + stime) of the command's process tree; a process's
figure is its last sample (it may miss up to 0.1 s of CPU at its end). Processes are named by their
second and following argv words' first words: `tripodal run --robot .../robot3.yaml` is named by
--label-arg's value (default --robot: robot3.yaml), `tripodal sim-server` by its subcommand.
Prints one line per process and the totals, then exits with the command's exit code.
"""
import os
import subprocess
import sys
import time

TICK = os.sysconf("SC_CLK_TCK")


def stat_of(pid):
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            data = f.read().decode(errors="replace")
    except OSError:
        return None
    rest = data[data.rindex(")") + 2:].split()
    ppid = int(rest[1])
    cpu_s = (int(rest[11]) + int(rest[12])) / TICK  # utime + stime
    return ppid, cpu_s


def cmdline_of(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return [w.decode(errors="replace") for w in f.read().split(b"\0") if w]
    except OSError:
        return []


def label(argv, label_arg):
    if label_arg in argv and argv.index(label_arg) + 1 < len(argv):
        return os.path.basename(argv[argv.index(label_arg) + 1])
    words = [os.path.basename(argv[0])] + argv[1:2] if argv else ["?"]
    return " ".join(words)


def main():
    args = sys.argv[1:]
    label_arg = "--robot"
    if args[:1] == ["--label-arg"]:
        label_arg, args = args[1], args[2:]
    if args[:1] == ["--"]:
        args = args[1:]
    if not args:
        print(__doc__, file=sys.stderr)
        return 2
    began = time.monotonic()
    child = subprocess.Popen(args)
    seen = {}  # pid -> [label, cpu_s]
    while child.poll() is None:
        parents = {}
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                s = stat_of(int(entry))
                if s is not None:
                    parents[int(entry)] = s
        tree = {child.pid}
        grew = True
        while grew:
            grew = False
            for pid, (ppid, _) in parents.items():
                if ppid in tree and pid not in tree:
                    tree.add(pid)
                    grew = True
        for pid in tree:
            if pid not in parents:
                continue
            if pid not in seen:
                seen[pid] = [label(cmdline_of(pid), label_arg), 0.0]
            seen[pid][1] = parents[pid][1]
        time.sleep(0.1)
    wall = time.monotonic() - began
    total = 0.0
    for pid, (name, cpu) in sorted(seen.items(), key=lambda kv: kv[1][0]):
        print(f"cpu {name}: {cpu:.2f} s")
        total += cpu
    print(f"cpu total: {total:.2f} s over {len(seen)} processes; wall {wall:.1f} s")
    return child.returncode


if __name__ == "__main__":
    sys.exit(main())
