"""The RKMS administration page and the touch page in a real browser: Debian's chromium, headless,
driven by chromium-driver through python3-selenium, against tripodal_hri_monitor_server (the
PSR-2 with an HRI module on a copy of Jinny's knowledge). On /rkms: a wrong token is refused; an
entry is added (an invalid one first, refused with the field's message beside it), edited,
refused as stale when it was changed through the API between the page's load and its save (the
file keeps the API's text), reloaded, and deleted; the history lists the changes. On /touch: the
big buttons ask the robot, the answer is shown, and spoken when the build has a voice (else the
page says the voice is off). On /: the HRI panel shows the HRI's display and the last exchange. Screenshots: <build>/artifacts/rkms.png and touch.png.

usage: rkms_browser_test.py SERVER SOURCE_DIR ARTIFACT_DIR"""
import os
import sys

try:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait
except ImportError:
    print("skipped: Debian's python3-selenium is not installed (scripts/install-deps.sh browser)")
    raise SystemExit(77)

from monitor_support import HriMonitorServer, check


def main():
    exe, source, artifacts = sys.argv[1:4]
    srv = HriMonitorServer(exe, source, os.path.join(source, "configs/hri/jinny.xml"))
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1300,1100",
                "--autoplay-policy=no-user-gesture-required"]:
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    disk = lambda: open(srv.knowledge, encoding="utf-8").read()
    try:
        wait = WebDriverWait(driver, 30, poll_frequency=0.1)
        el = lambda id: driver.find_element(By.ID, id)
        text = lambda id: el(id).text
        msg = lambda: text("msg")

        def typed(id, value):
            el(id).clear()
            if value:
                el(id).send_keys(value)

        def row(entry_id):
            rows = driver.find_elements(By.CSS_SELECTOR, 'tr[data-id="%s"]' % entry_id)
            return rows[0] if rows else None

        def save_and_wait():
            driver.execute_script("document.getElementById('msg').textContent = ''")
            el("save-btn").click()
            wait.until(lambda d: msg() != "")
            return msg()

        driver.get(srv.base + "/rkms?token=" + srv.token)
        wait.until(lambda d: text("list-state") == "25 entries")
        check(text("base-version") == "1" and text("file") == "jinny.xml", "the RKMS page lists Jinny's 25 entries at version 1")

        typed("token", "wrong-token-123")
        el("search-btn").click()
        wait.until(lambda d: text("list-state").startswith("refused (401)"))
        check(True, "a wrong token is refused: " + text("list-state"))
        typed("token", srv.token)
        typed("search-input", "umbrella")
        el("search-btn").click()
        wait.until(lambda d: text("list-state") == "1 entries match")
        check(row("weather") is not None, "search 'umbrella' finds the weather entry")
        typed("search-input", "")
        el("search-btn").click()
        wait.until(lambda d: text("list-state") == "25 entries")

        # Add: an invalid entry first (the error beside its field), then a valid one.
        el("new-btn").click()
        typed("author", "alice")
        typed("f-id", "car park")
        typed("f-topic", "the parking")
        typed("f-keywords", "parking, car")
        typed("f-questions", "Where can I park my car?")
        typed("f-answer", "The car park is behind the hall, entrance B.")
        m = save_and_wait()
        check(m.startswith("refused (400)") and "expected letters, digits" in text("err-id"),
              "an invalid id is refused, the message beside the field: " + text("err-id"))
        check("car park" not in disk(), "nothing was saved")
        typed("f-id", "parking")
        m = save_and_wait()
        check(m == "entry 'parking' added as version 2", "added: " + m)
        wait.until(lambda d: row("parking") is not None)
        check('<entry id="parking" topic="the parking">' in disk() and 'version="2"' in disk(), "the file holds the entry at version 2")

        # Edit it.
        row("parking").find_element(By.CSS_SELECTOR, "button.edit").click()
        wait.until(lambda d: el("f-version").get_attribute("value") == "2")
        typed("f-answer", "The car park is behind the hall, entrance C.")
        m = save_and_wait()
        check(m == "entry 'parking' saved as version 3", "edited: " + m)
        wait.until(lambda d: row("parking").find_elements(By.TAG_NAME, "td")[2].text == "3")
        check("entrance C." in disk(), "the file holds the edit")

        # A stale edit: the page read version 3; someone saves through the API; the page's save is refused.
        wait.until(lambda d: el("f-version").get_attribute("value") == "3")
        status, j = srv.op("rkms.edit", id="parking", version=3, author="api",
                           entry={"id": "parking", "topic": "the parking", "keywords": ["parking", "car"],
                                  "questions": ["Where can I park my car?"], "answer": "Park at entrance D."})
        check(status == 200 and j["version"] == 4, "meanwhile the entry is changed through the API (version 4)")
        typed("f-answer", "The car park is at entrance E.")
        m = save_and_wait()
        check(m.startswith("refused (409, stale version)") and "was changed since you read it" in m,
              "the page's stale edit is refused: " + m.replace("\n", " | "))
        check("entrance D." in disk() and "entrance E." not in disk(), "the file keeps the API's change")
        check(el("f-answer").get_attribute("value") == "The car park is at entrance E.", "the editor's text stays in the form")
        driver.save_screenshot(os.path.join(artifacts, "rkms.png"))
        el("reload-entry-btn").click()
        wait.until(lambda d: el("f-version").get_attribute("value") == "4")
        check(el("f-answer").get_attribute("value") == "Park at entrance D.", "'reload this entry' shows the saved version 4")

        # Delete it (the page asks first).
        driver.execute_script("document.getElementById('msg').textContent = ''")
        row("parking").find_element(By.CSS_SELECTOR, "button.delete").click()
        wait.until(lambda d: d.switch_to.alert)
        driver.switch_to.alert.accept()
        wait.until(lambda d: msg() != "")
        check(msg() == "entry 'parking' deleted as version 5", "deleted: " + msg())
        wait.until(lambda d: row("parking") is None)
        check("parking" not in disk() and 'version="5"' in disk(), "the file no longer holds the entry")

        el("history-btn").click()
        wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#history li")) == 4)
        items = [li.text for li in driver.find_elements(By.CSS_SELECTOR, "#history li")]
        check(items[0].startswith("version 5, ") and "delete parking" in items[0] and "alice" in items[0]
              and "api: edit parking" in items[1] and "answer:" in items[1], "the history, newest first: " + " | ".join(items))

        # The touch page.
        driver.get(srv.base + "/touch?token=" + srv.token)
        wait.until(lambda d: len(d.find_elements(By.CSS_SELECTOR, "#buttons button.question")) == 8)
        check(text("title").startswith("Hello, I am Jinny!"), "the touch page shows 8 big buttons")
        wait.until(lambda d: el("state").get_attribute("data-task-state") == "idle")
        check(text("state") == "the robot's state: idle | no process | no fault, paused",
              "the robot's state as the HRI displays it: " + text("state"))
        voice = text("voice").startswith("voice is on")
        driver.find_element(By.XPATH, '//button[text()="Introduce yourself."]').click()
        wait.until(lambda d: el("answer").get_attribute("data-kind") == "answered")
        check(text("answer").startswith("Hello, I am Jinny, the guide robot"), "a button's question is answered: " + text("answer"))
        if voice:
            wait.until(lambda d: el("voice").get_attribute("data-audio-bytes"))
            check(int(el("voice").get_attribute("data-audio-bytes")) > 44 + 22050 * 2, "the answer is spoken: " + text("voice"))
        else:
            check(text("voice").startswith("voice is off"), "the page says the voice is off: " + text("voice"))
        typed("ask-input", "hows the wether today")
        el("ask-btn").click()
        wait.until(lambda d: "sunny" in text("answer"))
        check(el("answer").get_attribute("data-entry") == "weather", "a typed question with a typo is answered: " + text("answer"))
        driver.save_screenshot(os.path.join(artifacts, "touch.png"))

        # The monitor's page shows what the HRI displays: its state and the last exchange.
        driver.get(srv.base + "/?token=" + srv.token)
        wait.until(lambda d: el("hri-panel").is_displayed() and "wether" in text("hri"))
        check(text("hri-status") == "idle | no process | no fault", "the HRI panel shows the display line: " + text("hri-status"))
        check("typed: \u201chows the wether today\u201d" in text("hri") and "answered (weather)" in text("hri"),
              "the HRI panel shows the last input and its answer: " + text("hri").replace("\n", " | "))
    finally:
        driver.quit()
        out = srv.stop()
    del out


if __name__ == "__main__":
    main()
