"""The shipped guide robot serves its own RKMS and touch page: `tripodal run --robot jinny.yaml
--world exhibit_hall.yaml --monitor 0` (no visit file, no --task) on a copy of configs/ (edits go to
the copy's knowledge file, never the repository's). Over HTTP (urllib) and the page's stream
(python3-websockets): the touch op names Jinny; a reaction input typed on the touch screen is
answered from the RKMS; an entry added on /rkms is saved to the robot's knowledge file and answered
at once; a command the planner refuses comes back in plain words; a command it accepts starts the
guide task on the robot (PrAutoMove in the life cycle); /status carries what the HRI displays (task,
process, last input and answer); the run prints the touch screen's exchanges and ends with 0 when
stopped.

usage: guide_monitor_test.py TRIPODAL SOURCE_DIR"""
import asyncio
import json
import os
import shutil
import sys
import tempfile

try:
    import websockets
except ImportError:
    print("skipped: Debian's python3-websockets is not installed (scripts/install-deps.sh installs it)")
    raise SystemExit(77)

from monitor_support import MonitoredRun, check


async def hri_status(run, until, timeout_s=60):
    """The /status frames' hri field until `until(hri)` holds; returns it."""
    uri = "ws://127.0.0.1:%d/ws?token=%s" % (run.port, run.token)
    async with websockets.connect(uri, max_size=None) as ws:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout_s
        last = None
        while loop.time() < deadline:
            m = json.loads(await asyncio.wait_for(ws.recv(), 20))
            if m["topic"] != "/status":
                continue
            last = m["data"]["hri"]
            if last is not None and until(last):
                return last
        raise AssertionError("the HRI's display never came to the expected state; last: %s" % json.dumps(last))


def main():
    exe, source = sys.argv[1:3]
    work = tempfile.mkdtemp(prefix="tripodal_guide_monitor_")
    configs = os.path.join(work, "configs")
    shutil.copytree(os.path.join(source, "configs"), configs)
    knowledge = os.path.join(configs, "hri/jinny.xml")
    run = MonitoredRun(exe, os.path.join(configs, "robots/jinny.yaml"), os.path.join(configs, "worlds/exhibit_hall.yaml"),
                       "--no-voice", "--realtime", "4")
    out = ""
    try:
        status, j = run.post({"op": "touch"}, token=run.token)
        check(status == 200 and j["robot"] == "jinny" and len(j["questions"]) == 8, "the touch op names Jinny: %s" % j)
        status, j = run.post({"op": "rkms.list"}, token=None)
        check(status == 401, "the RKMS is not listed without the token")

        status, j = run.post({"op": "ask", "text": "Introduce yourself."}, token=run.token)
        check(status == 200 and j["kind"] == "answered" and j["entry"] == "introduce" and j["text"].startswith("Hello, I am Jinny"),
              "a reaction input is answered by the robot's RKMS: %s" % j.get("text"))

        status, j = run.post({"op": "ask", "text": "where can I buy a souvenir"}, token=run.token)
        check(j["kind"] == "not_understood", "the robot knows nothing of souvenirs at first: %s" % j["text"])
        entry = {"id": "souvenirs", "topic": "the souvenir shop", "keywords": ["souvenir", "souvenirs", "gift", "shop"],
                 "questions": ["Where can I buy a souvenir?"], "answer": "The souvenir shop is by the entrance, open until 17."}
        status, j = run.post({"op": "rkms.add", "entry": entry, "author": "test"}, token=run.token)
        check(status == 200 and j["version"] == 2, "an entry added on /rkms is saved as version 2: %s" % j)
        with open(knowledge, encoding="utf-8") as f:
            text = f.read()
        check('<knowledge version="2" robot="jinny">' in text and 'id="souvenirs"' in text,
              "the robot's own knowledge file (the profile's Hri module's) holds it")
        status, j = run.post({"op": "ask", "text": "where can I buy a souvenir"}, token=run.token)
        check(j["kind"] == "answered" and j["entry"] == "souvenirs", "the robot answers from the new entry at once: %s" % j)

        status, j = run.post({"op": "ask", "text": "guide me to node 7"}, token=run.token)
        check(j["kind"] == "task_refused" and "there is no node 7 here. I can guide you to node 0, 1 or 2" in j["text"] and "{" not in j["text"],
              "a command the planner refuses comes back in plain words: %s" % j["text"])

        status, j = run.post({"op": "ask", "text": "guide me to node 1"}, token=run.token)
        check(j["kind"] == "task_started" and j["task"] == "guide", "a command input starts the guide task: %s" % j)
        hri = asyncio.run(hri_status(run, lambda h: h["task"] == "guide" and h["process"].startswith("PrAutoMove")))
        check(hri["last"]["input"] == "guide me to node 1" and hri["last"]["kind"] == "task_started",
              "/status shows the HRI's display: %s" % hri["status"])
        check(hri["status"].startswith("task guide: running | process PrAutoMove(goal=node1)"), "the display line: " + hri["status"])
    finally:
        out = run.stop()
        shutil.rmtree(work, ignore_errors=True)
    check("no visit file: the monitor's visitors" in out, "the run says it has no visit file")
    check('touch screen: "Introduce yourself." -> Jinny [answered introduce]' in out, "the run prints the touch screen's exchanges")
    check('touch screen: "guide me to node 1" -> Jinny [task_started, task guide]' in out, "and the task it started")
    check("activate BhAutoMove" in out or "PrAutoMove" in out, "the guide task runs on the robot")
    check(run.proc.returncode == 0, "stopped by SIGTERM, the run ends with 0 (got %s)" % run.proc.returncode)


if __name__ == "__main__":
    main()
