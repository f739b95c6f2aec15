"""The monitor page in a real browser: Debian's chromium, driven headless by chromium-driver through
python3-selenium, against a running `tripodal run --monitor --start-paused`. A wrong token is
refused (401) and nothing runs; an unknown task shows the planner's answer; "clean the room 3211"
starts the task; the pose changes on the map; a place of PrCleaning becomes marked; a breakpoint
on it pauses the run. The page's screenshot is kept as the test's artifact.

usage: browser_test.py TRIPODAL ROBOT.yaml WORLD.yaml SCREENSHOT.png"""
import sys
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
    run = MonitoredRun(exe, robot, world, "--start-paused", "--realtime", "10")
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

        driver.find_element(By.ID, "bp-clear").click()
        wait.until(lambda d: "PrCleaning.P1" not in text("bps"))
        driver.find_element(By.ID, "resume").click()
        xy = lambda pose: [round(float(v), 1) for v in pose.split()[:2]]
        wait.until(lambda d: xy(text("pose")) != xy(pose_before))
        check(True, "the pose changes on the map: %s -> %s" % (pose_before, text("pose")))
        wait.until(lambda d: float(text("time")) > float(t1) + 20)  # some cleaned cells for the picture
        check(driver.find_elements(By.CSS_SELECTOR, 'div.net[data-net="PrCleaning"] g.place.marked[data-place="P1"]'),
              "PrCleaning's P1 stays marked while the section is cleaned")
        driver.save_screenshot(screenshot)
        check(True, "screenshot kept: " + screenshot)
    finally:
        driver.quit()
        out = run.stop()
    check("activate BhCleaning(section=A)" in out or "PrCleaning(section=A)" in out, "the run's log shows the cleaning")


if __name__ == "__main__":
    main()
