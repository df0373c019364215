"""The dashboard at / in a real browser: headless Chromium driven by Selenium (Debian's chromium,
chromium-driver and python3-selenium, installed by tools/bootstrap) against an `ftctune serve` this
module starts on an ephemeral loopback port with a store in a temporary directory.

Run by ctest as Dashboard.Browser:
    /usr/bin/python3 -m pytest -q tests/web --ftctune build/tools/ftctune
With FTCTUNE_SCREENSHOTS=DIR it also saves the jobs list and a job page as PNG files there (the
figures of docs/service.md: FTCTUNE_SCREENSHOTS=docs/figures).
"""
import copy
import json
import os
import re
import shutil
import subprocess
import tempfile
import time
import urllib.request

import pytest
from selenium import webdriver
from selenium.common.exceptions import (NoAlertPresentException, NoSuchElementException,
                                        StaleElementReferenceException)
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.support import expected_conditions as EC
from selenium.webdriver.support.ui import WebDriverWait

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HOSTILE = "<img src=x onerror=alert(1)>"


def table1():
    with open(os.path.join(ROOT, "jobs", "table1.json")) as f:
        return json.load(f)


def longer(name, iterations):
    """Table 1 with more iterations: long enough to be watched (or cancelled) while it runs."""
    job = table1()
    job["name"] = name
    job["tuning"]["algorithm"]["iterations"] = iterations
    return job


class Server:
    def __init__(self, binary, extra=()):
        self.dir = tempfile.mkdtemp(prefix="ftctune-dashboard-")
        self.proc = subprocess.Popen(
            [binary, "serve", "--port", "0", "--store", os.path.join(self.dir, "store"),
             "--threads", "1", *extra],
            stdout=subprocess.PIPE, text=True,
            stderr=open(os.environ["FTCTUNE_SERVER_LOG"], "w")
            if os.environ.get("FTCTUNE_SERVER_LOG") else subprocess.DEVNULL)
        line = self.proc.stdout.readline()
        m = re.search(r"http://127\.0\.0\.1:(\d+)", line)
        if not m:
            self.stop()
            raise RuntimeError("ftctune serve did not start: " + line)
        self.url = "http://127.0.0.1:" + m.group(1)

    def api(self, path, body=None, method=None):
        data = json.dumps(body).encode() if body is not None else None
        req = urllib.request.Request(self.url + path, data=data, method=method,
                                     headers={"Content-Type": "application/json"})
        with urllib.request.urlopen(req, timeout=30) as r:
            return json.loads(r.read())

    def wait_done(self, job_id, timeout=60):
        end = time.time() + timeout
        while time.time() < end:
            j = self.api("/v1/jobs/" + job_id)
            if j["status"] in ("succeeded", "failed", "cancelled"):
                return j
            time.sleep(0.05)
        raise AssertionError("job %s did not finish" % job_id)

    def stop(self):
        self.proc.terminate()
        try:
            self.proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        shutil.rmtree(self.dir, ignore_errors=True)


@pytest.fixture(scope="module")
def server(request):
    s = Server(request.config.getoption("--ftctune"))
    yield s
    s.stop()


DOWNLOADS = tempfile.mkdtemp(prefix="ftctune-dashboard-downloads-")


@pytest.fixture(scope="module")
def browser():
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1000", "--no-first-run", "--disable-extensions"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    # Downloads land in DOWNLOADS, where a test reads them.
    driver.execute_cdp_cmd("Browser.setDownloadBehavior",
                           {"behavior": "allow", "downloadPath": DOWNLOADS})
    yield driver
    driver.quit()
    shutil.rmtree(DOWNLOADS, ignore_errors=True)


def downloaded(name, timeout=20):
    """The JSON of file `name` once the browser has saved it in DOWNLOADS (removed after)."""
    path = os.path.join(DOWNLOADS, name)
    end = time.time() + timeout
    while time.time() < end:
        if os.path.exists(path):
            try:
                with open(path) as f:
                    data = json.load(f)
                os.remove(path)
                return data
            except ValueError:
                pass  # still being written
        time.sleep(0.05)
    raise AssertionError("the browser saved no " + name + " in " + DOWNLOADS)


