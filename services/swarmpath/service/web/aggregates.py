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

import json
import math
import threading
import time
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from swarmpath.legend import legend
from swarmpath.service.web.statistics import benchmark_statistics, map_statistics

GRID_POINTS = 64  # iterations sampled per convergence curve
PATH_POINTS = 150  # points kept per map path
MAX_PATHS = 200  # paths kept per map cell (the first ones by run index arrive first)
MAX_OUTLIERS = 40  # outliers listed per box (the most extreme ones)
SAVE_FORMAT = "swarmpath-dashboard-1"
#: Columns of the job page whose meaning is shown under it (swarmpath.legend).
BENCHMARK_LEGEND = ("failed", "rank", "marker")
MAP_LEGEND = ("failed", "success_rate", "success_marker", "collisions", "length_mean",
              "length_marker", "gap_mean", "seconds_mean", "seconds_marker")


def curve_grid(iterations: int, points: int = GRID_POINTS) -> np.ndarray:
    """Iteration numbers 1..iterations, log-spaced, first and last included, unique, ascending."""
    if iterations < 1:
        raise ValueError("iterations must be >= 1")
    raw = np.geomspace(1.0, float(iterations), num=min(points, iterations))
    grid = np.unique(np.rint(raw).astype(np.int64))
    grid[0], grid[-1] = 1, iterations
    return np.unique(grid)


def sample_curve(curve: Sequence[float], grid: np.ndarray, stride: int = 1) -> np.ndarray:
    """The curve's values at the grid's iterations (``curve[i]`` = best after iteration i + 1).

    A thinned curve (``stride`` > 1: samples 0, s, 2s, ... plus the last one) is read at the
    latest sample at or before each iteration, which for a best-so-far curve is an upper bound.
    Iterations past the curve's end take its last value."""
    values = np.asarray(curve, dtype=np.float64)
    if values.size == 0:
        return np.full(grid.shape, np.nan)
    index = grid - 1  # 0-based iteration index
    if stride > 1:
        length = int(grid[-1])  # the unthinned curve has one value per iteration
        regular = (length - 1) // stride + 1
        at = np.arange(values.size, dtype=np.int64) * stride
        if values.size == regular + 1:  # the last value was appended after the regular ones
            at[-1] = length - 1
        pos = np.searchsorted(at, index, side="right") - 1
    else:
        pos = index
    return values[np.clip(pos, 0, values.size - 1)]


def band(rows: np.ndarray) -> dict[str, list[float]]:
    """Per column of ``rows`` (runs x points): the median and the interquartile range (25th and
    75th percentiles, linear interpolation). Columns of all-NaN give NaN."""
    if rows.shape[0] == 0:
        nan = [math.nan] * rows.shape[1]
        return {"median": nan, "q1": list(nan), "q3": list(nan)}
    x = rows.astype(np.float64)
    if np.isnan(x).any():  # nanquantile works column by column: only when needed
        with warnings.catch_warnings():  # an all-NaN column (no run sent a curve) gives NaN
            warnings.simplefilter("ignore", RuntimeWarning)
            q1, med, q3 = np.nanquantile(x, [0.25, 0.5, 0.75], axis=0)
    else:
        with np.errstate(invalid="ignore"):
            q1, med, q3 = np.quantile(x, [0.25, 0.5, 0.75], axis=0)
    return {"median": med.tolist(), "q1": q1.tolist(), "q3": q3.tolist()}


def box_stats(values: Sequence[float] | np.ndarray) -> dict[str, Any] | None:
    """Tukey box plot of the finite values: quartiles, whiskers at the most extreme values within
    1.5 IQR of the box, outliers beyond (at most MAX_OUTLIERS, the most extreme), mean, n.
    None without a finite value."""
    x = np.asarray(values, dtype=np.float64)
    x = np.sort(x[np.isfinite(x)])
    if x.size == 0:
        return None
    q1, med, q3 = (float(v) for v in np.quantile(x, [0.25, 0.5, 0.75]))
    iqr = q3 - q1
    inside = x[(x >= q1 - 1.5 * iqr) & (x <= q3 + 1.5 * iqr)]
    out = x[(x < q1 - 1.5 * iqr) | (x > q3 + 1.5 * iqr)]
    if out.size > MAX_OUTLIERS:
        order = np.argsort(-np.abs(out - med), kind="stable")[:MAX_OUTLIERS]
        out = np.sort(out[order])
    return {
        "n": int(x.size), "min": float(x[0]), "max": float(x[-1]), "mean": float(x.mean()),
        "q1": q1, "median": med, "q3": q3,
        "lo": float(inside[0]), "hi": float(inside[-1]), "outliers": out.tolist(),
    }


