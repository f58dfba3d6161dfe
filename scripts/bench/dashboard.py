#!/usr/bin/env python3
"""The dashboard's cost: page loads of a 78,000-run job, and 50 polling dashboards versus the
workers' throughput.

    .venv/bin/python scripts/bench/dashboard.py [--skip pages|polling] [--runs 1000]
                                                [--clients 50] [--poll-runs 6000] [--repeat 2]

Part (a) pages: a coordinator (REST only, in this process, uvicorn on a free loopback port) gets
the ICOOT paper's Table 2 job (PSO, SSA, FDO, mCOOT, COOT, ICOOT x F1-F13 x 30 dims x 500
iterations x ``--runs`` runs per cell: 78,000 runs at 1000) whose results are synthetic (random
best-so-far curves of 500 iterations, as a worker would send them: encoded, packed, handed to the
coordinator's result handler, so the store and the dashboard's aggregates see the real path).
Then it times, median of 5: every request of the job page (HTML, scripts, status, aggregates),
the jobs list and its snapshot; the same page in headless Chromium from navigation to the last
chart drawn (when chromium is here); after a coordinator restart: the page data served from the
page saved when the job ended, the aggregates loaded from the saved arrays, and rebuilt from the
store alone.

Part (b) polling: ``swarmpath up --workers 2`` runs a benchmark job (GWO, PSO, ICOOT x F1-F13 x
10 dims, 30 agents, 200 iterations, runs per cell to make ``--poll-runs`` runs) alone and with
``--clients`` simulated dashboards, alternated (``--repeat`` pairs, then alone once more), each
dashboard holding the /events stream open and polling as job.js does: the status every 2 s, the
aggregates (with If-None-Match) every 6 s. Throughput = runs / (finished -
started) on the coordinator's clock; request latencies of the dashboards' polls (p50, p99). The
clients run in this process, on the same machine: their own CPU time is reported beside the
numbers.

Markdown goes to stdout, progress to stderr.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import platform
import shutil
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import httpx

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "services"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import synthetic  # noqa: E402  (scripts/bench/synthetic.py)
from service import Up, note  # noqa: E402  (scripts/bench/service.py)

TABLE2_ALGORITHMS = ["PSO", "SSA", "FDO", "mCOOT", "COOT", "ICOOT"]
FUNCTIONS = [f"F{i}" for i in range(1, 14)]


# ------------------------------------------------------------------------------ (a) pages
def fill(core: Any, spec: dict[str, Any]) -> str:
    """Submit ``spec`` and feed synthetic results through the coordinator's result handler."""

    def progress(done: int, total: int, seconds: float) -> None:
        if done % 5000 < 1000:
            note(f"  {done}/{total} runs stored ({seconds:.0f} s)")

    job, final = synthetic.fill(core, spec, 30 * spec["iterations"], progress)
    if final is None or final.runs_done != final.runs_total:
        raise RuntimeError(f"the synthetic results were not all accepted: {final}")
    return job


def timed(fn: Any, repeat: int = 5) -> tuple[float, Any]:
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def browser_load(url: str) -> float | None:
    """Seconds from navigation to the job page's charts drawn, in headless Chromium."""
    chromium, driver_path = shutil.which("chromium"), shutil.which("chromedriver")
    if chromium is None or driver_path is None:
        return None
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    opts = Options()
    opts.binary_location = chromium
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--no-proxy-server"):
        opts.add_argument(arg)
    driver = webdriver.Chrome(service=Service(driver_path), options=opts)
    try:
        times = []
        for _ in range(3):
            driver.get(url)
            WebDriverWait(driver, 120).until(
                lambda d: d.find_elements(By.CSS_SELECTOR, "body[data-version]"))
            times.append(driver.execute_script("return performance.now()") / 1000.0)
        return statistics.median(times)
    finally:
        driver.quit()


