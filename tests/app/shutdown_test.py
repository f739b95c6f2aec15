"""Shutdown is a tested path: starts the real `tripodal run` in one MODE, waits for the line on its
stdout that shows it is running, sends SIGNAL and checks that the run stopped in order: the exit
code (130 for SIGINT, 143 for SIGTERM when a task or visit was cut short; 0 for a served run that
was idle), report.json valid JSON naming the stop ("interrupted by SIGTERM"), the base commanded
zero at the end, and map.png a PNG (also when the run had no task: no cells, no path, no sections).

usage: shutdown_test.py TRIPODAL SOURCE_DIR MODE SIGNAL
MODE: task, realtime_task (the robot on its own threads, `--realtime 4`: the report also gives each
loop's period error and overruns), monitor_idle, monitor_task, board_pty, dds_profile, hardware_dds
(the simulator in a `tripodal sim-server` of its own), visit. Exit 77: skipped (a build without DDS for the DDS modes)."""
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time

SKIP = 77


def fail(message, output=""):
    print("FAIL: " + message)
    if output:
        print("---- output ----\n" + output)
    sys.exit(1)


def main():
    exe, source, mode, sig_name = sys.argv[1:5]
    sig = {"SIGINT": signal.SIGINT, "SIGTERM": signal.SIGTERM}[sig_name]
    work = tempfile.mkdtemp(prefix="tripodal_shutdown_")
    try:
        run(exe, source, mode, sig, sig_name, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def run(exe, source, mode, sig, sig_name, work):
    configs = os.path.join(source, "configs")
    robots, worlds = os.path.join(configs, "robots"), os.path.join(configs, "worlds")
    workspace = os.path.join(worlds, "workspace.yaml")
    out = os.path.join(work, "out")
    psr2 = os.path.join(robots, "psr2.yaml")
    # Each mode: the command, the line that shows the run is under way, and whether the signal
    # cuts a task or visit short (exit 128 + N, state "interrupted") or ends a served, idle run (0).
    # A behavior that drives the base is active: the signal comes a second later, the robot moving.
    running_task = r"activate Bh(Cleaning|AutoMove)\w*\("
    if mode == "task":
        cmd = ["run", "--robot", psr2, "--world", workspace, "--task", "clean the room 3211", "--seed", "1"]
        ready, cut = running_task, True
    elif mode == "realtime_task":
        cmd = ["run", "--robot", psr2, "--world", workspace, "--task", "clean the room 3211", "--seed", "1", "--realtime", "4"]
        ready, cut = running_task, True
    elif mode == "monitor_idle":  # the "task from the console" flow, no task ever given
        cmd = ["run", "--robot", psr2, "--world", workspace, "--monitor", "0"]
        ready, cut = r"monitor: http://", False
    elif mode == "monitor_task":
        cmd = ["run", "--robot", psr2, "--world", workspace, "--monitor", "0", "--realtime", "4", "--task", "clean the room 2111"]
        ready, cut = running_task, True
    elif mode == "board_pty":
        cmd = ["run", "--robot", os.path.join(robots, "disinfection.yaml"), "--world", workspace, "--task", "disinfect the room 2111",
               "--seed", "1", "--board", "pty"]
        ready, cut = running_task, True
    elif mode in ("dds_profile", "hardware_dds") and subprocess.run([exe, "sim-server", "--help"], capture_output=True).returncode != 0:
        print("skipped: this tripodal was built without DDS")  # sim-server is built with the dds area only
        sys.exit(SKIP)
    elif mode == "hardware_dds":
        ns, domain = "shutdown_hw_%d" % os.getpid(), str(100 + os.getpid() % 50)
        server = subprocess.Popen([exe, "sim-server", "--robot", psr2, "--world", workspace, "--namespace", ns, "--domain", domain,
                                   "--seed", "1", "--wait-s", "60"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        cmd = ["run", "--robot", psr2, "--world", workspace, "--task", "clean the room 2111", "--seed", "1", "--hardware", "dds",
               "--hardware-param", "namespace=" + ns, "--hardware-param", "domain_id=" + domain]
        ready, cut = running_task, True
    if mode == "dds_profile":
        # A copy of configs/ (the profile's files are relative to it) whose PSR-2 is on DDS, on a
        # domain of its own.
        copy = os.path.join(work, "configs")
        shutil.copytree(configs, copy)
        profile = os.path.join(copy, "robots", "psr2.yaml")
        domain = 100 + os.getpid() % 50
        with open(profile, "a") as f:
            f.write("dds: {domain_id: %d, namespace: shutdown_%d, loopback: true, tasks: false}\n" % (domain, os.getpid()))
        cmd = ["run", "--robot", profile, "--world", os.path.join(copy, "worlds", "workspace.yaml"), "--task", "clean the room 2111"]
        ready, cut = running_task, True
    elif mode == "visit":
        cmd = ["run", "--robot", os.path.join(robots, "jinny.yaml"), "--world", os.path.join(worlds, "exhibit_hall.yaml"), "--visit",
               os.path.join(configs, "visits", "exhibit_hall.yaml"), "--no-voice", "--monitor", "0", "--realtime", "2"]
        ready, cut = r"PrAutoMove\(goal=node1\) started", True
    elif mode not in ("task", "realtime_task", "monitor_idle", "monitor_task", "board_pty", "hardware_dds"):
        fail("unknown mode " + mode)
    cmd = [exe] + cmd + ["--out", out]

    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines, errors = [], []
    seen = threading.Event()

    def read_stdout():
        for line in proc.stdout:
            lines.append(line)
            if re.search(ready, line):
                seen.set()
        seen.set()  # the end of the output: the run is over, whatever it printed

    def read_stderr():  # the progress bar; read so that the pipe never fills
        for line in proc.stderr:
            errors.append(line)

    readers = [threading.Thread(target=read_stdout, daemon=True), threading.Thread(target=read_stderr, daemon=True)]
    for t in readers:
        t.start()
    output = lambda: "".join(lines) + "---- stderr (last lines) ----\n" + "".join(errors[-20:])
    if not seen.wait(timeout=120) or proc.poll() is not None:
        proc.kill()
        proc.wait()
        fail("the run did not show /%s/ within 120 s while running (exit %s)" % (ready, proc.returncode), output())
    if cut:
        time.sleep(1.0)
    proc.send_signal(sig)
    try:
        rc = proc.wait(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        fail("the run did not end within 120 s of %s" % sig_name, output())
    for t in readers:
        t.join(timeout=10)

    if mode == "hardware_dds":  # the robot gone, the server ends by itself; bounded all the same
        try:
            server.wait(timeout=30)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait()
    expected_rc = 128 + int(sig) if cut else 0
    if rc != expected_rc:
        fail("exit code %d after %s, expected %d" % (rc, sig_name, expected_rc), output())
    report_file = os.path.join(out, "report.json")
    if not os.path.exists(report_file):
        fail("no report.json", output())
    with open(report_file) as f:
        try:
            report = json.load(f)
        except ValueError as e:
            fail("report.json is not JSON: %s" % e, output())
    if report.get("stopped_by") != "interrupted by " + sig_name:
        fail("report.json stopped_by is %r, expected 'interrupted by %s'" % (report.get("stopped_by"), sig_name), output())
    command = report.get("base_command_at_end_rad_s")
    if report.get("base_at_rest") is not True or not command or any(v != 0 for v in command):
        fail("the base was not left at rest: base_at_rest %r, last command %r" % (report.get("base_at_rest"), command), output())
    moved = report.get("distance_m") if mode == "visit" else report.get("path", {}).get("length_m")
    if cut and not moved > 0.1:
        fail("the robot was not moving when the signal came (path %r m): the test would prove nothing" % moved, output())
    if mode == "visit":
        if report.get("completed") is not False:
            fail("the visit was cut short, yet completed is %r" % report.get("completed"), output())
    else:
        state = report.get("state")
        if state != ("interrupted" if cut else "idle"):
            fail("report.json state %r" % state, output())
        with open(os.path.join(out, "map.png"), "rb") as f:
            if f.read(8) != b"\x89PNG\r\n\x1a\n":
                fail("map.png is not a PNG", output())
        if mode == "board_pty" and not report.get("disinfection", {}).get("line", "").startswith("pty "):
            fail("the board's line is not a pty: %r" % report.get("disinfection"), output())
    if mode == "realtime_task":
        realtime = report.get("realtime") or {}
        loops = {l.get("name"): l for l in realtime.get("loops", [])}
        if realtime.get("speed") != 4 or set(loops) != {"motion", "sequencing"}:
            fail("report.json realtime: %r, expected speed 4 and the loops motion and sequencing" % realtime, output())
        for name, l in loops.items():
            error = l.get("period_error_us", {})
            if not l.get("cycles", 0) > 0 or not (0 <= error.get("p50", -1) <= error.get("p99", -1) <= error.get("max", -1)):
                fail("report.json realtime loop %s: %r" % (name, l), output())
            if not isinstance(l.get("overruns"), int) or not isinstance(l.get("deadline_faults"), int):
                fail("report.json realtime loop %s has no overrun counts: %r" % (name, l), output())
    print("%s: %s -> exit %d, %s, path %s m, base at rest %s" % (mode, sig_name, rc, report.get("stopped_by"), moved, command))
    print("".join(lines[-5:]))


if __name__ == "__main__":
    main()
