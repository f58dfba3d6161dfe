"""The dashboard in a real browser: headless Chromium (Debian packages ``chromium`` and
``chromium-driver``) driven by selenium opens every page of a coordinator served on a free
loopback port, waits for the plots and checks what they show; submits a job through the form,
sees its validation errors, and cancels a job from the jobs list.

``SWARMPATH_SCREENSHOTS=DIR`` saves a screenshot of each page into DIR (the README's images:
``SWARMPATH_SCREENSHOTS=docs/img pytest tests/test_web_browser.py``)."""

from __future__ import annotations

import os
import shutil
import socket
import threading
import time
from pathlib import Path

import pytest

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium (the test extra)")
from selenium.common.exceptions import (  # noqa: E402
    NoSuchElementException,
    TimeoutException,
)
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.support.ui import Select, WebDriverWait  # noqa: E402

from swarmpath.service.coordinator import Coordinator, CoordinatorSettings, create_app  # noqa: E402
from swarmpath.service.protocol import (  # noqa: E402
    Lease,
    LeaseRequest,
    decode_work_reply,
    encode,
)
from swarmpath.service.worker import execute_lease, pack_batches  # noqa: E402

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None or CHROMEDRIVER is None,
    reason="headless browser tests need Debian's 'chromium' and 'chromium-driver' packages "
           "(apt-get install chromium chromium-driver)",
)
SHOTS = os.environ.get("SWARMPATH_SCREENSHOTS")
WAIT = 30.0  # seconds a page may take on a loaded machine before the test fails

BENCH = {"kind": "benchmark", "algorithms": ["GWO", "PSO", "ICOOT"], "functions": ["F1", "F8"],
         "dims": [2, 5], "runs": 6, "agents": 8, "iterations": 40, "seed": 3}
MAP = {"kind": "map", "planners": ["MFB", "OMPL-RRTstar"], "maps": ["mfb-static", "mfb-dynamic"],
       "runs": 2, "seed": 1}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def work_off(core: Coordinator, worker: str = "w1") -> int:
    """A worker without the network: lease, execute, hand the results to the coordinator."""
    core.worker_alive(worker)
    n = 0
    while True:
        lease = decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker=worker, max_runs=100, host="test", slots=2))))
        if not isinstance(lease, Lease):
            return n
        results = execute_lease(lease)
        for payload in pack_batches(worker, [data for _run, data in results]):
            core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
        n += len(results)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """A coordinator (REST only) on a free loopback port, stopped after the module."""
    import uvicorn

    os.environ.pop("SWARMPATH_TOKEN", None)
    data = tmp_path_factory.mktemp("dashboard")
    app = create_app(CoordinatorSettings(data_dir=data / "data"), use_zenoh=False)
    port = _free_port()
    srv = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning",
                                        timeout_graceful_shutdown=2))
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + WAIT
    while not srv.started and thread.is_alive() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert srv.started, "the test coordinator did not start"
    try:
        yield f"http://127.0.0.1:{port}", app
    finally:
        srv.should_exit = True
        thread.join(timeout=WAIT)


@pytest.fixture(scope="module")
def jobs(server):
    """A finished benchmark job and a finished map job."""
    import httpx

    url, app = server
    core = app.state.core
    ids = {}
    for spec in (BENCH, MAP):
        r = httpx.post(f"{url}/jobs", json=spec)
        assert r.status_code == 201, r.text
        ids[spec["kind"]] = r.json()["id"]
        work_off(core)
    return ids


@pytest.fixture(scope="module")
def browser():
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    opts = Options()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1000", "--no-proxy-server"):
        opts.add_argument(arg)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})  # CSP reports in the console
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(WAIT)
    try:
        yield driver
    finally:
        driver.quit()


def wait_for(driver, css: str, count: int = 1):
    """The elements matching ``css`` once there are at least ``count`` of them."""
    try:
        WebDriverWait(driver, WAIT).until(
            lambda d: len(d.find_elements(By.CSS_SELECTOR, css)) >= count)
    except TimeoutException:
        logs = "; ".join(e["message"] for e in driver.get_log("browser")) if hasattr(
            driver, "get_log") else ""
        raise AssertionError(f"no {count} x {css!r} on {driver.current_url}: {logs}") from None
    return driver.find_elements(By.CSS_SELECTOR, css)


def shot(driver, name: str) -> None:
    if SHOTS:
        Path(SHOTS).mkdir(parents=True, exist_ok=True)
        height = driver.execute_script("return document.body.scrollHeight")
        driver.set_window_size(1400, min(max(900, int(height) + 40), 3000))
        driver.save_screenshot(str(Path(SHOTS) / f"dashboard-{name}.png"))
        driver.set_window_size(1400, 1000)


def texts(elements) -> list[str]:
    return [e.text for e in elements]


def test_jobs_page_lists_jobs_live_and_filters(server, jobs, browser):
    url, app = server
    browser.get(url + "/")
    rows = wait_for(browser, "#jobs tbody tr", 2)
    states = {r.get_attribute("data-job"): r.get_attribute("data-state") for r in rows}
    assert all(states.get(j) == "done" for j in jobs.values())
    # a job submitted elsewhere appears without a reload (pushed over /events)
    import httpx

    new = httpx.post(f"{url}/jobs", json={**BENCH, "runs": 1, "seed": 9}).json()["id"]
    wait_for(browser, f'#jobs tbody tr[data-job="{new}"][data-state="queued"]')
    shot(browser, "jobs")
    Select(browser.find_element(By.ID, "filter")).select_by_visible_text("queued")
    rows = wait_for(browser, "#jobs tbody tr")
    assert new in [r.get_attribute("data-job") for r in rows]
    assert {r.get_attribute("data-state") for r in rows} == {"queued"}
    assert set(jobs.values()).isdisjoint(r.get_attribute("data-job") for r in rows)
    # cancel it from the page
    browser.find_element(By.CSS_SELECTOR, f'tr[data-job="{new}"] button.cancel').click()
    Select(browser.find_element(By.ID, "filter")).select_by_visible_text("cancelled")
    wait_for(browser, f'#jobs tbody tr[data-job="{new}"][data-state="cancelled"]')
    assert app.state.core.store.job_status(new).state == "cancelled"


