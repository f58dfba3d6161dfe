"""What the dashboard draws, maintained as results arrive (never recomputed from every run).

Plain functions over numpy arrays (:func:`curve_grid`, :func:`sample_curve`, :func:`band`,
:func:`box_stats`, :func:`thin_path`) and one accumulator per job, :class:`JobAggregates`:
``add()`` takes one finished run (from an accepted result or a stored record) and updates its
cell in O(size of that run); ``view()`` returns the page's JSON. A cell's statistics are
recomputed only when the cell got new runs since the last view (from the cell's in-memory
arrays, not from the store), so a page of a finished 78,000-run job costs a dict lookup.

Benchmark cells keep each run's best-so-far error ``f - f*`` sampled at :data:`GRID_POINTS`
log-spaced iterations (float32; 78,000 runs x 64 points = 20 MB) and its best fitness. Map cells
keep each run's path thinned to :data:`PATH_POINTS` points, why it failed and where it collided
(recomputed once from the full path in that run's world), and its length, gap and planning time.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from swarmpath.evidence.buckets import BucketCell, bucket_curve
from swarmpath.evidence.legend import legend
from swarmpath.service.web.cells import Times, _BenchmarkCell, _f_star, _MapCell
from swarmpath.service.web.series import (
    GRID_POINTS,
    MAX_OUTLIERS,
    PATH_POINTS,
    band,
    box_stats,
    curve_grid,
    failure_kind,
    sample_curve,
    thin_path,
)
from swarmpath.service.web.statistics import benchmark_statistics, map_statistics

__all__ = [
    "GRID_POINTS",
    "MAX_OUTLIERS",
    "PATH_POINTS",
    "JobAggregates",
    "band",
    "box_stats",
    "curve_grid",
    "failure_kind",
    "sample_curve",
    "thin_path",
]

SAVE_FORMAT = "swarmpath-dashboard-2"  # 2: benchmark cells keep wall and CPU seconds
#: Columns of the job page whose meaning is shown under it (swarmpath.evidence.legend).
BENCHMARK_LEGEND = ("failed", "rank", "marker")
MAP_LEGEND = ("failed", "success_rate", "success_marker", "collisions", "length_mean",
              "length_marker", "gap_mean", "seconds_mean", "seconds_marker", "cpu_seconds_mean")


class JobAggregates:
    """The dashboard's state of one job (see the module docstring). Thread-safe."""

    def __init__(self, job_id: str, kind: str, cells: Sequence[Mapping[str, Any]],
                 seed: int = 0, reference: str | None = None, racing: bool = False,
                 buckets: Mapping[str, int] | None = None):
        self.job_id = job_id
        self.buckets = dict(buckets or {})  # map name -> MovingAI bucket (the spec's)
        self.reference = reference  # the statistics' reference (None: the last one listed)
        self.racing = racing  # a raced job: the page shows its race (GET /jobs/{id}/race)
        self.kind = kind
        self.version = 0  # bumped by every add(): a client's cached copy is current if equal
        self.loading = False  # being read from the store: the view is still incomplete
        self.finished = 0  # runs added (each run once)
        self._lock = threading.Lock()
        self._keys = {c["key"]: int(c["index"]) for c in cells}
        self.runs_per_cell = max((int(c["runs"]) for c in cells), default=0)
        self._cells: list[_BenchmarkCell | _MapCell] = []
        for c in sorted(cells, key=lambda c: int(c["index"])):
            spec = c["spec"]
            if kind == "benchmark":
                f_star = _f_star(spec["function"], int(spec["dim"]))
                self._cells.append(_BenchmarkCell(spec, int(c["runs"]), f_star))
            else:
                self._cells.append(_MapCell(spec, int(c["runs"]), seed))
        self._view: dict[str, Any] | None = None
        self._view_at = 0.0  # time.monotonic() of the last view

    def cell_index(self, key: str) -> int | None:
        return self._keys.get(key)

    def add(
        self,
        cell_index: int,
        run: int,
        *,
        ok: bool,
        metrics: Mapping[str, Any],
        curve: Any = None,
        path: Any = None,
        times: Times = None,
    ) -> bool:
        """One finished run; False (ignored) when it was added before or is out of range.
        ``times``: its (wall, CPU) seconds, either None when not known (a benchmark cell shows
        their medians; a map cell the planner's, from ``metrics``)."""
        with self._lock:
            if not 0 <= cell_index < len(self._cells):
                return False
            cell = self._cells[cell_index]
            if not 0 <= run < cell.seen.size or cell.seen[run]:
                return False
            if isinstance(cell, _BenchmarkCell):
                cell.add(run, ok, metrics, curve, times)
            else:
                cell.add(run, ok, metrics, path)
            self.version += 1
            self.finished += 1
            return True

    def add_many(self, entries: Iterable[tuple[int, int, bool, Mapping[str, Any], Any, Any,
                                               Times]]) -> int:
        """Finished runs (cell index, run, ok, metrics, curve, path, times) at once, as
        :meth:`add` each (repeats and runs out of range ignored); a benchmark cell samples its
        runs' curves together. Returns how many were added."""
        with self._lock:
            by_cell: dict[int, dict[int, tuple[bool, Mapping[str, Any], Any, Any, Times]]] = {}
            for index, run, ok, metrics, curve, path, times in entries:
                if not 0 <= index < len(self._cells):
                    continue
                cell = self._cells[index]
                if 0 <= run < cell.seen.size and not cell.seen[run]:
                    by_cell.setdefault(index, {}).setdefault(
                        run, (ok, metrics, curve, path, times))
            added = 0
            for index, runs in by_cell.items():
                cell = self._cells[index]
                if isinstance(cell, _BenchmarkCell):
                    cell.add_many([(run, ok, m, curve, t) for run, (ok, m, curve, _p, t) in
                                   runs.items()])
                else:
                    for run, (ok, m, _c, path, _t) in runs.items():
                        cell.add(run, ok, m, path)
                added += len(runs)
            self.version += added  # as many versions as runs, like one add per run
            self.finished += added
            return added

    def add_record(self, record: Mapping[str, Any]) -> bool:
        """A store/recorder record (``Store.iter_run_records``)."""
        return self.add(
            int(record["cell_index"]), int(record["run"]), ok=record["status"] == "ok",
            metrics=record.get("metrics") or {}, curve=record.get("curve"),
            path=record.get("path"), times=(record.get("seconds"), record.get("cpu_seconds")),
        )

    def set_loading(self, loading: bool) -> None:
        """Mark the aggregates as being (re)built from the store, or done; a new version."""
        with self._lock:
            self.loading = loading
            self.version += 1

    def longest_path(self, cell_index: int) -> float:
        """Seconds of the longest kept path of a map cell (0 when none, or not a map cell)."""
        with self._lock:
            if not 0 <= cell_index < len(self._cells):
                return 0.0
            cell = self._cells[cell_index]
            if not isinstance(cell, _MapCell):
                return 0.0
            return max((p["path"][-1][2] for p in cell.paths.values() if p["path"]),
                       default=0.0)

    def finished_runs(self) -> int:
        with self._lock:
            return int(sum(int(c.seen.sum()) for c in self._cells))

    def save(self, path: Path) -> None:
        """Write the aggregates to ``path`` (.npz, no pickles): a finished job's page loads from
        it after a restart instead of re-reading every run from the store."""
        arrays: dict[str, Any] = {"format": np.array(SAVE_FORMAT), "kind": np.array(self.kind)}
        with self._lock:
            for i, cell in enumerate(self._cells):
                for name, value in cell.state().items():
                    arrays[f"{i}.{name}"] = value
            arrays["version"] = np.array(self.version)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp.npz")
        np.savez(tmp, **arrays)
        tmp.replace(path)

    def load(self, path: Path) -> bool:
        """Restore what :meth:`save` wrote (False, and nothing changed, when the file is missing,
        of another format or does not fit this job's cells)."""
        try:
            with np.load(path, allow_pickle=False) as f:
                if str(f["format"]) != SAVE_FORMAT or str(f["kind"]) != self.kind:
                    return False
                states = [{k.split(".", 1)[1]: f[k] for k in f.files if k.startswith(f"{i}.")}
                          for i in range(len(self._cells))]
                version = int(f["version"])
        except (OSError, KeyError, ValueError):
            return False
        with self._lock:
            backup = [c.state() for c in self._cells]
            try:
                for cell, state in zip(self._cells, states, strict=True):
                    cell.restore(state)
            except (KeyError, ValueError, TypeError):
                for cell, state in zip(self._cells, backup, strict=True):
                    cell.restore(state)
                return False
            self.version = version
            self.finished = int(sum(int(c.seen.sum()) for c in self._cells))
            self._view = None
        return True

    def view(self, max_age: float = 0.0) -> dict[str, Any]:
        """The job page's data: ``benchmark`` groups (one per function x dim) or ``map`` groups
        (one per map), each with one entry per algorithm/planner. Recomputed (the changed cells
        only) when runs were added since, unless the last view is younger than ``max_age``
        seconds: many clients of a running job then share one view per ``max_age``."""
        with self._lock:
            view = self._view
            now = time.monotonic()
            if view is None or (view["version"] != self.version
                                and now - self._view_at >= max_age):
                view = (self._benchmark_view() if self.kind == "benchmark"
                        else self._map_view())
                self._view, self._view_at = view, now
            return view

    def _benchmark_view(self) -> dict[str, Any]:
        groups: dict[tuple[str, int], dict[str, Any]] = {}
        algorithms: list[str] = []
        for index, cell in enumerate(self._cells):
            assert isinstance(cell, _BenchmarkCell)
            s = cell.spec
            if s["algorithm"] not in algorithms:
                algorithms.append(s["algorithm"])
            g = groups.setdefault((s["function"], int(s["dim"])), {
                "function": s["function"], "dim": int(s["dim"]),
                "iterations": cell.grid.tolist(), "algorithms": {},
            })
            g["algorithms"][s["algorithm"]] = {**cell.view(), "cell": index}
        samples: dict[tuple[str, int], dict[str, np.ndarray]] = {}
        from swarmpath.evidence.anytime import grid_ecdf

        rows_of: dict[tuple[str, int], dict[str, np.ndarray]] = {}
        for cell in self._cells:
            assert isinstance(cell, _BenchmarkCell)
            key = (cell.spec["function"], int(cell.spec["dim"]))
            rows_of.setdefault(key, {})[cell.spec["algorithm"]] = cell.rows[cell.ok]
        for key, g in groups.items():  # the runtime ECDF over iterations (anytime view)
            g["ecdf"] = grid_ecdf(np.asarray(g["iterations"]), rows_of.get(key, {}))
        for g in groups.values():
            means = {a: v["describe"]["avg"] for a, v in g["algorithms"].items()
                     if v["describe"] is not None and not math.isnan(v["describe"]["avg"])}
            low = min(means.values(), default=None)
            g["best"] = sorted(a for a, m in means.items() if m == low)
            g["means"] = means
        for cell in self._cells:
            assert isinstance(cell, _BenchmarkCell)
            s = cell.spec
            samples.setdefault((s["function"], int(s["dim"])), {})[s["algorithm"]] = (
                cell.best[cell.ok])
        return {"job_id": self.job_id, "kind": "benchmark", "version": self.version,
                "format": SAVE_FORMAT,
                "loading": self.loading, "finished": self.finished,
                "runs_per_cell": self.runs_per_cell, "legend": legend(BENCHMARK_LEGEND),
                "racing": self.racing, "algorithms": algorithms, "groups": list(groups.values()),
                "statistics": benchmark_statistics(samples, groups, algorithms,
                                                   self.reference)}

    def _map_view(self) -> dict[str, Any]:
        groups: dict[str, dict[str, Any]] = {}
        samples: dict[str, dict[str, dict[str, list[float]]]] = {"length": {}, "gap": {},
                                                                  "seconds": {}}
        planners: list[str] = []
        bucketed: list[BucketCell] = []
        for index, cell in enumerate(self._cells):
            s = cell.spec
            if s["planner"] not in planners:
                planners.append(s["planner"])
            g = groups.setdefault(s["map"], {"map": s["map"], "cell": index, "planners": {},
                                             "bucket": self.buckets.get(s["map"])})
            g["planners"][s["planner"]] = {**cell.view(), "cell": index}
            for metric in ("length", "gap", "seconds"):
                samples[metric].setdefault(s["map"], {})[s["planner"]] = cell.values[metric]
            if s["map"] in self.buckets:  # the runs the summary counts: every one that ended
                assert isinstance(cell, _MapCell)
                bucketed.append(BucketCell(
                    s["planner"], s["map"], self.buckets[s["map"]],
                    cell.finished - cell.crashed, cell.succeeded, list(cell.values["gap"])))
        return {"job_id": self.job_id, "kind": "map", "version": self.version,
                "format": SAVE_FORMAT,
                "loading": self.loading, "finished": self.finished,
                "runs_per_cell": self.runs_per_cell, "legend": legend(MAP_LEGEND),
                "planners": planners, "groups": list(groups.values()),
                # success and gap per planner and MovingAI bucket (the difficulty curve)
                "buckets": bucket_curve(bucketed),
                "statistics": map_statistics(groups, planners, self.reference, samples)}