def wait(driver, condition, timeout=30):
    # The page rebuilds its tables and header on every live update, so an element found a moment
    # ago may be gone: such a condition is tried again, not failed.
    return WebDriverWait(driver, timeout, poll_frequency=0.05,
                         ignored_exceptions=(StaleElementReferenceException,
                                             NoSuchElementException)).until(
                                                 lambda d: condition(d))


def texts(driver, css):
    """The text of every element matching css, read in the page in one step (element handles go
    stale when a live update rebuilds a table)."""
    return driver.execute_script(
        "return Array.from(document.querySelectorAll(arguments[0])).map(e => e.textContent);", css)


def set_job_text(driver, text):
    """The job file pasted into the submit form (as a paste does: one input event)."""
    area = wait(driver, lambda d: d.find_element(By.ID, "job-text"))
    driver.execute_script(
        "arguments[0].value = arguments[1];"
        "arguments[0].dispatchEvent(new Event('input', {bubbles: true}));", area, text)


def open_job(driver, server, job_id):
    driver.get(server.url + "/#/job/" + job_id)
    wait(driver, lambda d: d.find_element(By.ID, "job-progress"))


def screenshot(driver, name):
    folder = os.environ.get("FTCTUNE_SCREENSHOTS")
    if folder:
        os.makedirs(folder, exist_ok=True)
        driver.save_screenshot(os.path.join(folder, name))


def test_submitting_table1_through_the_page(server, browser):
    browser.get(server.url + "/#/submit")
    set_job_text(browser, json.dumps(table1(), indent=2))
    wait(browser, lambda d: d.find_element(By.ID, "valid"))  # checked live by POST /v1/validate
    browser.find_element(By.ID, "submit-job").click()
    wait(browser, lambda d: re.search(r"#/job/[0-9a-f]{16}$", d.current_url))
    job_id = browser.current_url.rsplit("/", 1)[1]
    done = server.wait_done(job_id)
    assert done["status"] == "succeeded"
    assert done["name"] == "table1"
    # The page follows it to the end without a reload: one row per evaluation, one point per
    # iteration.
    evaluations = done["progress"]["evaluations"]
    wait(browser, lambda d: len(d.find_elements(By.CSS_SELECTOR, "#trials-table tbody tr"))
         == evaluations)
    wait(browser, lambda d: d.find_element(By.ID, "convergence").get_attribute("data-points")
         == str(done["progress"]["iteration"] + 1))
    wait(browser, lambda d: d.find_element(By.ID, "scatter").get_attribute("data-points")
         == str(evaluations))
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "#comparison-table tbody tr"))
    wait(browser, lambda d: "noise" in d.find_element(By.CSS_SELECTOR, ".noise-floor").text)
    # A run that succeeded with warnings in its gains file says so in its state (issue 41).
    gains = server.api("/v1/jobs/" + job_id + "/gains")
    assert gains["warnings"], "table1's gains file has warnings (a tuned value at its bound)"
    wait(browser, lambda d: texts(d, "h1 .state") == ["succeeded with warnings"])
    assert str(len(gains["warnings"])) in \
        browser.find_element(By.CSS_SELECTOR, "h1 .state.warned").get_attribute("title")
    # The comparison's columns are the metrics the service lists as tabulated (GET /v1/metrics),
    # per scenario, by label and unit; a metric per fault onset shows every onset's value.
    recorded = [m for m in server.api("/v1/metrics")["metrics"] if m["in_tables"]]
    comparison = server.api("/v1/jobs/" + job_id + "/comparison")
    heads = [h.strip() for h in texts(browser, "#comparison-table th")]
    assert heads == ["controller", "role", "objective", "fitness"] + [
        "%s: %s [%s]" % (s, m["label"], m["unit"]) for s in comparison["scenarios"]
        for m in recorded], heads
    peaks = texts(browser, '#comparison-table td[data-metric="peak_error_after_fault"]')
    onsets = len(comparison["controllers"][0]["scenarios"][0]["peak_error_after_fault"])
    assert len(peaks) == len(comparison["controllers"]) and onsets > 1
    assert all(len(p.split(" / ")) == onsets for p in peaks), peaks
    browser.execute_script("window.scrollTo(0, 0)")
    screenshot(browser, "dashboard-job.png")
    # Sorting by objective puts the lowest first.
    def click_objective(d):
        for h in d.find_elements(By.CSS_SELECTOR, "#trials-table th"):
            if h.text.strip().startswith("objective"):
                h.click()
                return True
        return False
    wait(browser, click_objective)
    heads = [h.strip() for h in texts(browser, "#trials-table th")]
    column = [i for i, h in enumerate(heads) if h.startswith("objective")][0]
    values = [float(c) for c in
              texts(browser, "#trials-table tbody tr td:nth-child(%d)" % (column + 1))[:20]]
    assert values == sorted(values)
    # Cells show six significant digits (they showed all 17), the exact value in their title.
    for cell in browser.find_elements(By.CSS_SELECTOR, "#trials-table tbody tr td")[:200]:
        mantissa = re.sub(r"[^0-9]", "", cell.text.split("e")[0]).lstrip("0")
        assert len(mantissa) <= 6, cell.text
        if cell.get_attribute("title"):
            assert float(cell.get_attribute("title")) == pytest.approx(float(cell.text), rel=1e-5)