def thin_path(path: Sequence[Sequence[float]], points: int = PATH_POINTS) -> list[list[float]]:
    """At most ``points`` rows [x, y, t] of a path, evenly spaced, first and last kept, rounded
    to a millimetre (and a millisecond)."""
    p = np.asarray(path, dtype=np.float64).reshape(-1, 3) if len(path) else np.zeros((0, 3))
    if p.shape[0] > points:
        idx = np.unique(np.linspace(0, p.shape[0] - 1, points).round().astype(np.int64))
        p = p[idx]
    return np.round(p, 3).tolist()


def _number(v: Any) -> float | None:
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    return float(v) if math.isfinite(v) else None


def failure_kind(metrics: Mapping[str, Any]) -> str:
    """Why a map run failed, in one word: collision, stall (the planner gave up or stopped
    moving), timeout (time or step limit), or other."""
    reason = str(metrics.get("reason") or "")
    if (_number(metrics.get("collisions")) or 0) > 0 or reason.startswith("collided"):
        return "collision"
    if "gave up" in reason or "stall" in reason:
        return "stall"
    if "limit" in reason:
        return "timeout"
    return "other"


class _BenchmarkCell:
    def __init__(self, spec: Mapping[str, Any], runs: int, f_star: float):
        self.spec = spec
        self.grid = curve_grid(int(spec["iterations"]))
        self.f_star = f_star
        self.rows = np.full((runs, self.grid.size), np.nan, dtype=np.float32)
        self.best = np.full(runs, np.nan)
        self.ok = np.zeros(runs, dtype=bool)
        self.seen = np.zeros(runs, dtype=bool)
        self.failed = 0
        self.cache: dict[str, Any] | None = None

    def add(self, run: int, ok: bool, metrics: Mapping[str, Any], curve: Any) -> None:
        self.seen[run] = True
        self.cache = None
        if not ok:
            self.failed += 1
            return
        self.ok[run] = True
        best = _number(metrics.get("best_fitness"))
        self.best[run] = math.inf if best is None else best
        if curve:
            stride = int(_number(metrics.get("curve_stride")) or 1)
            err = sample_curve(curve, self.grid, stride) - self.f_star
            self.rows[run] = np.maximum(err, 0.0)

    def view(self) -> dict[str, Any]:
        if self.cache is None:
            from swarmpath.stats import describe

            rows = self.rows[self.ok]
            best = self.best[self.ok]
            valid = np.where(self.ok, self.best, np.inf)
            self.cache = {
                "runs": int(self.ok.sum()), "failed": self.failed,
                "best_run": int(np.argmin(valid)) if best.size else None,
                "band": band(rows), "box": box_stats(best),
                "describe": describe(best) if best.size else None,
            }
        return self.cache


    def state(self) -> dict[str, Any]:
        return {"rows": self.rows, "best": self.best, "ok": self.ok, "seen": self.seen,
                "failed": np.array(self.failed)}

    def restore(self, state: Mapping[str, Any]) -> None:
        for name in ("rows", "best", "ok", "seen"):
            value = np.asarray(state[name])
            if value.shape != getattr(self, name).shape:
                raise ValueError(f"saved {name} has shape {value.shape}")
            setattr(self, name, value.astype(getattr(self, name).dtype))
        self.failed = int(state["failed"])
        self.cache = None


