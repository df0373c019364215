"""How long the dashboard takes to load on a store of 1 000 jobs, in headless Chromium.

    /usr/bin/python3 tests/web/bench_page.py build/tools/ftctune

Starts `ftctune serve` on a temporary store, submits 1 000 small jobs through the API and lets
them run, then loads the jobs list ten times (from about:blank, so each is a whole page load: the
HTML, the styles, Chart.js, the script, the first page of 50 jobs and the event stream) and prints
the time from the request until the 50 rows are on the page, and the browser's own load time
(Navigation Timing: until the load event). Not part of the test suite: filling the store takes a
while.
"""
import json
import os
import statistics
import sys
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_dashboard import Server, table1  # noqa: E402
from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402

JOBS = int(os.environ.get("FTCTUNE_BENCH_JOBS", "1000"))


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else "build/tools/ftctune"
    server = Server(binary, ["--max-queued", "0", "--max-queued-per-client", "0"])
    try:
        tiny = table1()
        tiny["scenarios"][0]["duration"] = 0.05
        tiny["scenarios"][0]["faults"][0]["onset"] = 0.01
        tiny["scenarios"][0]["faults"][1]["onset"] = 0.03
        tiny["objective"]["window"] = [0, 0.05]
        tiny["tuning"]["algorithm"]["population"] = 2
        tiny["tuning"]["algorithm"]["iterations"] = 1
        t0 = time.time()
        for i in range(JOBS):
            tiny["name"] = "job-%04d" % i
            server.api("/v1/jobs", tiny)
        while server.api("/healthz")["queued"] or server.api("/healthz")["running"]:
            time.sleep(0.2)
        print("store: %d jobs submitted and run in %.1f s" % (JOBS, time.time() - t0))

        options = webdriver.ChromeOptions()
        options.binary_location = "/usr/bin/chromium"
        for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                    "--window-size=1400,1000"):
            options.add_argument(arg)
        driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
        rows, loads = [], []
        try:
            for _ in range(11):
                driver.get("about:blank")
                t = time.perf_counter()
                driver.get(server.url + "/#/")
                while driver.execute_script(
                        "return document.querySelectorAll('#jobs-table tbody tr').length") < 50:
                    time.sleep(0.005)
                rows.append(1000 * (time.perf_counter() - t))
                if os.environ.get("FTCTUNE_BENCH_VERBOSE"):
                    print("%.0f ms" % rows[-1], driver.execute_script(
                        "return performance.getEntriesByType('resource').map("
                        "r => r.name.replace(/^https?:\\/\\/[^/]*/, '') + ' ' + "
                        "Math.round(r.startTime) + '+' + Math.round(r.duration)).join(', ')"))
                loads.append(driver.execute_script(
                    "return performance.getEntriesByType('navigation')[0].duration"))
        finally:
            driver.quit()
        rows, loads = rows[1:], loads[1:]  # the first warms Chromium up
        print("jobs list, 50 of %d rows on the page: median %.0f ms, max %.0f ms (10 loads)"
              % (JOBS, statistics.median(rows), max(rows)))
        print("browser's load event (Navigation Timing): median %.0f ms, max %.0f ms"
              % (statistics.median(loads), max(loads)))
        api = []
        for _ in range(11):
            t = time.perf_counter()
            with urllib.request.urlopen(server.url + "/v1/jobs?limit=50", timeout=10) as r:
                json.loads(r.read())
            api.append(1000 * (time.perf_counter() - t))
        print("GET /v1/jobs?limit=50 alone: median %.1f ms (11 requests)" % statistics.median(api))
    finally:
        server.stop()


if __name__ == "__main__":
    main()