def front_ensemble_job():
    """A front over a short ensemble (tests/goal_job.hpp's front_ensemble_job): the CVaR of the
    post-fault ISE against the median control TV, under a limit on the peak command."""
    with open(os.path.join(ROOT, "jobs", "robust-faults.json")) as f:
        job = json.load(f)
    job["name"] = "front-ensemble"
    job["scenarios"][0]["duration"] = 10
    job["scenarios"][0]["faults"][0]["onset"] = 3
    job["scenarios"][0]["faults"][1]["onset"] = 4
    job["ensemble"]["count"] = 11
    job["ensemble"]["faults"]["onset"] = {"uniform": [3, 5]}
    del job["objective"]
    job["goals"] = [
        {"metric": "ise", "window": [0, 4], "window_from": "first_fault", "aggregate": "cvar",
         "alpha": 0.8, "minimize": True},
        {"metric": "control_tv", "aggregate": "quantile", "q": 0.5, "minimize": True},
        {"metric": "peak_command", "aggregate": "max", "at_most": 30}]
    job["tuning"]["algorithm"] = {"type": "bat", "population": 4, "iterations": 1}
    return job


def test_a_front_is_checked_on_held_out_members(server, browser):
    # Issue 42: the page evaluates the front on members the run never saw (GET .../held-out),
    # draws each point's held-out value joined to its in-sample one and lists both; the server
    # keeps the result, so the page shows it again when opened.
    job_id = server.api("/v1/jobs", front_ensemble_job())["id"]
    assert server.wait_done(job_id)["status"] == "succeeded"
    front = server.api("/v1/jobs/" + job_id + "/files/front.json")
    open_job(browser, server, job_id)
    wait(browser, lambda d: d.find_element(By.ID, "held-out-section").is_displayed())
    count = browser.find_element(By.ID, "held-out-count")
    assert count.get_attribute("value") == "11"  # the ensemble's, evaluate's default
    assert browser.find_element(By.ID, "held-out-seed").get_attribute("value") == "8"
    count.clear()
    count.send_keys("5")
    browser.find_element(By.ID, "held-out-run").click()
    rows = "#held-out-points tbody tr"
    wait(browser, lambda d: len(d.find_elements(By.CSS_SELECTOR, rows)) == len(front["points"]),
         timeout=60)
    held = server.api("/v1/jobs/" + job_id + "/files/held-out.json")
    assert held["held_out"]["count"] == 5 and held["held_out"]["seed"] == 8, held["held_out"]
    summary = browser.find_element(By.ID, "held-out-summary").text
    stay = sum(1 for p in held["points"] if not p["dominated"])
    assert summary.startswith("On 5 held-out members (seed 8): %d of %d points stay on the front"
                              % (stay, len(held["points"]))), summary
    for row, p in zip(browser.find_elements(By.CSS_SELECTOR, rows), held["points"]):
        cells = [c.text for c in row.find_elements(By.TAG_NAME, "td")]
        # in sample, held out, ratio for each soft goal (6 significant digits shown)
        for g in range(2):
            assert abs(float(cells[1 + 3 * g]) - p["in_sample"][g]) <= 1e-5 * abs(p["in_sample"][g])
            assert abs(float(cells[2 + 3 * g]) - p["goals"][g]) <= 1e-5 * abs(p["goals"][g])
        assert cells[-1] == ("no" if p["dominated"] else "yes"), cells
    drawable = sum(1 for p in held["points"] if all(isinstance(v, float) for v in p["goals"][:2]))
    wait(browser, lambda d: d.find_element(By.ID, "front-chart").get_attribute("data-held-out")
         == str(drawable))
    screenshot(browser, "dashboard-held-out.png")
    # Kept: opened again, the page shows it without being asked.
    browser.refresh()
    open_job(browser, server, job_id)
    wait(browser, lambda d: len(d.find_elements(By.CSS_SELECTOR, rows)) == len(front["points"]))