def test_job_page_follows_a_running_job(server, jobs, browser):
    """The page of a queued job fills itself in as results arrive, without a reload."""
    import httpx

    url, app = server
    job = httpx.post(f"{url}/jobs", json={**BENCH, "runs": 2, "seed": 11}).json()["id"]
    browser.get(f"{url}/ui/jobs/{job}")
    wait_for(browser, "body[data-version]")  # the page drew what there is: nothing yet
    assert browser.find_element(By.ID, "job-state").text == "queued"
    assert not browser.find_elements(By.CSS_SELECTOR, "#charts g.sp-series")  # no runs yet
    work_off(app.state.core)
    wait_for(browser, "body[data-loaded='1']")  # the refresh loop saw the job end
    assert browser.find_element(By.ID, "job-state").text == "done"
    groups = len(BENCH["functions"]) * len(BENCH["dims"])
    assert len(browser.find_elements(By.CSS_SELECTOR, "#charts .conv g.sp-series")) == groups * len(
        BENCH["algorithms"])
    # the runtime ECDF of every algorithm beside each convergence chart, and A12 / P under the
    # markers of the pivot table
    assert len(browser.find_elements(By.CSS_SELECTOR, "#charts .ecdf g.sp-series")) == groups * len(
        BENCH["algorithms"])
    assert browser.find_elements(By.CSS_SELECTOR, "#pivot .effect")


def test_benchmark_job_page_table_curves_and_boxes(server, jobs, browser):
    url, _app = server
    browser.get(f"{url}/ui/jobs/{jobs['benchmark']}")
    groups = len(BENCH["functions"]) * len(BENCH["dims"])
    wait_for(browser, "#charts .conv svg", groups)
    rows = browser.find_elements(By.CSS_SELECTOR, "#pivot tbody tr")
    assert len(rows) == groups
    header = texts(browser.find_elements(By.CSS_SELECTOR, "#pivot thead th"))
    assert header == ["function", "dim", *BENCH["algorithms"]]
    for row in rows:  # one best per row, the others with a statistics marker
        assert len(row.find_elements(By.CSS_SELECTOR, "td.best")) >= 1
        assert len(row.find_elements(By.CSS_SELECTOR, ".marker")) == len(BENCH["algorithms"]) - 1
    foot = texts(browser.find_elements(By.CSS_SELECTOR, "#pivot tfoot th"))
    assert any("mean rank" in t for t in foot) and any("+/=/-" in t for t in foot)
    # time per run beside the table: wall / CPU medians, as the aggregates hold them
    view = _app.state.core.dashboard.aggregates(jobs["benchmark"]).view()
    times = browser.find_elements(By.CSS_SELECTOR, "#times tbody tr")
    assert len(times) == groups
    for row, g in zip(times, view["groups"], strict=True):
        for a in BENCH["algorithms"]:
            cell = row.find_element(By.CSS_SELECTOR, f'td[data-algorithm="{a}"]')
            wall = float(cell.find_element(By.CSS_SELECTOR, ".wall").text)
            cpu = float(cell.find_element(By.CSS_SELECTOR, ".cpu").text)  # measured: a number
            want = g["algorithms"][a]
            assert cpu >= 0.0 and wall >= 0.0
            # three significant digits (SP.sig)
            assert abs(cpu - want["cpu_seconds"]) <= 0.005 * abs(want["cpu_seconds"]) + 1e-12
            assert abs(wall - want["seconds"]) <= 0.005 * abs(want["seconds"]) + 1e-12
    for chart in browser.find_elements(By.CSS_SELECTOR, "#charts .conv"):
        assert len(chart.find_elements(By.CSS_SELECTOR, "g.sp-series")) == len(BENCH["algorithms"])
        assert len(chart.find_elements(By.CSS_SELECTOR, "polygon.sp-band")) == len(
            BENCH["algorithms"])
        labels = texts(chart.find_elements(By.CSS_SELECTOR, ".sp-axis-label"))
        assert labels == ["iteration", "best-so-far f(x) - f*"]
    for chart in browser.find_elements(By.CSS_SELECTOR, "#charts .box"):
        assert len(chart.find_elements(By.CSS_SELECTOR, "g.sp-box")) == len(BENCH["algorithms"])
    import httpx

    links = {a.get_attribute("id"): a.get_attribute("href")
             for a in browser.find_elements(By.CSS_SELECTOR, "#downloads a")}
    assert {"dl-mcap", "dl-summary-csv", "dl-summary-json", "dl-runs-csv", "dl-runs-parquet",
            "dl-runs-json"} <= set(links)
    for href in links.values():  # every download answers
        r = httpx.get(href, timeout=WAIT)
        assert r.status_code == 200 and r.content, href
    legend = texts(browser.find_elements(By.CSS_SELECTOR, "#legend dt"))
    assert legend == ["failed", "rank", "marker"]
    shot(browser, "job-benchmark")
    # the table's values open the cell's best run
    first = browser.find_element(By.CSS_SELECTOR, "#pivot tbody a.run-link")
    first.click()
    wait_for(browser, "#plot g.sp-series")
    assert "/runs/" in browser.current_url


# a raced job with the default design (looks every round, recycling, futility; see
# test_store_racing: F7's PSO against GWO stops as futile at the look at 30 runs)
RACED = {"kind": "benchmark", "algorithms": ["FDO", "PSO", "GWO"], "functions": ["F1", "F7"],
         "dims": [5], "runs": 60, "agents": 8, "iterations": 30, "seed": 3,
         "racing": {"min_runs": 10, "batch": 10}}