class _MapCell:
    def __init__(self, spec: Mapping[str, Any], runs: int, seed: int):
        self.spec = spec
        self.seed = seed
        self.scenario: Any = None
        self.seen = np.zeros(runs, dtype=bool)
        self.paths: dict[int, dict[str, Any]] = {}
        self.values: dict[str, list[float]] = {"length": [], "gap": [], "seconds": []}
        self.finished = 0
        self.succeeded = 0
        self.crashed = 0
        self.collisions = 0  # colliding steps summed over the runs
        self.failures: dict[str, int] = {}
        self.cache: dict[str, Any] | None = None

    def add(self, run: int, ok: bool, metrics: Mapping[str, Any], path: Any) -> None:
        self.seen[run] = True
        self.cache = None
        self.finished += 1
        if not ok:
            self.crashed += 1
            return
        success = metrics.get("success") is True
        kind = None if success else failure_kind(metrics)
        self.collisions += int(_number(metrics.get("collisions")) or 0)
        if success:
            self.succeeded += 1
            for name in ("length", "gap"):
                v = _number(metrics.get(name))
                if v is not None:
                    self.values[name].append(v)
        else:
            self.failures[kind or "other"] = self.failures.get(kind or "other", 0) + 1
        seconds = _number(metrics.get("seconds"))
        if seconds is not None:
            self.values["seconds"].append(seconds)
        if path is not None and len(path) and len(self.paths) < MAX_PATHS:
            self.paths[run] = {
                "run": run, "success": success, "failure": kind,
                "reason": str(metrics.get("reason") or ""),
                "path": thin_path(path),
                "collisions": self._collisions(run, path) if kind == "collision" else [],
            }

    _FIELDS = ("paths", "values", "finished", "succeeded", "crashed", "collisions", "failures")

    def state(self) -> dict[str, Any]:
        data = {name: getattr(self, name) for name in self._FIELDS}
        data["paths"] = list(self.paths.values())
        return {"json": np.array(json.dumps(data)), "seen": self.seen}

    def restore(self, state: Mapping[str, Any]) -> None:
        seen = np.asarray(state["seen"], dtype=bool)
        if seen.shape != self.seen.shape:
            raise ValueError(f"saved seen has shape {seen.shape}")
        data = json.loads(str(state["json"]))
        for name in self._FIELDS:
            setattr(self, name, data[name])
        self.paths = {int(p["run"]): p for p in data["paths"]}
        self.seen = seen
        self.cache = None

    def _collisions(self, run: int, path: Any) -> list[list[float]]:
        from swarmpath.service.web.scene import collision_points, load_cell_scenario

        try:
            if self.scenario is None:
                self.scenario = load_cell_scenario(self.spec)
            return collision_points(self.scenario, self.seed, run, path)
        except Exception:  # a scenario that no longer loads: the path is still drawn
            return []

    def view(self) -> dict[str, Any]:
        if self.cache is None:
            self.cache = {
                "runs": self.finished, "crashed": self.crashed, "succeeded": self.succeeded,
                "collisions": self.collisions,
                "success_rate": self.succeeded / self.finished if self.finished else None,
                "failures": dict(self.failures),
                "box": {k: box_stats(v) for k, v in self.values.items()},
                "paths": [self.paths[k] for k in sorted(self.paths)],
            }
        return self.cache


def _f_star(function: str, dim: int) -> float:
    try:
        from swarmpath.functions import get_function

        return float(get_function(function).f_min_for(dim))
    except Exception:  # an unknown (renamed) function: curves show f itself
        return 0.0


class JobAggregates:
    """The dashboard's state of one job (see the module docstring). Thread-safe."""

    def __init__(self, job_id: str, kind: str, cells: Sequence[Mapping[str, Any]],
                 seed: int = 0, reference: str | None = None):
        self.job_id = job_id
        self.reference = reference  # the statistics' reference (None: the last one listed)
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
    ) -> bool:
        """One finished run; False (ignored) when it was added before or is out of range."""
        with self._lock:
            if not 0 <= cell_index < len(self._cells):
                return False
            cell = self._cells[cell_index]
            if not 0 <= run < cell.seen.size or cell.seen[run]:
                return False
            if isinstance(cell, _BenchmarkCell):
                cell.add(run, ok, metrics, curve)
            else:
                cell.add(run, ok, metrics, path)
            self.version += 1
            self.finished += 1
            return True

    def add_record(self, record: Mapping[str, Any]) -> bool:
        """A store/recorder record (``Store.iter_run_records``)."""
        return self.add(
            int(record["cell_index"]), int(record["run"]), ok=record["status"] == "ok",
            metrics=record.get("metrics") or {}, curve=record.get("curve"),
            path=record.get("path"),
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
                "loading": self.loading, "finished": self.finished,
                "runs_per_cell": self.runs_per_cell, "legend": legend(BENCHMARK_LEGEND),
                "algorithms": algorithms, "groups": list(groups.values()),
                "statistics": benchmark_statistics(samples, groups, algorithms,
                                                   self.reference)}

    def _map_view(self) -> dict[str, Any]:
        groups: dict[str, dict[str, Any]] = {}
        samples: dict[str, dict[str, dict[str, list[float]]]] = {"length": {}, "seconds": {}}
        planners: list[str] = []
        for index, cell in enumerate(self._cells):
            s = cell.spec
            if s["planner"] not in planners:
                planners.append(s["planner"])
            g = groups.setdefault(s["map"], {"map": s["map"], "cell": index, "planners": {}})
            g["planners"][s["planner"]] = {**cell.view(), "cell": index}
            for metric in ("length", "seconds"):
                samples[metric].setdefault(s["map"], {})[s["planner"]] = cell.values[metric]
        return {"job_id": self.job_id, "kind": "map", "version": self.version,
                "loading": self.loading, "finished": self.finished,
                "runs_per_cell": self.runs_per_cell, "legend": legend(MAP_LEGEND),
                "planners": planners, "groups": list(groups.values()),
                "statistics": map_statistics(groups, planners, self.reference, samples)}