def test_a_two_goal_job_shows_its_front(server, browser):
    job = table1()
    job["name"] = "two-goals"
    job["scenarios"][0]["duration"] = 0.05
    job["scenarios"][0]["faults"][0]["onset"] = 0.01
    job["scenarios"][0]["faults"][1]["onset"] = 0.03
    del job["objective"]
    job["goals"] = [{"metric": "ise", "window": [0, 0.05], "minimize": True},
                    {"metric": "control_tv", "minimize": True}]
    job["tuning"]["algorithm"]["population"] = 4
    job["tuning"]["algorithm"]["iterations"] = 2
    job["tuning"]["parameters"]["Kp"] = {"bounds": [1, 50], "scale": "log"}
    job_id = server.api("/v1/jobs", job)["id"]
    assert server.wait_done(job_id)["status"] == "succeeded"
    front = server.api("/v1/jobs/" + job_id + "/files/front.json")
    open_job(browser, server, job_id)
    wait(browser, lambda d: d.find_element(By.ID, "front-chart").get_attribute("data-points")
         == str(len(front["points"])))
    assert "Pareto front: %d tuned points" % len(front["points"]) in \
        browser.find_element(By.CSS_SELECTOR, "#front h3").text
    # Its progress is the front so far, not a "best J" of one corner of it (issue 41).
    best = browser.find_element(By.ID, "job-best").text
    assert best.startswith("front: %d point" % len(front["points"])), best
    assert "one corner of the front" in browser.find_element(By.ID, "convergence-title").text
    # The page loads the finished job again when its live stream opens: read it once that is done.
    wait(browser, lambda d: d.find_element(By.ID, "live").text == "live"
         and d.execute_script("return document.body.dataset.loading") == "0")
    # Each point's noise floor: a band on the chart and a cell of the table, as front.json has it;
    # the pairs that are no trade-off as front.json lists each point's partners (the run's rule,
    # docs/usage.md), and the goals by front.json's labels and units.
    points = front["points"]
    finite = [p for p in points if any(isinstance(f, float) for f in p["noise_floor"][:2])]
    assert finite, "the test job's front has measured floors"
    partners = [p["within_noise"] for p in points]
    assert all(i in partners[k] for i in range(len(points)) for k in partners[i]), partners
    heads = [h.strip() for h in texts(browser, "#front-points th")]
    labels = ["%s [%s]" % (g["label"], g["unit"]) for g in front["goals"]]
    assert heads[2] == labels[0] and heads[4] == labels[1], (heads, labels)
    assert labels[1] == "control TV [command's unit]", labels
    chart = browser.find_element(By.ID, "front-chart")
    assert chart.get_attribute("data-noise-bands") == str(len(finite))
    assert chart.get_attribute("data-noise-links") == str(sum(map(len, partners)) // 2)
    rows = browser.find_elements(By.CSS_SELECTOR, "#front-points tbody tr")
    assert len(rows) == len(points)
    for k, (row, p) in enumerate(zip(rows, points)):
        cells = [c.text for c in row.find_elements(By.TAG_NAME, "td")]
        assert cells[0] == str(k) and cells[1] == str(p["trial"])
        for g in range(2):
            f = p["noise_floor"][g]
            if f is None:
                assert cells[3 + 2 * g] == "–"
            else:
                shown = float(cells[3 + 2 * g].removesuffix(" %"))
                assert abs(shown - 100 * f) <= 0.05 * 100 * f, (k, g, cells, f)
        assert cells[-2] == ", ".join("point %d" % i for i in partners[k]), (k, cells)
        assert cells[-1] == "gains-point-%d.json" % k, (k, cells)
    assert "picked" in rows[front["picked"]["index"]].get_attribute("class")
    # One button per file, though the page loaded the finished job twice.
    buttons = texts(browser, "#downloads button")
    assert sorted(buttons) == sorted(set(buttons)) and "gains.json" in buttons, buttons
    # The front's own files are offered too (issue 41).
    assert "front.json" in buttons and "front.csv" in buttons, buttons
    # Its state names its warnings only when its gains file has some.
    warned = bool(server.api("/v1/jobs/" + job_id + "/gains")["warnings"])
    assert texts(browser, "h1 .state") == [
        "succeeded with warnings" if warned else "succeeded"]
    # A parameter searched on a log scale is drawn on a log axis, and the colours have a scale
    # (issue 41).
    wait(browser, lambda d: d.execute_script("return Chart.getChart('scatter').scales.x.type")
         == "logarithmic")
    assert browser.execute_script("return Chart.getChart('scatter').scales.y.type") == "linear"
    assert "(log scale)" in browser.execute_script(
        "return Chart.getChart('scatter').options.scales.x.title.text")
    heads, rows = trials_of(server, job_id)
    column = heads.index("objective")
    cells = [r.split(",")[column] for r in rows]
    finite = [float(c) for c in cells if c and float(c) > 0]
    bar = browser.find_element(By.ID, "scatter-scale-bar")
    assert float(bar.get_attribute("data-lo")) == min(finite)
    assert float(bar.get_attribute("data-hi")) == max(finite)
    assert "lowest blue" in browser.find_element(By.ID, "scatter-scale").text
    # A point of the front picked on the chart downloads its gains file, as pick writes it
    # (issue 41): clicked where Chart.js drew it; then another by its row's button.
    browser.execute_script("document.getElementById('front').scrollIntoView()")
    k = len(points) - 1
    x, y, w, h = browser.execute_script(
        "const c = Chart.getChart('front-chart');"
        "const e = c.getDatasetMeta(0).data.find((d, i) => c.data.datasets[0].data[i].point"
        " === arguments[0]);"
        "const r = c.canvas.getBoundingClientRect();"
        "return [e.x, e.y, r.width, r.height];", k)
    chart = browser.find_element(By.ID, "front-chart")
    ActionChains(browser).move_to_element_with_offset(chart, x - w / 2, y - h / 2).click().perform()
    assert downloaded("gains-point-%d.json" % k) == \
        server.api("/v1/jobs/%s/gains?pick=index:%d" % (job_id, k))
    assert browser.find_element(By.ID, "front").get_attribute("data-picked") == str(k)
    picked = server.api("/v1/jobs/%s/gains?pick=index:0" % job_id)
    assert picked["tuned"] == points[0]["parameters"]
    browser.find_element(By.CSS_SELECTOR, "#front-points button.pick[data-point='0']").click()
    assert downloaded("gains-point-0.json") == picked
    screenshot(browser, "dashboard-front.png")


def trials_of(server, job_id):
    """trials.csv of a job: its header's columns, and its rows as text."""
    with urllib.request.urlopen(server.url + "/v1/jobs/%s/trials" % job_id, timeout=30) as r:
        lines = [l for l in r.read().decode().split("\n") if l]
    return lines[0].split(","), lines[1:]


def test_progress_updates_without_a_reload(server, browser):
    blocker = server.api("/v1/jobs", longer("blocker", 40))["id"]
    job_id = server.api("/v1/jobs", longer("watched", 30))["id"]
    open_job(browser, server, job_id)  # while it waits in the queue
    browser.execute_script("window.__sameDocument = true;")
    server.api("/v1/jobs/%s/cancel" % blocker, body={}, method="POST")
    seen = set()
    end = time.time() + 60
    while time.time() < end:
        # Read in the page, in one step: the header is rebuilt on every update.
        text, done = browser.execute_script(
            "const p = document.getElementById('job-progress');"
            "return [p ? p.textContent : '', !!document.querySelector('h1 .state.succeeded')];")
        seen.add(text)
        if done:
            break
        time.sleep(0.02)
    assert browser.find_elements(By.CSS_SELECTOR, "h1 .state.succeeded"), seen
    assert len(seen) >= 4, seen  # queued, then several iterations, then done
    assert browser.execute_script("return window.__sameDocument === true;")


def test_jobs_list_is_live_and_filterable(server, browser):
    browser.get(server.url + "/#/")
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "#jobs-table tbody tr"))
    jobs = "#jobs-table tbody tr[data-id]"
    before = len(browser.find_elements(By.CSS_SELECTOR, jobs))
    job_id = server.api("/v1/jobs", longer("listed", 2))["id"]
    row = "#jobs-table tbody tr[data-id='%s']" % job_id
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, row))  # appears without a reload
    done = server.wait_done(job_id)
    wait(browser, lambda d: "succeeded" in d.find_element(By.CSS_SELECTOR, row).text)
    assert len(browser.find_elements(By.CSS_SELECTOR, jobs)) == before + 1
    # Its badge names its gains file's warnings, as its own page does (issue 41).
    warned = len(server.api("/v1/jobs/" + job_id + "/gains").get("warnings", []))
    assert warned > 0, "this short Table 1 run warns (a tuned value at its bound)"
    assert done["warnings"] == warned
    wait(browser, lambda d: d.find_element(By.CSS_SELECTOR, row + " .state").text
         == ("succeeded with warnings" if warned else "succeeded"))
    # Jobs are grouped by what their J measures: each row sits under its measure's header, and
    # the two-goal job's front apart from Table 1's ISE (issue 41).
    groups = browser.execute_script(
        "const out = []; let g = null;"
        "for (const r of document.querySelectorAll('#jobs-table tbody tr')) {"
        "  if (r.classList.contains('group')) { g = r.dataset.objective; out.push([g, []]); }"
        "  else out[out.length - 1][1].push(r.dataset.id); }"
        "return out;")
    listed = {j["id"]: j["objective"] for j in server.api("/v1/jobs?limit=50")["jobs"]}
    assert len({g for g, _ in groups}) == len(groups), groups  # one header per measure
    for objective, ids in groups:
        assert ids and all(listed[i] == objective for i in ids), (objective, ids)
    assert "ISE[0 s, 30 s]" in [g for g, _ in groups], groups
    assert any(g.startswith("front of ") for g, _ in groups), groups
    box = browser.find_element(By.ID, "filter-name")
    box.send_keys("listed")
    wait(browser, lambda d: len(d.find_elements(By.CSS_SELECTOR, jobs)) == 1)
    box.clear()
    box.send_keys(" ")  # an input event with the box emptied again
    browser.execute_script("arguments[0].value=''; arguments[0].dispatchEvent(new Event('input'));",
                           box)
    wait(browser, lambda d: len(d.find_elements(By.CSS_SELECTOR, jobs)) > 1)
    screenshot(browser, "dashboard-jobs.png")