def pages(runs: int, tmp: Path) -> list[str]:

    from swarmpath.service.coordinator import CoordinatorSettings, create_app
    from swarmpath.service.web.live import Dashboard

    spec = {"kind": "benchmark", "algorithms": TABLE2_ALGORITHMS, "functions": FUNCTIONS,
            "dims": [30], "runs": runs, "agents": 30, "iterations": 500, "seed": 1}
    app = create_app(CoordinatorSettings(data_dir=tmp / "pages", synchronous="NORMAL"),
                     use_zenoh=False)
    server, thread, url = synthetic.start_server(app)
    rows = []
    try:
        core = app.state.core
        t = time.perf_counter()
        job = fill(core, spec)
        total = core.store.job_status(job).runs_total
        note(f"  {total} runs stored in {time.perf_counter() - t:.0f} s")
        with httpx.Client(base_url=url, timeout=60) as http:
            etag = http.get(f"/ui/jobs/{job}/data").headers["etag"]
            assets = ("job.js", "plot.js", "common.js", "style.css")
            requests: list[tuple[str, list[tuple[str, dict[str, str]]]]] = [
                ("job page HTML", [(f"/ui/jobs/{job}", {})]),
                ("job.js + plot.js + common.js + style.css",
                 [(f"/static/{n}", {}) for n in assets]),
                ("job status `/jobs/{id}`", [(f"/jobs/{job}", {})]),
                ("job aggregates `/ui/jobs/{id}/data` (every curve, box, table row, test)",
                 [(f"/ui/jobs/{job}/data", {})]),
                ("same, unchanged (`If-None-Match`: 304)",
                 [(f"/ui/jobs/{job}/data", {"If-None-Match": etag})]),
                ("jobs page HTML + `/ui/jobs`", [("/", {}), ("/ui/jobs", {})]),
            ]
            for label, gets in requests:
                seconds, res = timed(lambda gets=gets: [http.get(p, headers=h) for p, h in gets])
                size = sum(len(r.content) for r in res)
                rows.append(f"| {label} | {seconds * 1000:.0f} ms | {size / 1024:.0f} KiB |")
        seconds = browser_load(f"{url}/ui/jobs/{job}")
        if seconds is not None:
            rows.append(f"| job page in headless Chromium, navigation to last chart drawn | "
                        f"{seconds * 1000:.0f} ms | |")
        t = time.perf_counter()
        assert Dashboard(core.store, core.dashboard.cache_dir).page_data(job) is not None
        rows.append(f"| job page data after a coordinator restart (the page saved when the job "
                    f"ended) | {(time.perf_counter() - t) * 1000:.0f} ms | |")
        for label, cache in (("aggregates loaded from the saved arrays, view computed",
                              core.dashboard.cache_dir),
                             ("aggregates rebuilt from the store alone (no saved file)", None)):
            t = time.perf_counter()
            cold = Dashboard(core.store, cache).aggregates(job)
            assert cold is not None
            cold.view()
            rows.append(f"| {label} | {(time.perf_counter() - t) * 1000:.0f} ms | |")
    finally:
        server.should_exit = True
        thread.join(30)
    head = [f"Job of {total:,} runs (Table 2 shape: 6 algorithms x 13 functions x 30 dims x "
            f"{runs} runs, 500 iterations; synthetic results).", "",
            "| request | time (median of 5) | size |", "|---|---:|---:|"]
    return head + rows


# ---------------------------------------------------------------------------- (b) polling
async def dashboards(url: str, job: str, clients: int, stop: asyncio.Event,
                     latencies: list[float]) -> None:
    """``clients`` job pages: /events held open, status + aggregates polled every 2 s."""
    limits = httpx.Limits(max_connections=2 * clients + 10)
    async with httpx.AsyncClient(base_url=url, timeout=30, limits=limits) as http:
        async def events() -> None:
            while not stop.is_set():
                try:
                    async with http.stream("GET", "/events") as r:
                        async for _chunk in r.aiter_bytes():
                            if stop.is_set():
                                return
                except httpx.HTTPError:
                    await asyncio.sleep(1.0)

        async def poll(offset: float) -> None:
            await asyncio.sleep(offset)
            for name in ("job.js", "plot.js", "common.js", "style.css"):
                await http.get(f"/static/{name}")
            etag, tick = "", 0
            while not stop.is_set():  # as job.js: status every 2 s, data every third time
                t = time.perf_counter()
                await http.get(f"/jobs/{job}")
                if tick % 3 == 0:
                    r = await http.get(f"/ui/jobs/{job}/data", headers={"If-None-Match": etag})
                    etag = r.headers.get("etag", etag)
                latencies.append(time.perf_counter() - t)
                tick += 1
                try:
                    await asyncio.wait_for(stop.wait(), 2.0)
                except TimeoutError:
                    pass

        tasks = [asyncio.create_task(events()) for _ in range(clients)]
        tasks += [asyncio.create_task(poll(2.0 * i / clients)) for i in range(clients)]
        await stop.wait()
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)


