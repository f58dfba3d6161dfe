"""One dashboard cell's accumulated runs (benchmark: sampled curves and best fitness; map: thinned
paths, failures, collisions, length, gap and time), kept by
:class:`swarmpath.service.web.aggregates.JobAggregates`."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from swarmpath.path_metrics import PATH_METRICS
from swarmpath.service.cell_notes import OPTIMUM_REASON, WARNING_PREFIX, cell_notes
from swarmpath.service.web.series import (
    _number,
    band,
    box_stats,
    curve_grid,
    failure_kind,
    sample_curve,
    thin_path,
)

MAX_PATHS = 200  # paths kept per map cell (the first ones by run index arrive first)
#: A run's (wall seconds, CPU seconds), either None when not known; or None for neither.
Times = tuple[Any, Any] | None


def _median(values: np.ndarray) -> float | None:
    known = values[np.isfinite(values)]
    return float(np.median(known)) if known.size else None


class _BenchmarkCell:
    def __init__(self, spec: Mapping[str, Any], runs: int, f_star: float):
        self.spec = spec
        self.grid = curve_grid(int(spec["iterations"]))
        self.f_star = f_star
        self.rows = np.full((runs, self.grid.size), np.nan, dtype=np.float32)
        self.best = np.full(runs, np.nan)
        self.ok = np.zeros(runs, dtype=bool)
        self.seen = np.zeros(runs, dtype=bool)
        #: each run's wall and CPU seconds (NaN: not known, e.g. stored before CPU was measured)
        self.times = np.full((runs, 2), np.nan)
        self.failed = 0
        self.cache: dict[str, Any] | None = None

    def add(self, run: int, ok: bool, metrics: Mapping[str, Any], curve: Any,
            times: Times = None) -> None:
        self.seen[run] = True
        self.cache = None
        self._time(run, times)
        if not ok:
            self.failed += 1
            return
        self.ok[run] = True
        best = _number(metrics.get("best_fitness"))
        self.best[run] = math.inf if best is None else best
        if curve is not None and len(curve):
            stride = int(_number(metrics.get("curve_stride")) or 1)
            err = sample_curve(curve, self.grid, stride) - self.f_star
            self.rows[run] = np.maximum(err, 0.0)

    def _time(self, run: int, times: Times) -> None:
        if times is not None:
            for k, v in enumerate(times):
                number = _number(v)
                if number is not None:
                    self.times[run, k] = number

    def add_many(self, items: Sequence[tuple[int, bool, Mapping[str, Any], Any, Times]]
                 ) -> None:
        """Several new runs (run, ok, metrics, curve, (wall, CPU seconds) or None) at once: the
        whole curves (one value per iteration) are sampled in one numpy operation, the others
        one by one (:meth:`add`)."""
        length = int(self.grid[-1])
        runs: list[int] = []
        curves: list[Any] = []
        bests: list[float] = []
        for run, ok, metrics, curve, times in items:
            if ok and curve is not None and len(curve) == length \
                    and "curve_stride" not in metrics:
                best = _number(metrics.get("best_fitness"))
                bests.append(math.inf if best is None else best)
                runs.append(run)
                curves.append(curve)
                self._time(run, times)
            else:
                self.add(run, ok, metrics, curve, times)
        if runs:  # (the runs are distinct: JobAggregates.add_many keeps one entry per run)
            self.seen[runs] = self.ok[runs] = True
            self.best[runs] = bests
            self.cache = None
            err = np.asarray(curves, dtype=np.float64)[:, self.grid - 1] - self.f_star
            self.rows[runs] = np.maximum(err, 0.0)

    def view(self) -> dict[str, Any]:
        if self.cache is None:
            from swarmpath.evidence.stats import describe

            rows = self.rows[self.ok]
            best = self.best[self.ok]
            valid = np.where(self.ok, self.best, np.inf)
            wall, cpu = (self.times[self.ok, k] for k in (0, 1))
            self.cache = {
                "runs": int(self.ok.sum()), "failed": self.failed,
                # medians over the finished runs that have them (None: none has)
                "seconds": _median(wall), "cpu_seconds": _median(cpu),
                "best_run": int(np.argmin(valid)) if best.size else None,
                "band": band(rows), "box": box_stats(best),
                "describe": describe(best) if best.size else None,
            }
        return self.cache


    def state(self) -> dict[str, Any]:
        return {"rows": self.rows, "best": self.best, "ok": self.ok, "seen": self.seen,
                "times": self.times, "failed": np.array(self.failed)}

    def restore(self, state: Mapping[str, Any]) -> None:
        for name in ("rows", "best", "ok", "seen", "times"):
            value = np.asarray(state[name])
            if value.shape != getattr(self, name).shape:
                raise ValueError(f"saved {name} has shape {value.shape}")
            setattr(self, name, value.astype(getattr(self, name).dtype))
        self.failed = int(state["failed"])
        self.cache = None


#: Values a map cell keeps per run for its box statistics: of the successful runs, the length,
#: the gap and the field's path metrics (:data:`swarmpath.path_metrics.PATH_METRICS`); of
#: every run, the planning wall and CPU time and the least clearance (the job page shows its
#: smallest, as the summary and ``swarmpath plan`` do).
SUCCESS_VALUES = ("length", "gap", "travel_time", *PATH_METRICS)
RUN_VALUES = ("seconds", "cpu_seconds", "min_clearance")
MAP_VALUES = (*SUCCESS_VALUES, *RUN_VALUES)


class _MapCell:
    def __init__(self, spec: Mapping[str, Any], runs: int, seed: int):
        self.spec = spec
        self.seed = seed
        self.scenario: Any = None
        self.seen = np.zeros(runs, dtype=bool)
        self.paths: dict[int, dict[str, Any]] = {}
        self.values: dict[str, list[float]] = {k: [] for k in MAP_VALUES}
        self.finished = 0
        self.succeeded = 0
        self.crashed = 0
        self.collisions = 0  # colliding steps summed over the runs
        self.failures: dict[str, int] = {}
        self.optimum_reason: str | None = None  # why no exact optimum (cell_notes, checked)
        self.warnings: list[list[str]] = []  # [field in the scenario, message] (cell_notes)
        self.cache: dict[str, Any] | None = None

    def add(self, run: int, ok: bool, metrics: Mapping[str, Any], path: Any) -> None:
        self.seen[run] = True
        self.cache = None
        self.finished += 1
        if not ok:
            self.crashed += 1
            return
        if self.optimum_reason is None and OPTIMUM_REASON in metrics:
            self.optimum_reason = cell_notes([metrics], None, "").optimum_reason
        if not self.warnings and any(k.startswith(WARNING_PREFIX) for k in metrics):
            self.warnings = _warnings(metrics)
        success = metrics.get("success") is True
        kind = None if success else failure_kind(metrics)
        self.collisions += int(_number(metrics.get("collisions")) or 0)
        if success:
            self.succeeded += 1
            for name in SUCCESS_VALUES:
                v = _number(metrics.get(name))
                if v is not None:
                    self.values[name].append(v)
        else:
            self.failures[kind or "other"] = self.failures.get(kind or "other", 0) + 1
        for name in RUN_VALUES:
            value = _number(metrics.get(name))
            if value is not None:
                self.values[name].append(value)
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
        data["optimum_reason"] = self.optimum_reason
        data["warnings"] = self.warnings
        return {"json": np.array(json.dumps(data)), "seen": self.seen}

    def restore(self, state: Mapping[str, Any]) -> None:
        seen = np.asarray(state["seen"], dtype=bool)
        if seen.shape != self.seen.shape:
            raise ValueError(f"saved seen has shape {seen.shape}")
        data = json.loads(str(state["json"]))
        for name in self._FIELDS:
            setattr(self, name, data[name])
        for name in MAP_VALUES:  # saved before the value existed: none kept
            self.values.setdefault(name, [])
        self.paths = {int(p["run"]): p for p in data["paths"]}
        self.optimum_reason = cell_notes([data], None, "").optimum_reason  # older saves: none
        saved = data.get("warnings")
        self.warnings = _warnings({WARNING_PREFIX + str(f): m for f, m in saved
                                   } if isinstance(saved, list) and all(
                                       isinstance(w, list) and len(w) == 2 for w in saved)
                                  else {})
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
                "optimum_reason": self.optimum_reason,
                "warnings": self.warnings,
                "box": {k: box_stats(v) for k, v in self.values.items()},
                "paths": [self.paths[k] for k in sorted(self.paths)],
            }
        return self.cache


def _warnings(metrics: Mapping[str, Any]) -> list[list[str]]:
    """[field, message] of a run's valid ``warning:<field>`` notes (cell_notes' checks)."""
    prefix = len("maps[0].")
    return [[w.field[prefix:], w.message] for w in cell_notes([metrics], 0, "").warnings]


def _f_star(function: str, dim: int) -> float:
    try:
        from swarmpath.functions import get_function

        return float(get_function(function).f_min_for(dim))
    except Exception:  # an unknown (renamed) function: curves show f itself
        return 0.0

