"""Another site's page cannot command the robot nor read its state, even knowing the token, while the
monitor's own page still works: headless Chromium (chromium-driver, python3-selenium) against
`tripodal run --monitor 0 --start-paused --monitor-read-open`. The other site is a second loopback
HTTP server on another port (another origin) whose page, given the token, tries everything a page
can: fetch() with the token header (a CORS preflight), a no-cors fetch with the token in the address,
a form posted as text/plain into a hidden frame, and WebSockets with and without the token. A page
reached through a DNS name that resolves to the robot (Chromium's --host-resolver-rules maps
rebound.test to 127.0.0.1: DNS rebinding) is refused with 421. The run stays paused throughout;
then the monitor's own page resumes it and has a task answered. A run started with
--monitor-allow-host rebound.test serves its page under that name (docs/monitor.md, "Host and Origin").

usage: cross_origin_browser_test.py TRIPODAL ROBOT.yaml WORLD.yaml"""
import http.server
import json
import sys
import threading
import time

try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait
except ImportError:
    print("skipped: Debian's python3-selenium is not installed (scripts/install-deps.sh browser)")
    raise SystemExit(77)

from monitor_support import MonitoredRun, check

ATTACK = """<!doctype html><html><head><meta charset="utf-8"><title>another site</title></head><body>
<div id="out"></div>
<iframe name="sink" style="display:none"></iframe>
<form id="form" method="POST" enctype="text/plain" target="sink" action="%(base)s/api/command?token=%(token)s">
  <input name='{"op":"resume","x":"' value='"}'>
</form>
<script>
const base = "%(base)s", token = "%(token)s", ws_base = base.replace("http://", "ws://");
const out = {fetch_header: "", fetch_no_cors: "", ws_open: "", ws_token: "", messages: 0};
function stream(path, key) {
  return new Promise((done) => {
    const ws = new WebSocket(ws_base + path);
    ws.onmessage = () => { out.messages++; };
    ws.onopen = () => { out[key] = "open"; };
    ws.onerror = () => { if (!out[key]) out[key] = "error"; };
    ws.onclose = () => { if (!out[key]) out[key] = "closed"; done(); };
    setTimeout(() => { try { ws.close(); } catch (e) {} done(); }, 3000);
  });
}
(async () => {
  try {
    const r = await fetch(base + "/api/command", {method: "POST", body: '{"op":"resume"}',
      headers: {"Content-Type": "application/json", "Authorization": "Bearer " + token}});
    out.fetch_header = "status " + r.status + ": " + await r.text();
  } catch (e) { out.fetch_header = "blocked: " + e; }
  try {
    const r = await fetch(base + "/api/command?token=" + token, {method: "POST", mode: "no-cors", body: '{"op":"resume"}',
      headers: {"Content-Type": "text/plain"}});
    out.fetch_no_cors = "opaque " + r.type;
  } catch (e) { out.fetch_no_cors = "blocked: " + e; }
  document.getElementById("form").submit();
  await stream("/ws", "ws_open");
  await stream("/ws?token=" + token, "ws_token");
  await new Promise((r) => setTimeout(r, 500));
  document.getElementById("out").textContent = JSON.stringify(out);
})();
</script></body></html>"""


class AttackSite(http.server.ThreadingHTTPServer):
    """The other origin: serves one page (given the monitor's address and token) on 127.0.0.1."""

    def __init__(self, page):
        page_bytes = page.encode()

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):
                self.send_response(200)
                self.send_header("Content-Type", "text/html; charset=utf-8")
                self.send_header("Content-Length", str(len(page_bytes)))
                self.end_headers()
                self.wfile.write(page_bytes)

            def log_message(self, *args):
                pass

        super().__init__(("127.0.0.1", 0), Handler)


def main():
    exe, robot, world = sys.argv[1:4]
    run = MonitoredRun(exe, robot, world, "--start-paused", "--monitor-read-open", "--realtime", "10")
    site = AttackSite(ATTACK % {"base": run.base, "token": run.token})
    threading.Thread(target=site.serve_forever, daemon=True).start()
    site_url = "http://127.0.0.1:%d/" % site.server_address[1]
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1200,900",
                "--host-resolver-rules=MAP rebound.test 127.0.0.1"]:
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        wait = WebDriverWait(driver, 60, poll_frequency=0.1)
        text = lambda id: driver.find_element(By.ID, id).text

        # The monitor's own page first: connected, paused, no task.
        driver.get(run.base + "/?token=" + run.token)
        wait.until(lambda d: text("conn") == "connected")
        wait.until(lambda d: text("paused").startswith("paused"))
        check(True, "the monitor's own page connects; the run is paused")

        # Another site's page, with the token, tries everything.
        driver.get(site_url)
        wait.until(lambda d: text("out") != "")
        out = json.loads(text("out"))
        print("another site's page saw: " + json.dumps(out))
        check(out["fetch_header"].startswith("blocked"), "fetch() with the token header is blocked (no CORS): " + out["fetch_header"])
        check(out["ws_open"] != "open", "a WebSocket without the token (read-open) is refused to another site: " + out["ws_open"])
        check(out["ws_token"] != "open", "a WebSocket with the token is refused to another site: " + out["ws_token"])
        check(out["messages"] == 0, "another site's page read nothing of the robot's state")

        # DNS rebinding: the monitor reached under a name that resolves to it.
        driver.get("http://rebound.test:%d/?token=%s" % (run.port, run.token))
        body = driver.find_element(By.TAG_NAME, "body").text
        check("Host is not this server's name" in body, "a page reached through a rebound DNS name is refused (421): " + body[:80])

        # Nothing of it ran: the own page shows the run still paused.
        driver.get(run.base + "/?token=" + run.token)
        wait.until(lambda d: text("conn") == "connected")
        wait.until(lambda d: text("paused") != "running")
        time.sleep(1.0)  # a few status updates: a resume would show by now
        check(text("paused").startswith("paused"), "the run is still paused: no command of the other site ran (" + text("paused") + ")")
        status, answer = run.post({"op": "net", "run": "X99"}, token=run.token)
        check(status == 404, "a client that is not a browser (no Origin), with the token, is still served: %d %s" % (status, answer))

        # The own page still commands the robot.
        driver.find_element(By.ID, "resume").click()
        wait.until(lambda d: text("paused") == "running")
        check(True, "the monitor's own page resumes the run")
        wait.until(lambda d: text("answer") != "")  # the resume's answer, then the task's
        driver.execute_script("document.getElementById('answer').textContent = ''")
        box = driver.find_element(By.ID, "task-input")
        box.send_keys("fly to the moon")
        driver.find_element(By.ID, "task-submit").click()
        wait.until(lambda d: text("answer").startswith("refused") or text("answer").startswith("accepted"))
        check(text("answer").startswith("refused: "), "the own page's task is answered by the planner: " + text("answer"))
        run.stop()

        # The operator names the robot's host: then the page is served under that name too.
        named = MonitoredRun(exe, robot, world, "--start-paused", "--monitor-allow-host", "rebound.test")
        try:
            driver.get("http://rebound.test:%d/?token=%s" % (named.port, named.token))
            wait.until(lambda d: text("conn") == "connected")
            check(True, "with --monitor-allow-host rebound.test the page is served under that name and connects")
        finally:
            named.stop()
    finally:
        driver.quit()
        site.shutdown()
        run.stop()


if __name__ == "__main__":
    main()