def test_raced_job_page_shows_the_race(server, browser):
    """Per cell its runs, state and round, per pair its verdict, round, pairs and interval (a
    futile one with its look and predictive power), the runs spent against the unraced job's,
    and the table's markers are the race's decisions."""
    import httpx

    url, app = server
    r = httpx.post(f"{url}/jobs", json=RACED)
    assert r.status_code == 201, r.text
    job = r.json()["id"]
    work_off(app.state.core)
    race = httpx.get(f"{url}/jobs/{job}/race").json()
    browser.get(f"{url}/ui/jobs/{job}")
    pairs = wait_for(browser, "#race-pairs tbody tr", 4)
    assert len(pairs) == sum(len(b["duels"]) for b in race["blocks"]) == 4
    shown = {row.get_attribute("data-pair"): row.text for row in pairs}
    markers, futile = {}, []
    for b in race["blocks"]:
        f, d = b["block"]["function"], b["block"]["dim"]
        for duel in b["duels"]:
            text = shown[f"{f}/{d}/{duel['a']}/{duel['b']}"]
            verdict = (f"{duel['better']} better" if duel["decision"] == "different"
                       else duel["decision"])
            assert f"{duel['a']} vs {duel['b']}" in text and verdict in text
            assert f"r{duel['round']}" in text and f"{duel['theta']:.3f}" in text
            assert duel["b"] == "GWO"
            if duel["decision"] == "futile":
                futile.append((f, duel["a"]))
                assert f"(look at {duel['look']} runs), predictive power {duel['power']:.3f}" \
                    in text
            markers[(f, duel["a"])] = duel["marker"]
        row = browser.find_element(By.CSS_SELECTOR, f'#race-cells tr[data-block="{f}/{d}"]')
        for c in b["cells"]:
            cell = row.find_element(By.CSS_SELECTOR, f'td[data-algorithm="{c["algorithm"]}"]')
            assert cell.text == f"{c['runs']} · {c['reason']} r{c['stopped_round']}"
    assert futile == [("F7", "PSO")]
    used = sum(c["runs"] for b in race["blocks"] for c in b["cells"])
    assert used < 6 * 60
    line = browser.find_element(By.ID, "race-line").text
    assert f"{used} runs of {6 * 60}" in line and "futility below 0.05" in line
    for row in browser.find_elements(By.CSS_SELECTOR, "#pivot tbody tr"):
        f = row.get_attribute("data-group").split("/")[0]
        cells = row.find_elements(By.CSS_SELECTOR, "td")[2:]
        for a, cell in zip(RACED["algorithms"], cells, strict=True):
            got = cell.find_elements(By.CSS_SELECTOR, ".marker")
            assert (got[0].text if got else None) == markers.get((f, a))
    legend = browser.find_element(By.CSS_SELECTOR, "#content p.legend").text
    assert "the race's decisions" in legend and "Wilcoxon" not in legend
    shot(browser, "job-raced")


def test_map_job_page_paths_failures_and_boxes(server, jobs, browser):
    import httpx

    url, app = server
    browser.get(f"{url}/ui/jobs/{jobs['map']}")
    maps = wait_for(browser, "#maps section .mapchart svg", len(MAP["maps"]))
    runs_per_map = len(MAP["planners"]) * MAP["runs"]
    for m in maps:
        assert len(m.find_elements(By.CSS_SELECTOR, "polyline.sp-path")) == runs_per_map
        assert m.find_elements(By.CSS_SELECTOR, ".sp-obstacle")
        # presets have no frame of their own: the chart says its positions are the scenario's
        label = m.find_element(By.CSS_SELECTOR, "text.sp-frame")
        assert label.get_attribute("data-frame") == "scenario"
        assert label.text.startswith("scenario frame (m): lower left (0, 0), upper right (")
    view = app.state.core.dashboard.aggregates(jobs["map"]).view()
    paths = [p for g in view["groups"] for c in g["planners"].values() for p in c["paths"]]
    hits = sum(len(p["collisions"]) for p in paths)
    stops = sum(1 for p in paths if not p["success"] and p["failure"] != "collision")
    assert hits > 0  # RRT* plans around the static obstacles only and is hit on mfb-dynamic
    assert len(browser.find_elements(By.CSS_SELECTOR, "#maps .sp-collision")) == hits
    assert len(browser.find_elements(By.CSS_SELECTOR, "#maps .sp-failure")) == hits + stops
    dynamic = browser.find_element(By.CSS_SELECTOR, 'section[data-map="mfb-dynamic"]')
    assert dynamic.find_elements(By.CSS_SELECTOR, "polyline.sp-track")  # moving obstacles
    static = browser.find_element(By.CSS_SELECTOR, 'section[data-map="mfb-static"]')
    assert not static.find_elements(By.CSS_SELECTOR, "polyline.sp-track")
    for what in ("length", "seconds"):
        boxes = browser.find_elements(By.CSS_SELECTOR, f"#maps .box-{what} g.sp-box")
        assert len(boxes) >= len(MAP["maps"])
    cells = browser.find_elements(By.CSS_SELECTOR, "#success tbody tr")
    assert len(cells) == len(MAP["maps"])
    per_cell = browser.find_elements(By.CSS_SELECTOR, "#cells tbody tr")
    assert len(per_cell) == len(MAP["maps"]) * len(MAP["planners"])
    gaps = {tuple(texts(r.find_elements(By.TAG_NAME, "td"))[:2]): texts(
        r.find_elements(By.TAG_NAME, "td"))[7] for r in per_cell}
    for (name, _planner), gap in gaps.items():  # a blank gap says why (the workers' reason)
        if name == "mfb-dynamic":
            assert gap == "no optimum: the map has moving obstacles or a moving goal"
        elif name == "mfb-static":
            assert not gap.startswith("no optimum")
    header = texts(browser.find_elements(By.CSS_SELECTOR, "#cells thead th"))
    assert header[8:10] == ["planning s (median)", "CPU s (median)"]
    for row in per_cell:  # every cell has a CPU time beside its wall time
        assert float(texts(row.find_elements(By.TAG_NAME, "td"))[9]) >= 0.0
    quality = browser.find_elements(By.CSS_SELECTOR, "#quality tbody tr")
    assert len(quality) == len(MAP["maps"]) * len(MAP["planners"])
    head = texts(browser.find_elements(By.CSS_SELECTOR, "#quality thead th"))
    assert head[2:6] == ["clearance min (m)", "clearance mean (m)", "curvature max (1/m)",
                         "curvature mean (1/m)"]
    summary = httpx.get(f"{url}/jobs/{jobs['map']}/summary", timeout=WAIT).json()
    for row in quality:  # a cell with a successful run shows its path metrics
        tds = texts(row.find_elements(By.TAG_NAME, "td"))
        cell = next(g for g in view["groups"] if g["map"] == tds[0])["planners"][tds[1]]
        assert (tds[3] != "") == (cell["succeeded"] > 0)
        # the least clearance over every run: the summary's, with three decimals
        least = next(r["min_clearance"] for r in summary["rows"]
                     if (r["map"], r["planner"]) == (tds[0], tds[1]))
        assert float(tds[2]) == pytest.approx(least, abs=0.0006)
    ranks = browser.find_elements(By.CSS_SELECTOR, "#map-ranks tbody tr")
    assert [r.get_attribute("data-planner") for r in ranks] == MAP["planners"]
    header = texts(browser.find_elements(By.CSS_SELECTOR, "#map-ranks thead th"))
    assert header[1:] == ["success +/=/-", "length +/=/-", "gap +/=/-", "planning s +/=/-",
                          "length mean rank", "gap mean rank", "planning s mean rank"]
    st = view["statistics"]
    for row, p in zip(ranks, MAP["planners"], strict=True):
        cells = texts(row.find_elements(By.TAG_NAME, "td"))
        rank = st["friedman"]["seconds"]["mean_ranks"][p]
        assert abs(float(cells[-1]) - rank) < 0.006  # shown with 2 decimals
        assert (cells[1] == "ref.") == (p == st["reference"])
    legend = texts(browser.find_elements(By.CSS_SELECTOR, "#legend dt"))
    assert {"failed", "collisions", "gap_mean"} <= set(legend)
    shot(browser, "job-map")
    # a path opens its run
    link = browser.find_element(By.CSS_SELECTOR, "#maps a.sp-path-group")
    browser.get(url + browser.execute_script("return arguments[0].getAttribute('href')", link))
    wait_for(browser, "#plot svg .sp-robot")