def test_a_bad_job_shows_its_json_path(server, browser):
    job = table1()
    job["scenarios"][0]["duration"] = -1
    browser.get(server.url + "/#/submit")
    set_job_text(browser, json.dumps(job))
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, ".json-error"))
    paths = [t.strip() for t in texts(browser, ".json-error code.path")]
    assert "/scenarios/0/duration" in paths
    assert browser.find_element(By.ID, "submit-job").get_attribute("disabled") is not None
    set_job_text(browser, "{ not json")
    wait(browser, lambda d: "request body" in d.find_element(By.ID, "validation").text)


def test_cancelling_a_job(server, browser):
    # 5 000 iterations (within the service's step budget) take over two minutes on one thread, so
    # the job still runs when the cancel is confirmed. 400 (4.7 s) once finished first on a loaded
    # CI machine.
    job_id = server.api("/v1/jobs", longer("cancelled", 5000))["id"]
    open_job(browser, server, job_id)
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "h1 .state.running"))
    browser.find_element(By.ID, "action-cancel").click()
    assert server.api("/v1/jobs/" + job_id)["status"] == "running"  # not before it is confirmed
    browser.find_element(By.ID, "confirm-yes").click()
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "h1 .state.cancelled"))
    done = server.api("/v1/jobs/" + job_id)
    assert done["status"] == "cancelled" and done["progress"]["iteration"] < 5000
    # Its results so far, marked partial.
    wait(browser, lambda d: "results of the iterations run so far"
         in d.find_element(By.ID, "job-notes").text)
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "#downloads button[data-file]"))


