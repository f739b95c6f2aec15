"""The monitor page in a real browser: Debian's chromium, driven headless by chromium-driver through
python3-selenium, against a running `tripodal run --monitor --start-paused`. A wrong token is
refused (401) and nothing runs; an unknown task shows the planner's answer; "clean the room 3211"
starts the task; the pose changes on the map; a place of PrCleaning becomes marked; a breakpoint
on it pauses the run; live mapping begins from the console and saves a map beside the run's
outputs (a name with a folder in it refused); an edited PrCleaning net that does not load is refused with the loader's
located diagnostics on the page, one that loads is reloaded at the quiet marking and drawn; the
board link panel stays hidden (the PSR-2 has no control board). The page's screenshot is kept as
the test's artifact.

usage: browser_test.py TRIPODAL ROBOT.yaml WORLD.yaml SCREENSHOT.png"""
import os
import re
import shutil
import sys
import tempfile
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


def main():
    exe, robot, world, screenshot = sys.argv[1:5]
    out_dir = tempfile.mkdtemp(prefix="tripodal_browser_")
    run = MonitoredRun(exe, robot, world, "--start-paused", "--realtime", "10", "--out", out_dir)
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1400,1500"]:
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        wait = WebDriverWait(driver, 60, poll_frequency=0.1)
        text = lambda id: driver.find_element(By.ID, id).text

        driver.get(run.base + "/?token=" + run.token)
        wait.until(lambda d: text("conn") == "connected")
        check(True, "the page loads and connects")
        wait.until(lambda d: text("paused").startswith("paused"))
        check(text("task-state") == "idle", "started paused, no task")

        def submit(task, token):
            field = driver.find_element(By.ID, "token")
            field.clear()
            field.send_keys(token)
            box = driver.find_element(By.ID, "task-input")
            box.clear()
            box.send_keys(task)
            driver.execute_script("document.getElementById('answer').textContent = ''")
            driver.find_element(By.ID, "task-submit").click()
            wait.until(lambda d: text("answer") != "")
            return text("answer")

        answer = submit("clean the room 3211", "wrong-token")
        check(answer.startswith("refused (401)"), "a wrong token is refused: " + answer)
        answer = submit("clean the room 3211", "")
        check(answer.startswith("refused (401)"), "a missing token is refused: " + answer)
        time.sleep(0.5)  # a few status updates: still nothing runs
        check(text("task-state") == "idle", "nothing runs after the refusals")

        answer = submit("fly to the moon", run.token)
        check(answer.startswith("refused: ") and len(answer) > len("refused: "), "an unknown task shows the planner's message: " + answer)

        bp = driver.find_element(By.ID, "bp-input")
        bp.clear()
        bp.send_keys("PrCleaning.P1")
        driver.find_element(By.ID, "bp-set").click()
        wait.until(lambda d: "PrCleaning.P1" in text("bps"))
        check(True, "a breakpoint on PrCleaning.P1")

        answer = submit("clean the room 3211", run.token)
        check(answer.startswith("accepted: "), "clean the room 3211 is accepted: " + answer)
        pose_before = text("pose")
        driver.find_element(By.ID, "resume").click()
        wait.until(lambda d: text("task-state") == "running")
        check(True, "the task runs")

        # The robot starts at section A's entry: PrCleaning's P1 (BhCleaning) is marked at once.
        wait.until(lambda d: "breakpoint" in text("paused"))
        check(True, "the breakpoint paused the run: " + text("paused"))
        marked = driver.find_elements(By.CSS_SELECTOR, 'div.net[data-net="PrCleaning"] g.place.marked[data-place="P1"]')
        check(len(marked) == 1, "a place of PrCleaning (P1) is marked")
        t1 = text("time")
        time.sleep(1.0)
        check(text("time") == t1, "paused: the robot's time stands still (%s s)" % t1)
        check(not driver.find_element(By.ID, "board-panel").is_displayed(), "no board link panel for the PSR-2")

        # Edit the running PrCleaning net: its text from the robot, a broken edit refused with the
        # diagnostics, a good one reloaded at the quiet marking (paused at the breakpoint).
        wait.until(lambda d: any("PrCleaning" in o.text for o in d.find_elements(By.CSS_SELECTOR, "#edit-run option")))
        for o in driver.find_elements(By.CSS_SELECTOR, "#edit-run option"):
            if "PrCleaning" in o.text:
                o.click()
                run_id = o.get_attribute("value")
        driver.find_element(By.ID, "edit-load").click()
        wait.until(lambda d: "<net" in d.find_element(By.ID, "edit-xml").get_attribute("value"))
        check(True, "the text of PrCleaning's net (run %s) is in the editor" % run_id)
        edit = lambda js: driver.execute_script("const e = document.getElementById('edit-xml'); e.value = " + js + ";")
        original = driver.find_element(By.ID, "edit-xml").get_attribute("value")
        edit("e.value.replace('</place>', '')")
        driver.find_element(By.ID, "edit-reload").click()
        wait.until(lambda d: text("edit-result").startswith("refused"))
        result = text("edit-result")
        check(re.search(r"PrCleaning\.edited\.xml:\d+:\d+: error: ", result) is not None,
              "a net that does not load is refused with located diagnostics: " + result.replace("\n", " | "))
        check(driver.find_element(By.ID, "edit-result").get_attribute("class") == "refused", "shown as refused")
        driver.execute_script("document.getElementById('edit-xml').value = arguments[0];",
                              original.replace("</net>", '  <place id="P99" description="operator note"/>\n</net>'))
        driver.find_element(By.ID, "edit-reload").click()
        wait.until(lambda d: text("edit-result").startswith("reloaded") or text("edit-result").startswith("refused:"))
        result = text("edit-result")
        check(result.startswith("reloaded " + run_id + " at a quiet marking (") and "P1=1" in result,
              "an edited net that loads is reloaded with the marking carried over: " + result.replace("\n", " | "))
        wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, 'div.net[data-net="PrCleaning"] g.place[data-place="P99"]'))
        check(driver.find_elements(By.CSS_SELECTOR, 'div.net[data-net="PrCleaning"] g.place.marked[data-place="P1"]'),
              "the edited net is drawn, P1 still marked")

        driver.find_element(By.ID, "bp-clear").click()
        wait.until(lambda d: "PrCleaning.P1" not in text("bps"))
        driver.find_element(By.ID, "resume").click()
        xy = lambda pose: [round(float(v), 1) for v in pose.split()[:2]]
        wait.until(lambda d: xy(text("pose")) != xy(pose_before))
        check(True, "the pose changes on the map: %s -> %s" % (pose_before, text("pose")))
        driver.find_element(By.ID, "map-begin").click()
        wait.until(lambda d: text("map-state").startswith("mapping"))
        check(True, "live mapping begun from the console: " + text("map-state"))
        wait.until(lambda d: float(text("time")) > float(t1) + 20)  # some cleaned cells for the picture
        driver.find_element(By.ID, "map-name").send_keys("../elsewhere")
        driver.find_element(By.ID, "map-save").click()
        wait.until(lambda d: "expected" in text("map-state"))
        check(True, "a map name with a folder in it is refused: " + text("map-state"))
        driver.find_element(By.ID, "map-name").clear()
        driver.find_element(By.ID, "map-name").send_keys("hall")
        driver.find_element(By.ID, "map-save").click()
        wait.until(lambda d: text("map-state").startswith("saved"))
        check(os.path.isfile(os.path.join(out_dir, "hall.yaml")) and os.path.isfile(os.path.join(out_dir, "hall.pgm")),
              "the map is saved beside the run's outputs: " + text("map-state"))
        check(driver.find_elements(By.CSS_SELECTOR, 'div.net[data-net="PrCleaning"] g.place.marked[data-place="P1"]'),
              "PrCleaning's P1 stays marked while the section is cleaned")
        driver.save_screenshot(screenshot)
        check(True, "screenshot kept: " + screenshot)
    finally:
        driver.quit()
        out = run.stop()
        shutil.rmtree(out_dir, ignore_errors=True)
    check("activate BhCleaning(section=A)" in out or "PrCleaning(section=A)" in out, "the run's log shows the cleaning")
    check("net reloaded from PrCleaning.edited.xml at a quiet marking" in out, "the life cycle records the reload")


if __name__ == "__main__":
    main()