def test_map_job_page_draws_the_difficulty_curve_of_scen_pairs(server, jobs, browser):
    """A job on pairs of an uploaded .scen: the bucket table equals the summary's rows (what
    swarmpath plan --scen prints) and each planner has a line in both difficulty charts; a job
    without buckets has no such section."""
    import httpx

    url, app = server
    data = Path(__file__).parent / "data"
    up = httpx.post(f"{url}/maps", json={"name": "arena", "format": "movingai",
                                         "map": (data / "arena.map").read_text(),
                                         "scen": (data / "arena.map.scen").read_text()},
                    timeout=WAIT * 4)  # the import process starts at the first upload
    assert up.status_code == 201, up.text
    spec = {"kind": "map", "planners": ["OMPL-RRTstar", "OMPL-BITstar"], "runs": 2, "seed": 2,
            "params": {"OMPL-RRTstar": {"iterations": 60}, "OMPL-BITstar": {"iterations": 400}},
            "maps": [{"map": up.json()["id"], "scen": {"buckets": [0, 15]}}]}
    r = httpx.post(f"{url}/jobs", json=spec, timeout=WAIT)
    assert r.status_code == 201, r.text
    job = r.json()["id"]
    assert work_off(app.state.core) == 8
    summary = httpx.get(f"{url}/jobs/{job}/summary", timeout=WAIT).json()
    assert [(b["planner"], b["bucket"]) for b in summary["buckets"]] == [
        (p, b) for p in spec["planners"] for b in (0, 15)]

    browser.get(f"{url}/ui/jobs/{job}")
    rows = wait_for(browser, "#buckets tbody tr", len(summary["buckets"]))
    shown = [texts(row.find_elements(By.CSS_SELECTOR, "td")) for row in rows]
    want = sorted(summary["buckets"], key=lambda b: (b["bucket"], spec["planners"].index(
        b["planner"])))
    assert [row[:4] for row in shown] == [
        [str(b["bucket"]), b["planner"], str(b["pairs"]), f"{b['successes']}/{b['runs']}"]
        for b in want]
    for row, b in zip(shown, want, strict=True):
        assert float(row[4]) == pytest.approx(100 * b["success_rate"], abs=0.05)
        if isinstance(b["gap_median"], float):
            assert float(row[5]) == pytest.approx(100 * b["gap_median"], rel=0.01, abs=0.006)
        else:
            assert row[5] == ""
    for chart, key in ((".difficulty-success", "success_rate"), (".difficulty-gap", "gap_median")):
        series = browser.find_elements(By.CSS_SELECTOR, f"#difficulty {chart} g.sp-series")
        assert [g.get_attribute("data-name") for g in series] == spec["planners"]
        for g, planner in zip(series, spec["planners"], strict=True):
            points = [b for b in want if b["planner"] == planner and isinstance(b[key], float)]
            d = g.find_element(By.CSS_SELECTOR, "path.sp-line").get_attribute("d")
            assert d.count("M") + d.count("L") == len(points)  # one vertex per bucket with a value
        labels = texts(browser.find_elements(By.CSS_SELECTOR, f"#difficulty {chart} .sp-xlabel"))
        assert labels == ["MovingAI bucket"]
    shot(browser, "job-buckets")
    browser.get(f"{url}/ui/jobs/{jobs['map']}")
    wait_for(browser, "#maps section .mapchart svg", len(MAP["maps"]))
    assert not browser.find_elements(By.CSS_SELECTOR, "#buckets, #difficulty")


