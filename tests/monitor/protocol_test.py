"""The monitor's protocol against a running `tripodal run --monitor`, with Debian's python3-websockets:
the page and its limits over HTTP, the token, a page client's topics and a Foxglove client
(foxglove.websocket.v1: serverInfo, advertise, subscribe, binary messageData).

usage: protocol_test.py TRIPODAL ROBOT.yaml WORLD.yaml"""
import asyncio
import json
import struct
import sys
import urllib.request

try:
    import websockets
except ImportError:
    print("skipped: Debian's python3-websockets is not installed (scripts/install-deps.sh installs it)")
    raise SystemExit(77)

from monitor_support import MonitoredRun, check


async def page_client(run):
    uri = "ws://127.0.0.1:%d/ws?token=%s" % (run.port, run.token)
    async with websockets.connect(uri, max_size=None) as ws:
        topics = {}
        while not {"hello", "/map", "/pose", "/status"} <= topics.keys():
            m = json.loads(await asyncio.wait_for(ws.recv(), 20))
            topics[m["topic"]] = m["data"]
        check("/lifecycle" in topics["hello"]["topics"], "a page client is told the topics")
        check(topics["/map"]["width"] > 0 and topics["/map"]["sections"], "the map comes with its sections")
        check(topics["/status"]["task_state"] == "idle", "no task runs before the operator gives one")
    try:
        async with websockets.connect("ws://127.0.0.1:%d/ws?token=wrong" % run.port):
            check(False, "a stream with a wrong token is refused")
    except websockets.exceptions.InvalidStatusCode as e:
        check(e.status_code == 401, "a stream with a wrong token is refused with 401")


async def foxglove_client(run):
    uri = "ws://127.0.0.1:%d/?token=%s" % (run.port, run.token)
    async with websockets.connect(uri, subprotocols=["foxglove.websocket.v1"], max_size=None) as ws:
        check(ws.subprotocol == "foxglove.websocket.v1", "the server speaks foxglove.websocket.v1")
        info = json.loads(await ws.recv())
        check(info["op"] == "serverInfo" and "json" in info["supportedEncodings"], "serverInfo first")
        adv = json.loads(await ws.recv())
        check(adv["op"] == "advertise", "then advertise")
        channels = {c["topic"]: c for c in adv["channels"]}
        for topic in ["/pose", "/path", "/markings", "/lifecycle", "/laser", "/nets"]:
            check(topic in channels, "channel " + topic + " advertised")
            json.loads(channels[topic]["schema"])
            check(channels[topic]["schemaEncoding"] == "jsonschema" and channels[topic]["encoding"] == "json",
                  topic + ": a JSON channel with a JSON schema")
        check(channels["/laser"]["schemaName"] == "foxglove.LaserScan", "the laser is a foxglove.LaserScan")
        check(channels["/pose"]["schemaName"] == "foxglove.PoseInFrame", "the pose is a foxglove.PoseInFrame")
        subs = {1: "/pose", 2: "/lifecycle", 3: "/laser", 4: "/markings"}
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": sid, "channelId": channels[t]["id"]} for sid, t in subs.items()]}))
        seen = {}
        accepted = None
        def done():
            return (len(seen) == 4 and any("task clean" in e.get("text", "") for e in seen["/lifecycle"])
                    and any(n["run"] == "task" for n in seen["/markings"][-1]["nets"]))
        while not done():
            frame = await asyncio.wait_for(ws.recv(), 30)
            check(isinstance(frame, bytes) and frame[0] == 1, "messageData arrives as binary frames (opcode 1)")
            sid, stamp_ns = struct.unpack_from("<IQ", frame, 1)
            payload = json.loads(frame[13:])
            seen.setdefault(subs[sid], []).append(payload)
            if accepted is None and "/pose" in seen:
                status, answer = run.post({"op": "task", "text": "clean the room 3211"}, token=run.token)
                check(status == 200 and answer["accepted"], "the task is accepted with the token: " + answer["text"])
                accepted = answer
        pose = seen["/pose"][-1]
        check(pose["frame_id"] == "map" and "orientation" in pose["pose"], "a pose in the map frame")
        scan = seen["/laser"][-1]
        check(len(scan["ranges"]) > 10 and scan["end_angle"] > scan["start_angle"], "a laser scan with ranges")
        check(True, "the task net's marking: " + json.dumps(seen["/markings"][-1]["nets"][0]["marked"]))


def main():
    exe, robot, world = sys.argv[1:4]
    run = MonitoredRun(exe, robot, world, "--realtime", "5")
    try:
        with urllib.request.urlopen(run.base + "/", timeout=10) as r:
            page = r.read().decode()
            check(r.status == 200 and "<title>tripodal monitor</title>" in page, "the page is served at /")
            check("http://" not in page.replace("http://www.w3.org/2000/svg", ""), "the page loads nothing from the network")
        for path in ["/etc/passwd", "/../CMakeLists.txt", "/index.js"]:
            try:
                urllib.request.urlopen(run.base + path, timeout=10)
                check(False, path + " is not served")
            except urllib.error.HTTPError as e:
                check(e.code == 404, path + " is not served (404)")
        status, body = run.post({"op": "task", "text": "clean the room 3211"})
        check(status == 401, "a command without the token is refused with 401")
        status, body = run.post({"op": "task", "text": "clean the room 3211"}, token="wrong")
        check(status == 401 and "token" in body["error"], "a command with a wrong token is refused with 401")
        status, body = run.post({"op": "drive", "vx": 0.3})
        check(status == 401, "driving by hand without the token is refused with 401")
        status, body = run.post(None, token=run.token, raw=b"x" * 100000)
        check(status == 413, "a body over the limit is refused with 413")
        status, body = run.post({"op": "warp"}, token=run.token)
        check(status == 400 and "unknown op 'warp'" in body["error"], "an unknown op is named")
        status, body = run.post({"op": "task", "text": "fly to the moon"}, token=run.token)
        check(status == 200 and not body["accepted"] and body["text"], "an unknown task: the planner's answer: " + body["text"])
        asyncio.run(page_client(run))
        asyncio.run(foxglove_client(run))
    finally:
        out = run.stop()
    check("operator: \"clean the room 3211\": accepted" in out or "task clean" in out, "the run's log shows the task")


if __name__ == "__main__":
    main()