def quick(name):
    """Table 1 with one iteration of two bats: a job that finishes at once."""
    job = table1()
    job["name"] = name
    job["tuning"]["algorithm"]["iterations"] = 1
    job["tuning"]["algorithm"]["population"] = 2
    return job


def open_finished(server, browser, job):
    """Submits `job`, waits for its success and opens its page; its id."""
    job_id = server.api("/v1/jobs", job)["id"]
    assert server.wait_done(job_id)["status"] == "succeeded"
    open_job(browser, server, job_id)
    return job_id


def test_a_hostile_compare_label_stays_text(server, browser):
    job = quick("hostile")
    job["compare"][0]["label"] = HOSTILE
    open_finished(server, browser, job)
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "#comparison-table td.label"))
    labels = [t.strip() for t in texts(browser, "#comparison-table td.label")]
    assert HOSTILE in labels
    sources = browser.execute_script("return Array.from(document.images).map(i => i.src || '');")
    assert not [src for src in sources if src.endswith("/x")]
    with pytest.raises(NoAlertPresentException):
        browser.switch_to.alert.text


def test_a_job_with_sensors_shows_what_its_controller_read(server, browser):
    job = quick("sensed")
    job["scenarios"][0]["sensors"] = {"rate": {"noise": 1e-3}, "delay": 2,
                                      "acceleration": {"source": "differentiated",
                                                       "time_constant": 0.005}}
    open_finished(server, browser, job)
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "#job-notes .sensors"))
    assert texts(browser, "#job-notes .sensors") == [
        "Sensors of scenario paper: rate noise 0.001 rad/s, delay 2 samples, acceleration "
        "differentiated (τ = 0.005 s), noise seed 1, stream 0."]
    # A job without sensors shows none.
    open_finished(server, browser, quick("plain"))
    wait(browser, lambda d: d.find_elements(By.CSS_SELECTOR, "#comparison-table tbody tr"))
    assert not browser.find_elements(By.CSS_SELECTOR, "#job-notes .sensors")