def test_run_pages(server, jobs, browser):
    url, _app = server
    browser.get(f"{url}/ui/jobs/{jobs['benchmark']}/runs/0")
    wait_for(browser, "#plot g.sp-series")
    assert len(browser.find_elements(By.CSS_SELECTOR, "#best-position tbody tr")) == \
        BENCH["dims"][0]
    shot(browser, "run-benchmark")
    # a map run that failed on the dynamic map (RRT* collides there): the slider moves things
    browser.get(f"{url}/ui/jobs/{jobs['map']}/runs/6")
    wait_for(browser, "#plot svg .sp-robot")
    assert "Failure" in browser.find_element(By.ID, "failure").text
    assert browser.find_elements(By.CSS_SELECTOR, "#plot .sp-collision")
    before = browser.find_element(By.CSS_SELECTOR, "#plot .sp-robot").get_attribute("cx")
    browser.execute_script("const s = document.getElementById('time'); s.value = s.max / 3;"
                           "s.dispatchEvent(new Event('input'));")
    after = browser.find_element(By.CSS_SELECTOR, "#plot .sp-robot").get_attribute("cx")
    assert before != after
    assert browser.find_element(By.ID, "time-label").text.startswith("t = ")
    shot(browser, "run-map")


def test_workers_page(server, jobs, browser):
    url, _app = server
    browser.get(url + "/ui/workers")
    rows = wait_for(browser, "#workers tbody tr")
    assert rows[0].get_attribute("data-worker") == "w1"
    cells = texts(rows[0].find_elements(By.TAG_NAME, "td"))
    assert cells[3] == "2"  # slots
    assert int(cells[6]) > 0  # runs done
    shot(browser, "workers")


def test_submit_form_shows_errors_at_fields_then_submits(server, jobs, browser):
    url, app = server
    browser.get(url + "/ui/submit")
    wait_for(browser, "#submit-form input[name=algorithms]")
    form = browser.find_element(By.ID, "submit-form")
    form.find_element(By.CSS_SELECTOR, "input[name=algorithms][value=GWO]").click()
    form.find_element(By.CSS_SELECTOR, "input[name=functions][value=F1]").click()
    dims = form.find_element(By.NAME, "dims")
    dims.clear()
    dims.send_keys("2, x")
    runs = form.find_element(By.NAME, "runs")
    runs.clear()
    runs.send_keys("0")
    browser.find_element(By.ID, "submit-button").click()
    wait_for(browser, '[data-error="runs"]:not(:empty)')
    assert browser.find_element(By.CSS_SELECTOR, '[data-error="dims"]').text
    assert not browser.find_element(By.CSS_SELECTOR, '[data-error="agents"]').text
    shot(browser, "submit")
    dims.clear()
    dims.send_keys("2")
    runs.clear()
    runs.send_keys("2")
    browser.find_element(By.ID, "submit-button").click()
    link = wait_for(browser, "#new-job")[0]
    status = app.state.core.store.job_status(link.text)
    assert status is not None and status.runs_total == 2
    assert not browser.find_element(By.CSS_SELECTOR, '[data-error="runs"]').text
    # a map job: an unknown reference planner is named at its field
    browser.find_element(By.CSS_SELECTOR, "input[name=kind][value=map]").click()
    form.find_element(By.CSS_SELECTOR, "input[name=planners][value=MFB]").click()
    form.find_element(By.CSS_SELECTOR, "input[name=maps][value=mfb-static]").click()
    form.find_element(By.NAME, "map_reference").send_keys("NOPE")
    form.find_element(By.NAME, "optimum_budget").send_keys("0")
    browser.find_element(By.ID, "submit-button").click()
    wait_for(browser, '[data-error="map_reference"]:not(:empty)')
    wait_for(browser, '[data-error="optimum_budget"]:not(:empty)')
    form.find_element(By.NAME, "map_reference").clear()
    form.find_element(By.NAME, "optimum_budget").clear()
    form.find_element(By.NAME, "optimum_budget").send_keys("7.5")
    browser.find_element(By.ID, "submit-button").click()
    WebDriverWait(browser, WAIT, ignored_exceptions=(NoSuchElementException,)).until(
        lambda d: d.find_element(By.ID, "new-job").text not in ("", status.id))
    new = app.state.core.store.job_status(browser.find_element(By.ID, "new-job").text)
    assert new is not None and new.kind == "map"
    assert new.runs_total == 10  # the form's default runs per cell, one cell
    assert app.state.core.store.job_spec(new.id).optimum_budget == 7.5


def test_token_is_asked_for_and_sent(tmp_path, browser, monkeypatch):
    """With SWARMPATH_TOKEN set, the pages ask for it; submit and cancel send it."""
    import httpx
    import uvicorn

    monkeypatch.setenv("SWARMPATH_TOKEN", "s3cret-token")
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    port = _free_port()
    srv = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning",
                                        timeout_graceful_shutdown=2))
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    try:
        while not srv.started and thread.is_alive():
            time.sleep(0.05)
        url = f"http://127.0.0.1:{port}"
        browser.get(url + "/ui/submit")
        browser.execute_script("localStorage.clear()")
        browser.get(url + "/ui/submit")
        wait_for(browser, "#token-box:not([hidden])")  # the page asks at once
        assert "SWARMPATH_TOKEN" in browser.find_element(By.ID, "token-message").text
        wait_for(browser, "#submit-form input[name=algorithms]")
        form = browser.find_element(By.ID, "submit-form")
        form.find_element(By.CSS_SELECTOR, "input[name=algorithms][value=GWO]").click()
        form.find_element(By.CSS_SELECTOR, "input[name=functions][value=F1]").click()
        browser.find_element(By.ID, "submit-button").click()  # no token yet: 401
        wait_for(browser, '#general-error:not(:empty)')
        browser.find_element(By.ID, "token-input").send_keys("s3cret-token")
        browser.find_element(By.CSS_SELECTOR, "#token-box button").click()
        browser.find_element(By.ID, "submit-button").click()
        job = wait_for(browser, "#new-job")[0].text
        assert httpx.get(f"{url}/jobs/{job}").json()["state"] == "queued"
        browser.get(url + "/")
        wait_for(browser, f'#jobs tbody tr[data-job="{job}"] button.cancel')[0].click()
        wait_for(browser, f'#jobs tbody tr[data-job="{job}"][data-state="cancelled"]')
    finally:
        browser.execute_script("localStorage.clear()")
        srv.should_exit = True
        thread.join(timeout=WAIT)


