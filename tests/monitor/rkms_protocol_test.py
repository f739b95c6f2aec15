"""The RKMS administration and touch ops seen by an HTTP client (Python's urllib) against the
monitor of a robot with an HRI module (tripodal_hri_monitor_server): every op needs the token
(401 without, nothing changes); list and search; add, edit, delete, each saved to the knowledge
file as its next version (read back with the file's own text); a stale edit and a stale delete
refused (409) with the entry as it is now; invalid entries refused naming the field; oversize,
binary and malformed bodies refused politely; the history; the touch screen's questions.

usage: rkms_protocol_test.py SERVER SOURCE_DIR"""
import json
import os
import re
import shutil
import subprocess
import sys
import urllib.request

from monitor_support import HriMonitorServer, check


def read(path):
    with open(path, "rb") as f:
        return f.read()


def main():
    exe, source = sys.argv[1:3]
    srv = HriMonitorServer(exe, source, os.path.join(source, "configs/hri/jinny.xml"))
    try:
        status, j = srv.op("rkms.list")
        check(status == 200 and j["version"] == 1 and len(j["entries"]) == 25, "rkms.list: 25 entries at version 1")
        original = read(srv.knowledge)

        entry = {"id": "parking", "topic": "the parking", "keywords": ["parking", "car"],
                 "questions": ["Where can I park my car?"], "answer": "Behind the hall, entrance B."}
        for token in (None, "wrong-token-123"):
            status, j = srv.post({"op": "rkms.add", "entry": entry}, token=token)
            check(status == 401, "rkms.add without the right token: 401 (%s)" % token)
            status, j = srv.post({"op": "rkms.list"}, token=token)
            check(status == 401, "rkms.list without the right token: 401")
        check(read(srv.knowledge) == original, "the refused requests changed nothing")

        status, j = srv.op("rkms.add", entry=entry, author="alice")
        check(status == 200 and j["version"] == 2 and j["entry_version"] == 2, "rkms.add: saved as version 2: %s" % j)
        text = read(srv.knowledge).decode()
        check('<knowledge version="2" robot="jinny">' in text and '<entry id="parking" topic="the parking">' in text,
              "the file on disk is at version 2 with the entry")
        status, j = srv.op("ask", text="where do I park my car?")
        check(j["kind"] == "answered" and j["entry"] == "parking", "the HRI answers from the new entry at once")

        status, j = srv.op("rkms.add", entry=entry)
        check(status == 409 and j["status"] == "exists", "adding a taken id: 409 exists")

        edit = dict(entry, answer="Behind the hall, entrance C.")
        status, j = srv.op("rkms.edit", id="parking", version=2, entry=edit, author="bob")
        check(status == 200 and j["version"] == 3, "rkms.edit: version 3")
        before = read(srv.knowledge)
        status, j = srv.op("rkms.edit", id="parking", version=2, entry=dict(entry, answer="Nowhere."), author="carol")
        check(status == 409 and j["status"] == "stale" and j["entry_version"] == 3
              and j["current"]["answer"] == "Behind the hall, entrance C.", "a stale edit is refused with the entry as it is now")
        status, j = srv.op("rkms.delete", id="parking", version=2)
        check(status == 409 and j["status"] == "stale", "a stale delete is refused")
        check(read(srv.knowledge) == before, "the stale requests changed nothing on disk")

        status, j = srv.op("rkms.add", entry=dict(entry, id="two words", topic=" "))
        fields = [e["field"] for e in j.get("errors", [])]
        check(status == 400 and fields[:2] == ["id", "topic"], "an invalid entry: 400 naming id and topic: %s" % fields)
        status, j = srv.op("rkms.add", entry=dict(entry, id="big", answer="x" * 5000))
        check(status == 400 and j["errors"][0]["message"] == "answer is 5000 bytes long; expected at most 4000", "an oversize answer is refused")
        status, j = srv.op("rkms.add", entry=dict(entry, id="bin", topic="a\u0000b"))
        check(status == 400 and j["errors"][0]["field"] == "topic" and "not text" in j["errors"][0]["message"], "a binary topic is refused")
        status, j = srv.post(None, token=srv.token, raw=b"\xff\xfe{not json")
        check(status == 400 and "expected a JSON object" in j["error"], "a body that is not JSON: 400")
        status, j = srv.post(None, token=srv.token, raw=json.dumps({"op": "rkms.add", "entry": dict(entry, id="huge", answer="x" * 70000)}).encode())
        check(status == 413, "a body over 64 KiB: 413")
        status, j = srv.op("rkms.edit", id="parking", entry=edit)
        check(status == 400 and "expected \"version\"" in j["error"], "an edit without a version: 400")
        check(read(srv.knowledge) == before, "the refused entries changed nothing on disk")

        odd = {"id": "odd.entry-1", "topic": "<R&D> \"quotes\"", "keywords": ["a<b", "R&D"],
               "questions": ["Is 1 < 2 & \"so\"?\r\nReally?"], "answer": "Line one,\nline two & {{braces}} at {time}.",
               "action": "guide me to node 1"}
        status, j = srv.op("rkms.add", entry=odd)
        check(status == 200, "an entry with markup characters, quotes and line breaks is added")
        xmllint = shutil.which("xmllint")
        if xmllint:
            r = subprocess.run([xmllint, "--noout", "--schema", os.path.join(source, "configs/hri/rkms.xsd"), srv.knowledge],
                               capture_output=True, text=True)
            check(r.returncode == 0, "the saved file validates against configs/hri/rkms.xsd: " + r.stderr.strip())
        status, j = srv.op("rkms.get", id="odd.entry-1")
        check(j["entry"]["questions"] == ["Is 1 < 2 & \"so\"?\nReally?"] and j["entry"]["topic"] == "<R&D> \"quotes\"",
              "it reads back as saved (line breaks as \\n)")
        status, j = srv.op("rkms.delete", id="odd.entry-1", version=j["entry"]["version"])
        check(status == 200, "and is deleted")

        status, j = srv.op("rkms.list", query="PARKING entrance")
        check([e["id"] for e in j["entries"]] == ["parking"] and j["entries"][0]["version"] == 3, "search finds the edited entry")
        status, j = srv.op("rkms.delete", id="parking", version=3, author="dave")
        check(status == 200 and j["version"] == 6, "rkms.delete: version 6")
        status, j = srv.op("rkms.history")
        ops = [(c["op"], c["id"], c["author"], c["version"]) for c in j["changes"]]
        check(ops == [("add", "parking", "alice", 2), ("edit", "parking", "bob", 3), ("add", "odd.entry-1", "operator", 4),
                      ("delete", "odd.entry-1", "operator", 5), ("delete", "parking", "dave", 6)],
              "the history: %s" % ops)
        check(re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", j["changes"][0]["time"]) is not None, "changes carry their UTC time")
        with open(srv.knowledge + ".history") as f:
            check(len(f.read().splitlines()) == 5, "the history file beside the knowledge has a line per change")

        status, j = srv.op("touch")
        check(status == 200 and len(j["questions"]) == 8 and isinstance(j["voice"], bool), "touch: 8 questions, voice %s" % j["voice"])
        status, j = srv.op("ask", text="", speak=False)
        check(j["kind"] == "refused_input", "an empty question is refused politely: " + j["text"])
        with urllib.request.urlopen(srv.base + "/rkms", timeout=10) as r:
            check(r.status == 200 and b"RKMS" in r.read(), "GET /rkms serves the page")
    finally:
        srv.stop()


if __name__ == "__main__":
    main()