def test_page_headers_forbid_inline_script_and_sniffing(server):
    with urllib.request.urlopen(server.url + "/", timeout=10) as r:
        policy = r.headers["Content-Security-Policy"]
        assert "script-src 'self'" in policy and "unsafe-inline" not in policy
        assert r.headers["X-Content-Type-Options"] == "nosniff"
        assert r.headers.get("Access-Control-Allow-Origin") is None


def test_the_token_is_asked_for_and_kept_in_the_tab(request, browser):
    folder = tempfile.mkdtemp(prefix="ftctune-token-")
    token_file = os.path.join(folder, "token")
    with open(token_file, "w") as f:
        f.write("dashboard-secret\n")
    os.chmod(token_file, 0o600)
    server = Server(request.config.getoption("--ftctune"), ["--token-file", token_file])
    try:
        browser.get(server.url + "/#/")
        box = wait(browser, lambda d: d.find_element(By.ID, "token"))
        box.send_keys("wrong")
        box.submit()
        WebDriverWait(browser, 10).until(EC.staleness_of(box))
        box = wait(browser, lambda d: d.find_element(By.ID, "token"))  # asked again
        box.send_keys("dashboard-secret")
        box.submit()
        wait(browser, lambda d: d.find_element(By.ID, "jobs-count").text == "no jobs")
        assert browser.execute_script("return sessionStorage.getItem('ftctune-token')") \
            == "dashboard-secret"
        assert browser.execute_script("return document.cookie") == ""  # a header, not a cookie
        wait(browser, lambda d: d.find_element(By.ID, "live").text == "live")
    finally:
        browser.execute_script("sessionStorage.clear()")
        server.stop()
        shutil.rmtree(folder, ignore_errors=True)