# ----------------------------------------------------------------------- issue 25: rough edges
def page_ready(browser, url: str, page: str, css: str) -> list:
    """The browser console's messages while ``page`` loads and draws ``css``."""
    browser.get_log("browser")  # forget what earlier pages said
    browser.get(url + page)
    wait_for(browser, css)
    return [e["message"] for e in browser.get_log("browser")]


def test_every_page_draws_under_its_content_security_policy(server, jobs, browser):
    """Every page is served with the dashboard's CSP (no inline script or style, no framing)
    and the other security headers, and draws without one CSP violation in the console (the
    pages set styles through the CSSOM); the favicon is served and linked."""
    import httpx

    from swarmpath.service.http.middleware import DASHBOARD_CSP

    url, _app = server
    pages = {"/": "#jobs tbody tr", "/ui/workers": "#workers tbody tr",
             "/ui/submit": "#submit-form input[name=algorithms]",
             f"/ui/jobs/{jobs['benchmark']}": "#charts .conv svg",
             f"/ui/jobs/{jobs['map']}": "#maps section .mapchart svg",
             f"/ui/jobs/{jobs['benchmark']}/runs/0": "#plot g.sp-series",
             f"/ui/jobs/{jobs['map']}/runs/6": "#plot svg .sp-robot"}
    for page, css in pages.items():
        r = httpx.get(url + page)
        assert r.headers["content-security-policy"] == DASHBOARD_CSP, page
        assert r.headers["x-frame-options"] == "DENY"
        assert r.headers["x-content-type-options"] == "nosniff"
        said = page_ready(browser, url, page, css)
        violations = [m for m in said if "Content Security Policy" in m]
        assert not violations, (page, violations)
        icon = browser.find_element(By.CSS_SELECTOR, "link[rel=icon]").get_attribute("href")
        assert icon.endswith("/static/favicon.svg")
    for path in ("/favicon.ico", "/static/favicon.svg"):
        r = httpx.get(url + path)
        assert r.status_code == 200 and r.headers["content-type"] == "image/svg+xml"
        assert r.content.startswith(b"<svg")
    # progress bars keep their width without an inline style attribute
    browser.get(url + "/")
    bar = wait_for(browser, f'#jobs tr[data-job="{jobs["benchmark"]}"] .bar > span')[0]
    assert browser.execute_script("return arguments[0].style.width", bar) == "100%"


def test_numbers_read_as_the_cli_prints_them(server, jobs, browser):
    """A small standard deviation keeps its significant digits (GWO F1 showed 0.004 (0)); the
    gap is in percent, as the CLI prints it (the dashboard showed 0.022 where the CLI said 2.26);
    the jobs list says what each job runs."""
    url, app = server
    browser.get(f"{url}/ui/jobs/{jobs['benchmark']}")
    wait_for(browser, "#pivot tbody tr")
    assert browser.execute_script("return [SP.sig(0.004, 2), SP.sig(0.0041234, 2), "
                                  "SP.sig(123.456, 3), SP.sig(0, 2), SP.sig(2.5e-7, 2)]") == [
        "0.004", "0.0041", "123", "0", "2.5e-7"]
    view = app.state.core.dashboard.aggregates(jobs["benchmark"]).view()
    for g in view["groups"]:
        row = browser.find_element(By.CSS_SELECTOR, f'#pivot tr[data-group="{g["function"]}/'
                                                    f'{g["dim"]}"]')
        for td, a in zip(row.find_elements(By.TAG_NAME, "td")[2:], BENCH["algorithms"],
                         strict=True):
            std = g["algorithms"][a]["describe"]["std"]
            shown = td.text.split("(", 1)[1].split(")", 1)[0]
            assert shown == browser.execute_script("return SP.sig(arguments[0], 2)", std)
            assert (shown == "0") == (std == 0)
    browser.get(f"{url}/ui/jobs/{jobs['map']}")
    rows = wait_for(browser, "#cells tbody tr", len(MAP["maps"]) * len(MAP["planners"]))
    header = texts(browser.find_elements(By.CSS_SELECTOR, "#cells thead th"))
    assert header[7] == "gap % (median)"
    view = app.state.core.dashboard.aggregates(jobs["map"]).view()
    for row in rows:
        tds = texts(row.find_elements(By.TAG_NAME, "td"))
        cell = next(g for g in view["groups"] if g["map"] == tds[0])["planners"][tds[1]]
        if cell["box"].get("gap"):
            assert float(tds[7].split("\n")[0].rstrip("+=-")) == pytest.approx(
                100 * cell["box"]["gap"]["median"], abs=0.006)
    browser.get(url + "/")
    wait_for(browser, "#jobs tbody tr")
    contents = {r.get_attribute("data-job"): r.find_element(By.CSS_SELECTOR, "td.contents").text
                for r in browser.find_elements(By.CSS_SELECTOR, "#jobs tbody tr")}
    assert contents[jobs["benchmark"]] == "GWO, PSO, ICOOT x F1, F8 x D 2, 5"
    assert contents[jobs["map"]] == "MFB, OMPL-RRTstar x mfb-static, mfb-dynamic"


