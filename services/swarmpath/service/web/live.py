"""The dashboard's in-memory state in the coordinator: one :class:`JobAggregates` per recent job,
fed by the coordinator as it accepts results (:meth:`Dashboard.observe`), built once from the
store for a job that is not in memory (after a restart, or evicted), and the live jobs list that
every open page shares (:meth:`Dashboard.jobs_snapshot`, computed at most twice a second
whatever the number of clients).

A finished job's aggregates are saved in ``cache_dir`` (:meth:`Dashboard.finished`) and loaded
from there when the job is not in memory, so its page stays quick after a restart; unfinished
jobs are rebuilt from the store in the background at startup (:meth:`Dashboard.warm`).

Bounded: at most ``max_jobs`` jobs' aggregates (least recently used evicted), a rate window of
``RATE_WINDOW`` seconds per job, at most ``max_scenes`` map scenes."""

from __future__ import annotations

import json
import logging
import re
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from swarmpath.service.store import FINAL_STATES
from swarmpath.service.util import json_safe
from swarmpath.service.web.aggregates import SAVE_FORMAT, JobAggregates

_SAFE_ID = re.compile(r"^[A-Za-z0-9_.-]{1,64}$")

log = logging.getLogger("swarmpath.dashboard")

RATE_WINDOW = 30.0  # seconds of accepted results behind a job's runs/s
SNAPSHOT_SECONDS = 0.5  # the jobs list is recomputed at most this often
VIEW_SECONDS = 1.0  # a running job's page data is recomputed at most this often
SNAPSHOT_JOBS = 200  # jobs in the live list (newest first)


