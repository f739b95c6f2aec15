"""Starts `tripodal run --monitor` for the monitor's Python tests and reads the address and token it
prints; stops it with SIGTERM (the run writes its report and exits)."""
import os
import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request


class MonitoredRun:
    def __init__(self, exe, robot, world, *extra):
        self._start([exe, "run", "--robot", robot, "--world", world, "--monitor", "0", *extra])

    def _start(self, cmd):
        self.cmd = cmd
        self.proc = subprocess.Popen(self.cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        self.lines = []
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            line = self.proc.stdout.readline()
            if not line:
                break
            self.lines.append(line)
            m = re.search(r"monitor: (http://[0-9.]+:(\d+))/\?token=([0-9a-zA-Z_-]+)", line)
            if m:
                self.base, self.port, self.token = m.group(1), int(m.group(2)), m.group(3)
                return
        self.stop()
        raise RuntimeError(" ".join(self.cmd[:2]) + " did not print the monitor's address: " + "".join(self.lines))

    def post(self, body, token=None, raw=None):
        """POST /api/command; returns (status, parsed JSON)."""
        import json
        data = raw if raw is not None else json.dumps(body).encode()
        req = urllib.request.Request(self.base + "/api/command", data=data, method="POST",
                                     headers={"Content-Type": "application/json"})
        if token is not None:
            req.add_header("Authorization", "Bearer " + token)
        try:
            with urllib.request.urlopen(req, timeout=10) as r:
                return r.status, json.loads(r.read())
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read())

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        rest = self.proc.stdout.read() if self.proc.stdout else ""
        self.lines.append(rest)
        return "".join(self.lines)


class HriMonitorServer(MonitoredRun):
    """tripodal_hri_monitor_server: the PSR-2 with an HRI module on a copy of `knowledge` in a
    fresh folder (self.knowledge), served by the monitor, paused."""

    def __init__(self, exe, source_dir, knowledge):
        import shutil
        import tempfile
        self.dir = tempfile.mkdtemp(prefix="tripodal_rkms_")
        self.knowledge = os.path.join(self.dir, os.path.basename(knowledge))
        shutil.copyfile(knowledge, self.knowledge)
        self._start([exe, source_dir, self.knowledge])

    def op(self, op, **fields):
        return self.post(dict(op=op, **fields), token=self.token)

    def stop(self):
        import shutil
        out = super().stop()
        shutil.rmtree(self.dir, ignore_errors=True)
        return out


def check(cond, what):
    if not cond:
        print("FAILED: " + what, file=sys.stderr)
        raise SystemExit(1)
    print("ok: " + what)