def test_maps_are_uploaded_and_chosen_in_the_submit_form(server, browser):
    """The dashboard uploads a MovingAI map and a nav2 map (YAML + image), lists the uploaded
    maps beside the presets, submits a job on one, and the job's pages name it as uploaded, not
    by its id; a nav2 upload without its image is refused at the form."""
    url, app = server
    data = Path(__file__).parent / "data"
    browser.get(url + "/ui/submit")
    wait_for(browser, "#submit-form input[name=algorithms]")
    form = browser.find_element(By.ID, "submit-form")
    browser.find_element(By.CSS_SELECTOR, "input[name=kind][value=map]").click()
    form.find_element(By.NAME, "up_yaml").send_keys(str(data / "tb3_sandbox.yaml"))
    browser.find_element(By.ID, "upload-button").click()
    wait_for(browser, '[data-error="upload"]:not(:empty)')  # no image chosen
    form.find_element(By.NAME, "up_image").send_keys(str(data / "tb3_sandbox.pgm"))
    browser.find_element(By.ID, "upload-button").click()
    nav_id = wait_for(browser, "#uploaded-id")[0].text
    assert app.state.core.store.map_info(nav_id)["name"] == "tb3_sandbox"
    Select(form.find_element(By.NAME, "up_format")).select_by_value("movingai")
    form.find_element(By.NAME, "up_map").send_keys(str(data / "arena.map"))
    resolution = form.find_element(By.NAME, "up_resolution")
    resolution.clear()
    resolution.send_keys("0.5")
    browser.find_element(By.ID, "upload-button").click()
    WebDriverWait(browser, WAIT).until(
        lambda d: d.find_element(By.ID, "uploaded-id").text not in ("", nav_id))
    arena_id = browser.find_element(By.ID, "uploaded-id").text
    chosen = [i.get_attribute("value") for i in
              form.find_elements(By.CSS_SELECTOR, "input[name=uploaded]:checked")]
    assert chosen == [nav_id, arena_id]  # each upload is chosen for the job
    # the job on one of them: tb3_sandbox (OMPL-RRTstar's run on arena was 18 s of CPU)
    form.find_element(By.CSS_SELECTOR, f'input[name=uploaded][value="{arena_id}"]').click()
    form.find_element(By.CSS_SELECTOR, "input[name=planners][value=OMPL-RRTstar]").click()
    runs = form.find_element(By.NAME, "map_runs")
    runs.clear()
    runs.send_keys("1")
    browser.find_element(By.ID, "submit-button").click()
    job = wait_for(browser, "#new-job")[0].text
    spec = app.state.core.store.job_spec(job)
    assert [m["name"] for m in spec.maps] == ["tb3_sandbox"]
    assert spec.maps[0]["description"].startswith(f"uploaded map {nav_id}")
    work_off(app.state.core)
    browser.get(f"{url}/ui/jobs/{job}")
    row = wait_for(browser, "#cells tbody tr")[0]
    assert row.find_elements(By.TAG_NAME, "td")[0].text == "tb3_sandbox"
    shown = browser.find_element(By.TAG_NAME, "body").text
    assert nav_id not in shown.replace(f"uploaded map {nav_id}", "")
    # a page opened before the upload lists it once reloaded
    browser.get(url + "/ui/submit")
    labels = [e.get_attribute("textContent").strip()
              for e in wait_for(browser, "#uploaded-maps label", 2)]
    assert any(t.startswith("arena") for t in labels), labels