class Dashboard:
    def __init__(self, store: Any, cache_dir: Path | None = None, max_jobs: int = 8,
                 max_scenes: int = 64):
        self.store = store
        self.cache_dir = cache_dir  # finished jobs' aggregates (JobAggregates.save)
        self.max_jobs = max_jobs
        self.max_scenes = max_scenes
        self._lock = threading.Lock()
        self._jobs: OrderedDict[str, JobAggregates] = OrderedDict()
        self._ready: dict[str, threading.Event] = {}
        self._rates: dict[str, deque[tuple[float, int]]] = {}
        self._scenes: OrderedDict[tuple[Any, ...], dict[str, Any]] = OrderedDict()
        self._encoded: OrderedDict[str, tuple[int, bytes]] = OrderedDict()
        self._ended: set[str] = set()  # jobs seen ending (evicted first)
        self._snapshot: tuple[float, bytes] = (-1.0, b"")
        self._closing = threading.Event()  # close(): builds stop reading the store
        self._threads: set[threading.Thread] = set()  # builds and warm-ups running

    # ------------------------------------------------------------------------------- feeding
    def observe(self, job_id: str, results: Iterable[Any], now: float | None = None) -> None:
        """Results just accepted for ``job_id`` (``RunResult`` objects): update the job's
        aggregates (created on its first results) and its rate."""
        self.observe_runs(job_id, [(r.cell, r.run, r.status == "ok", r.metrics, r.curve, r.path,
                                    (getattr(r, "seconds", None), getattr(r, "cpu_seconds", None)))
                                   for r in results], now)

    def observe_runs(self, job_id: str,
                     runs: Sequence[tuple[str, int, bool, Any, Any, Any, Any]],
                     now: float | None = None) -> None:
        """:meth:`observe` of runs given as (cell, run, ok, metrics, curve, path, times), times
        the run's (wall, CPU) seconds or None."""
        now = time.time() if now is None else now
        with self._lock:
            rate = self._rates.setdefault(job_id, deque())
            rate.append((now, len(runs)))
            while rate and rate[0][0] < now - RATE_WINDOW:
                rate.popleft()
            if len(self._rates) > 4 * self.max_jobs:  # forget the rates of the oldest jobs
                for old in list(self._rates)[: len(self._rates) - 4 * self.max_jobs]:
                    del self._rates[old]
        # never wait here: this is the store's result thread, and a job built from the store
        # takes seconds
        job = self.aggregates(job_id, wait=False, adding=len(runs))
        if job is None:
            return
        entries = []
        index_of = job.cell_index
        for cell, run, ok, metrics, curve, path, times in runs:
            index = index_of(cell)
            if index is not None:
                entries.append((index, run, ok, metrics, curve, path, times))
        job.add_many(entries)

    def aggregates(self, job_id: str, wait: bool = True,
                   adding: int = 0) -> JobAggregates | None:
        """The job's aggregates (None: unknown job), built from the store (or its saved
        arrays) the first time. With ``wait`` False a build runs in a background thread and the
        aggregates are returned at once, possibly incomplete (adding to them is safe meanwhile:
        runs are deduplicated). ``adding``: how many finished runs the caller adds right after
        (:meth:`observe_runs`, just stored); when they are all the store holds of a running job,
        nothing is read back (a job's first results are not read from the store again)."""
        with self._lock:
            job = self._jobs.get(job_id)
            if job is not None:
                self._jobs.move_to_end(job_id)
            ready = self._ready.get(job_id)
        if job is None:
            status = self.store.job_status(job_id)
            spec = self.store.job_spec(job_id)
            cells = self.store.cells(job_id)
            if status is None or spec is None or cells is None:
                return None
            with self._lock:
                job = self._jobs.get(job_id)
                if job is None:
                    job = _job_aggregates(job_id, status.kind, cells, spec)
                    self._jobs[job_id] = job
                    if adding and status.state not in FINAL_STATES \
                            and status.runs_done + status.runs_failed == adding:
                        self._evict()
                        return job
                    ready = self._ready[job_id] = threading.Event()
                    self._evict()
                    args = (job, status, spec, cells)
                    if not wait:
                        thread = threading.Thread(target=self._build, args=args,
                                                  daemon=True, name=f"dashboard-{job_id}")
                        self._threads.add(thread)  # we hold the lock
                        thread.start()
                        return job
                else:
                    args = None
                    ready = self._ready.get(job_id)
            if args is not None:
                return self._build(*args)
        if ready is not None and wait:
            ready.wait()
        return job

    def _evict(self) -> None:
        """Drop least recently used jobs beyond max_jobs, finished ones first (caller locks)."""
        while len(self._jobs) > self.max_jobs:
            idle = [j for j in self._jobs if j not in self._ready]
            ended = [j for j in idle if j in self._ended]
            if not idle:
                return
            victim = (ended or idle)[0]
            del self._jobs[victim]

    def _build(self, job: JobAggregates, status: Any, spec: Any,
               cells: list[dict[str, Any]]) -> JobAggregates:
        job_id = job.job_id
        started = time.perf_counter()
        how = "nothing"
        job.set_loading(True)
        try:
            finished = status.runs_done + status.runs_failed
            saved = self._saved(job_id)
            if (status.state in FINAL_STATES and saved is not None and job.load(saved)
                    and job.finished_runs() == finished):
                how = "its saved aggregates"
            else:
                if job.finished_runs():  # a stale file: start again from the store
                    job.set_loading(False)
                    job = _job_aggregates(job_id, status.kind, cells, spec)
                    job.set_loading(True)
                    with self._lock:
                        self._jobs[job_id] = job
                n = 0
                for rec in self.store.iter_run_records(job_id):
                    if self._closing.is_set():
                        break
                    n += job.add_record(rec)
                how = f"{n} stored runs"
                if status.state in FINAL_STATES and saved is not None \
                        and not self._closing.is_set():
                    job.set_loading(False)  # the saved page is the complete one
                    self._save(job, saved)
        except Exception:
            if self._closing.is_set():  # the store closed under us: shutting down
                log.info("dashboard: building job %s's aggregates stopped (closing)", job_id)
            else:
                log.exception("building the dashboard's aggregates of job %s failed", job_id)
        finally:
            job.set_loading(False)
            with self._lock:
                self._ready.pop(job_id).set()
                self._threads.discard(threading.current_thread())
        log.info("dashboard: job %s aggregated from %s in %.2f s", job_id, how,
                 time.perf_counter() - started)
        return job

    def longest_path(self, job_id: str, cell_index: int) -> float:
        """Seconds of the longest path kept for a map cell (0 when none)."""
        job = self.aggregates(job_id)
        return job.longest_path(cell_index) if job is not None else 0.0

    def aggregates_loaded(self) -> list[str]:
        """The jobs whose aggregates are in memory (least recently used first)."""
        with self._lock:
            return list(self._jobs)

    def _saved(self, job_id: str) -> Path | None:
        if self.cache_dir is None or not _SAFE_ID.match(job_id):
            return None
        return self.cache_dir / f"{job_id}.npz"

    def finished(self, job_id: str) -> None:
        """The job ended: save its aggregates when they are in memory (a job that is not is
        saved when its page first rebuilds them)."""
        path = self._saved(job_id)
        with self._lock:
            self._ended.add(job_id)
            if len(self._ended) > 64 * self.max_jobs:
                self._ended.intersection_update(self._jobs)
            job = self._jobs.get(job_id) if job_id not in self._ready else None
        if path is not None and job is not None:
            self._save(job, path)

    @staticmethod
    def _save(job: JobAggregates, path: Path) -> None:
        """The arrays (.npz) and the page (.json) of a finished job."""
        try:
            job.save(path)
            page = path.with_suffix(".json")
            tmp = page.with_suffix(".tmp")
            tmp.write_bytes(_encode(job.view()))
            tmp.replace(page)
        except OSError:
            log.exception("saving the dashboard's aggregates of job %s failed", job.job_id)

    def warm(self, job_ids: Iterable[str]) -> threading.Thread:
        """In a daemon thread: import the statistics (scipy) and build the aggregates of
        ``job_ids`` (the unfinished jobs after a restart), so the first pages are quick."""
        ids = list(job_ids)[-self.max_jobs:]

        def run() -> None:
            try:
                import swarmpath.evidence.compare  # noqa: F401
                for job_id in ids:
                    if self._closing.is_set():
                        break
                    self.aggregates(job_id)
            except Exception:
                if not self._closing.is_set():
                    log.exception("warming the dashboard up failed")
            finally:
                with self._lock:
                    self._threads.discard(threading.current_thread())

        thread = threading.Thread(target=run, name="dashboard-warm", daemon=True)
        self._start(thread)
        return thread

    def _start(self, thread: threading.Thread) -> None:
        with self._lock:
            self._threads.add(thread)
        thread.start()

    def close(self, timeout: float = 10.0) -> None:
        """Stop the builds (they stop at their next stored run) and wait for them, at most
        ``timeout`` seconds in all: call it before closing the store."""
        self._closing.set()
        deadline = time.monotonic() + timeout
        with self._lock:
            threads = list(self._threads)
        for thread in threads:
            thread.join(max(0.0, deadline - time.monotonic()))

    def page_data(self, job_id: str) -> tuple[int, bytes] | None:
        """(version, JSON bytes) of the job page's data: the aggregates' view, recomputed at
        most once per VIEW_SECONDS while results arrive and encoded once per version, whatever
        the number of clients; a finished job that is not in memory is served from its saved
        page (no arrays loaded). None for an unknown job."""
        with self._lock:
            loaded = job_id in self._jobs
        if not loaded:
            saved = self._saved_page(job_id)
            if saved is not None:
                return saved
        job = self.aggregates(job_id, wait=False)  # a page never waits for a build: it shows
        if job is None:  # what is there ("loading") and asks again
            return None
        view = job.view(max_age=VIEW_SECONDS)
        version = int(view["version"])
        with self._lock:
            hit = self._encoded.get(job_id)
        if hit is not None and hit[0] == version:
            return hit
        return self._remember(job_id, version, _encode(view))

    def _remember(self, job_id: str, version: int, body: bytes) -> tuple[int, bytes]:
        with self._lock:
            self._encoded[job_id] = (version, body)
            self._encoded.move_to_end(job_id)
            while len(self._encoded) > self.max_jobs:
                self._encoded.popitem(last=False)
        return version, body

    def _saved_page(self, job_id: str) -> tuple[int, bytes] | None:
        """A finished job's saved page, if it holds every finished run of the job."""
        path = self._saved(job_id)
        status = self.store.job_status(job_id)
        if path is None or status is None or status.state not in FINAL_STATES:
            return None
        finished = status.runs_done + status.runs_failed
        with self._lock:
            hit = self._encoded.get(job_id)
        if hit is not None and json.loads(hit[1]).get("finished") == finished:
            return hit
        try:
            body = path.with_suffix(".json").read_bytes()
            page = json.loads(body)
            version, complete = int(page["version"]), int(page["finished"]) == finished
        except (OSError, ValueError, KeyError, TypeError):
            return None
        if not complete or page.get("loading") or page.get("format") != SAVE_FORMAT:
            return None  # stale, partial or of an earlier layout: rebuild
        return self._remember(job_id, version, body)

    # --------------------------------------------------------------------------------- rates
    def rate(self, job_id: str, now: float | None = None) -> float:
        """Results accepted per second for the job over the last RATE_WINDOW seconds."""
        now = time.time() if now is None else now
        with self._lock:
            events = list(self._rates.get(job_id, ()))
        recent = [(t, n) for t, n in events if t >= now - RATE_WINDOW]
        if not recent:
            return 0.0
        span = max(now - recent[0][0], 1.0)
        return sum(n for _, n in recent) / span

    def jobs_snapshot(self, now: float | None = None) -> bytes:
        """The jobs list as JSON bytes (newest first), each job with ``progress`` (0..1),
        ``rate`` (runs/s) and ``eta`` (seconds, None when unknown); shared by every client for
        SNAPSHOT_SECONDS."""
        now = time.time() if now is None else now
        with self._lock:
            at, data = self._snapshot
        if data and now - at < SNAPSHOT_SECONDS:
            return data
        jobs = []
        for status in self.store.list_jobs(None, SNAPSHOT_JOBS, 0):
            item = status.model_dump()
            finished = status.runs_done + status.runs_failed
            item["progress"] = finished / status.runs_total if status.runs_total else 1.0
            rate = self.rate(status.id, now) if status.state == "running" else 0.0
            item["rate"] = round(rate, 3)
            left = status.runs_total - finished
            item["eta"] = round(left / rate, 1) if rate > 0 and left > 0 else None
            jobs.append(item)
        data = json.dumps({"time": now, "jobs": jobs}, separators=(",", ":")).encode()
        with self._lock:
            self._snapshot = (now, data)
        return data

    # -------------------------------------------------------------------------------- scenes
    def scene(self, job_id: str, cell_index: int, run: int | None, t_end: float,
              seed: int, path: Any = None) -> dict[str, Any] | None:
        """The map of a map cell with run ``run``'s (default 0) moving obstacles and goal up to
        ``t_end``, and where ``path`` (that run's) touched an obstacle; cached. None when the
        job or cell is unknown or not a map cell."""
        from swarmpath.service.web.scene import (
            collision_points,
            load_cell_scenario,
            motion,
            scene,
        )

        key = (job_id, cell_index, run, round(t_end, 3))
        with self._lock:
            hit = self._scenes.get(key)
            if hit is not None:
                self._scenes.move_to_end(key)
                return hit
        cells = self.store.cells(job_id)
        if cells is None or not 0 <= cell_index < len(cells):
            return None
        spec = cells[cell_index]["spec"]
        if spec.get("kind") != "map":
            return None
        scenario = load_cell_scenario(spec)
        out = scene(scenario)
        out["run"] = run
        out["motion"] = motion(scenario, seed, run if run is not None else 0, t_end)
        out["collisions"] = (collision_points(scenario, seed, run or 0, path)
                             if path is not None else [])
        with self._lock:
            self._scenes[key] = out
            while len(self._scenes) > self.max_scenes:
                self._scenes.popitem(last=False)
        return out


def _encode(view: Mapping[str, Any]) -> bytes:
    return json.dumps(json_safe(dict(view)), separators=(",", ":")).encode()


def _job_aggregates(job_id: str, kind: str, cells: list[dict[str, Any]], spec: Any
                    ) -> JobAggregates:
    """A job's empty aggregates. A raced job's cells hold as many runs as the job's ``runs``
    (its ``max_runs``), not their allowance so far: the race gives them more as it goes."""
    racing = getattr(spec, "racing", None) is not None
    if racing:
        cells = [{**c, "runs": spec.runs} for c in cells]
    return JobAggregates(job_id, kind, cells, spec.seed, getattr(spec, "reference", None),
                         racing=racing, buckets=getattr(spec, "buckets", None))