def polling(clients: int, total_runs: int, tmp: Path, repeat: int = 2) -> list[str]:
    algorithms, functions, dims = ["GWO", "PSO", "ICOOT"], FUNCTIONS, [10]
    runs = max(1, total_runs // (len(algorithms) * len(functions) * len(dims)))
    spec = {"kind": "benchmark", "algorithms": algorithms, "functions": functions, "dims": dims,
            "runs": runs, "agents": 30, "iterations": 200, "seed": 1}
    rows = ["| dashboards | runs | runs/s | coordinator CPU s | poll p50 | poll p99 | "
            "client CPU s | load before/after |", "|---:|---:|---:|---:|---:|---:|---:|---|"]
    order = [0, clients] * repeat + [0]  # alternated, so drifts in the machine's load show
    with Up(2, tmp) as up:
        for k, n in enumerate(order):
            note(f"  job {k + 1}/{len(order)} with {n} dashboards")
            cpu0 = time.process_time()
            status, latencies = with_dashboards(up, spec, n)
            seconds = float(status["finished"]) - float(status["started"])
            cpu = status["cpu"].get("coordinator")
            lat = sorted(latencies)
            p50 = f"{lat[len(lat) // 2] * 1000:.0f} ms" if lat else ""
            p99 = f"{lat[int(len(lat) * 0.99)] * 1000:.0f} ms" if lat else ""
            load = status["load"]
            rows.append(
                f"| {n} | {status['runs_total']} | {status['runs_total'] / seconds:.1f} | "
                f"{'' if cpu is None else f'{cpu:.1f}'} | {p50} | {p99} | "
                f"{time.process_time() - cpu0:.1f} | {load[0]:.1f} / {load[1]:.1f} |")
    return rows


def with_dashboards(up: Any, spec: dict[str, Any], clients: int) -> tuple[dict[str, Any],
                                                                          list[float]]:
    """Run ``spec`` on ``up`` with ``clients`` dashboards open on it; (status, poll latencies)."""
    latencies: list[float] = []
    job = up.http.post("/jobs", json=spec).json()["id"]
    loop = asyncio.new_event_loop()
    stop = asyncio.Event()

    def run_clients() -> None:
        asyncio.set_event_loop(loop)
        loop.run_until_complete(dashboards(up.url, job, clients, stop, latencies))

    thread = threading.Thread(target=run_clients, daemon=True)
    if clients:
        thread.start()
    try:
        status = wait_job(up, job)
    finally:
        if clients:
            loop.call_soon_threadsafe(stop.set)
            thread.join(60)
    loop.close()
    return status, latencies


def wait_job(up: Any, job: str) -> dict[str, Any]:
    from service import process_cpu

    load0 = os.getloadavg()
    cpu0 = process_cpu(up.proc.pid)
    final: dict[str, Any] = {}

    def ended() -> bool:
        final.update(up.http.get(f"/jobs/{job}").json())
        return final["state"] in ("done", "failed", "cancelled")

    up.wait(ended, 1800, f"job {job}", poll=0.5)
    cpu1 = process_cpu(up.proc.pid)
    final["cpu"] = {k: cpu1[k] - cpu0.get(k, 0.0) for k in cpu1}
    final["load"] = (load0[0], os.getloadavg()[0])
    return final


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--skip", action="append", default=[], choices=["pages", "polling"])
    ap.add_argument("--runs", type=int, default=1000, help="runs per cell of the big job")
    ap.add_argument("--clients", type=int, default=50)
    ap.add_argument("--poll-runs", type=int, default=6000, help="runs of the polled job")
    ap.add_argument("--repeat", type=int, default=2,
                    help="jobs with dashboards, alternated with jobs without (one more)")
    args = ap.parse_args()
    print(f"Machine: {platform.machine()}, {os.cpu_count()} CPUs, Python "
          f"{platform.python_version()}, load average {os.getloadavg()[0]:.1f} at the start.\n")
    with tempfile.TemporaryDirectory(prefix="swarmpath-dash-") as d:
        tmp = Path(d)
        if "pages" not in args.skip:
            note("(a) pages of a big job")
            print("\n".join(pages(args.runs, tmp)) + "\n")
        if "polling" not in args.skip:
            note(f"(b) {args.clients} polling dashboards")
            print("\n".join(polling(args.clients, args.poll_runs, tmp, args.repeat)) + "\n")


if __name__ == "__main__":
    main()