def test_a_scen_is_uploaded_with_its_map_and_its_pairs_picked_in_the_submit_form(
        server, browser, tmp_path):
    """The submit page uploads a MovingAI .map with its .scen (a broken .scen is refused at
    its field, nothing stored), shows a pairs picker for it, counts the pairs each choice
    names, and submits the job spec the API takes: N pairs per bucket, rows, every pair, the
    map's own start and goal; a choice the page can tell is wrong is not sent, and one the API
    refuses is shown in the picker with the field it names."""
    url, app = server
    core = app.state.core
    data = Path(__file__).parent / "data"

    def put(name: str, text: str) -> None:
        field[name].clear()
        field[name].send_keys(text)

    def shows(element, want: str) -> None:
        try:
            WebDriverWait(browser, WAIT).until(lambda d: element.text == want)
        except TimeoutException:
            raise AssertionError(f"{element.text!r} != {want!r}") from None

    browser.get(url + "/ui/submit")
    wait_for(browser, "#submit-form input[name=algorithms]")
    form = browser.find_element(By.ID, "submit-form")
    browser.find_element(By.CSS_SELECTOR, "input[name=kind][value=map]").click()
    Select(form.find_element(By.NAME, "up_format")).select_by_value("movingai")
    form.find_element(By.NAME, "up_map").send_keys(str(data / "arena.map"))
    bad = tmp_path / "arena.scen"
    bad.write_text("version 1\n0\tarena.map\t50\t49\t1\t1\t2\t2\t1.4\n")
    form.find_element(By.NAME, "up_scen").send_keys(str(bad))
    stored = len(core.store.list_maps(1000, 0))
    browser.find_element(By.ID, "upload-button").click()
    error = wait_for(browser, '[data-error="up.scen"]:not(:empty)')[0].text
    assert error.startswith("scen: ") and "line 2: a pair of a 50 x 49 map" in error, error
    assert len(core.store.list_maps(1000, 0)) == stored
    form.find_element(By.NAME, "up_scen").send_keys(str(data / "arena.map.scen"))
    browser.find_element(By.ID, "upload-button").click()
    map_id = wait_for(browser, "#uploaded-id")[0].text
    assert "160 .scen pairs in buckets 0-15" in browser.find_element(By.ID, "upload-result").text
    assert not browser.find_element(By.CSS_SELECTOR, '[data-error="up.scen"]').text
    picker = wait_for(browser, f'fieldset.pairs[data-map="{map_id}"]:not([hidden])')[0]
    field = {k: picker.find_element(By.CSS_SELECTOR, f'[data-pairs="{k}"]')
             for k in ("mode", "buckets", "per_bucket", "rows", "count")}
    box = picker.find_element(By.CSS_SELECTOR, f'[data-error="pairs.{map_id}"]')
    assert field["buckets"].get_attribute("value") == "0-15"
    shows(field["count"], "16 pairs: one map each")
    assert not field["rows"].is_displayed()
    form.find_element(By.CSS_SELECTOR, "input[name=planners][value=MFB]").click()
    form.find_element(By.CSS_SELECTOR, "input[name=maps][value=mfb-static]").click()
    runs = form.find_element(By.NAME, "map_runs")
    runs.clear()
    runs.send_keys("1")

    def submit() -> list[str]:
        """The maps of the job the form submits (cancelled: only its spec is looked at)."""
        before = texts(browser.find_elements(By.ID, "new-job"))
        browser.find_element(By.ID, "submit-button").click()
        WebDriverWait(browser, WAIT, ignored_exceptions=(NoSuchElementException,)).until(
            lambda d: texts(d.find_elements(By.ID, "new-job")) not in ([], before))
        job = browser.find_element(By.ID, "new-job").text
        spec = core.store.job_spec(job)
        core.cancel(job)
        names = [m if isinstance(m, str) else m["name"] for m in spec.maps]
        assert names[0] == "mfb-static"
        assert spec.buckets == {n: int(n.split("#")[1]) // 10 for n in names[1:] if "#" in n}
        return names[1:]

    put("buckets", "0, 15")
    put("per_bucket", "2")
    shows(field["count"], "4 pairs: one map each")
    shot(browser, "submit-pairs")
    assert submit() == ["arena#0", "arena#1", "arena#150", "arena#151"]
    Select(field["mode"]).select_by_value("rows")
    assert field["rows"].is_displayed() and not field["buckets"].is_displayed()
    put("rows", "3 40-41")
    shows(field["count"], "3 pairs: one map each")
    assert submit() == ["arena#3", "arena#40", "arena#41"]
    put("rows", "158-160")  # the page knows the .scen's 160 pairs: not sent
    shows(box, "rows: 160 is beyond the 160 pairs of the .scen (0 = first)")
    browser.find_element(By.ID, "submit-button").click()
    WebDriverWait(browser, WAIT).until(
        lambda d: d.find_element(By.ID, "result").text == "not sent")
    assert box.text.startswith("rows: 160 is beyond")
    put("rows", "7, 7")  # the API refuses it: shown in the picker, naming the field
    browser.find_element(By.ID, "submit-button").click()
    WebDriverWait(browser, WAIT).until(lambda d: box.text != "")
    assert box.text.startswith("scen.rows: ") and "duplicate" in box.text, box.text
    assert browser.find_element(By.ID, "result").text == "rejected (422)"
    Select(field["mode"]).select_by_value("all")
    shows(field["count"], "160 pairs: one map each")
    assert submit() == [f"arena#{k}" for k in range(160)]
    Select(field["mode"]).select_by_value("none")
    shows(field["count"], "")
    assert submit() == ["arena"]
    form.find_element(By.CSS_SELECTOR, f'input[name=uploaded][value="{map_id}"]').click()
    assert not picker.is_displayed()  # unchosen: no picker


def test_a_nav2_map_chart_names_its_map_frame_and_positions_in_it(server, browser):
    """The map chart of a job on a nav2 map is drawn in the scenario frame and labelled with
    the map's frame: its corners and the start/goal there are the scenario's plus the YAML
    origin (tb3_sandbox: -10, -10), what the tables and GET /maps report."""
    import base64

    import httpx

    url, app = server
    data = Path(__file__).parent / "data"
    up = httpx.post(f"{url}/maps", timeout=WAIT, json={
        "name": "tb3", "format": "nav2", "yaml": (data / "tb3_sandbox.yaml").read_text(),
        "image": base64.b64encode((data / "tb3_sandbox.pgm").read_bytes()).decode()})
    assert up.status_code == 201, up.text
    tb3 = up.json()
    assert (tb3["frame"], tb3["origin"]) == ("map", [-10.0, -10.0])
    r = httpx.post(f"{url}/jobs", json={
        "kind": "map", "planners": ["OMPL-RRTstar"], "maps": [{"map": tb3["id"]}], "runs": 1,
        "seed": 1, "params": {"OMPL-RRTstar": {"iterations": 500}}})
    assert r.status_code == 201, r.text
    work_off(app.state.core)
    browser.get(f"{url}/ui/jobs/{r.json()['id']}")
    (chart,) = wait_for(browser, "#maps section .mapchart svg")
    label = chart.find_element(By.CSS_SELECTOR, "text.sp-frame")
    assert label.get_attribute("data-frame") == "map"
    assert label.get_attribute("data-origin") == "-10,-10"
    w, h = tb3["size"]
    assert label.text == (f"map frame (m): lower left (-10, -10), upper right "
                          f"({round(w - 10.0, 2):g}, {round(h - 10.0, 2):g})")
    titles = [t.get_attribute("textContent") for t in
              chart.find_elements(By.CSS_SELECTOR, "circle.sp-start title, circle.sp-goal title")]
    import re

    for title, name in zip(titles, ("start", "goal"), strict=True):
        got = re.fullmatch(rf"{name} \((\S+), (\S+)\), map frame", title)
        assert got is not None, title
        # GET /maps gives start and goal in the map frame; the chart shows two decimals
        assert [float(v) for v in got.groups()] == pytest.approx(tb3[name], abs=0.0051)


def test_a_store_that_cannot_write_shows_a_banner(server, browser):
    """Disk full (issue 25, failure 7): every page says so until the store can write again."""
    url, app = server
    store = app.state.core.store
    store.write_problem = (time.time(), "the store cannot write to swarmpath.sqlite3 "
                                        "(database or disk is full; 0 bytes free on its disk)")
    try:
        browser.get(url + "/ui/workers")
        alert = wait_for(browser, "#health-alert:not([hidden])")[0]
        assert "database or disk is full" in alert.text and "no work is handed out" in alert.text
    finally:
        store.write_problem = None
    WebDriverWait(browser, WAIT).until(  # checked every 10 s
        lambda d: d.find_element(By.ID, "health-alert").get_attribute("hidden") is not None)
