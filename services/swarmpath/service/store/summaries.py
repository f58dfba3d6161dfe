"""Summaries: the statistics tables of a job, and CSV."""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence
from typing import Any

from swarmpath.evidence.audit import origin_suspect
from swarmpath.evidence.buckets import bucket_rows
from swarmpath.evidence.race_report import RACE_COLUMNS, apply_race
from swarmpath.failure_classes import count_classes
from swarmpath.path_metrics import PATH_METRICS
from swarmpath.service.cell_notes import CellNotes, cell_notes, job_warnings
from swarmpath.service.store.base import StoreBase, _safe
from swarmpath.service.summary_stats import (
    BENCHMARK_TEST_COLUMNS,
    MAP_TEST_COLUMNS,
    benchmark_statistics,
    map_statistics,
)

BENCHMARK_COLUMNS = (
    "algorithm", "function", "dim", "runs", "failed", "min", "max", "avg", "std", "median", "iqr",
    "seconds_mean", "cpu_seconds_mean", "rank",
    "origin_suspect", *BENCHMARK_TEST_COLUMNS,
)
MAP_COLUMNS = (
    "planner", "map", "bucket", "runs", "failed", "success_rate", "collisions", "length_mean",
    "length_std",
    "error_mean", "seconds_mean", "cpu_seconds_mean", "gap_mean", "robot_driven_contacts",
    "obstacle_driven_contacts", "travel_time_mean", "min_clearance", *PATH_METRICS,
    *MAP_TEST_COLUMNS,
)


def _mean(xs: Sequence[float]) -> float | None:
    return sum(xs) / len(xs) if xs else None


def _numbers(runs: Sequence[dict[str, Any]], key: str) -> list[float]:
    out = []
    for m in runs:
        v = m.get(key)
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v):
            out.append(float(v))
    return out


def map_cell_summary(runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Statistics of one planner x map from its runs' metrics (``swarmpath plan --json`` fields).

    success_rate over all finished runs; length mean/std (ddof=1), gap mean, travel time and the
    path metrics (:data:`swarmpath.path_metrics.PATH_METRICS`) over the successful runs;
    error, seconds (wall), cpu_seconds and collisions over all runs, ``min_clearance`` the
    least over all runs (as ``swarmpath plan`` reports it), the collisions also by cause
    (``robot_driven_contacts``, ``obstacle_driven_contacts``: :func:`swarmpath.metrics.
    contact_causes`). Missing values are left out; None when no run has the value."""
    from swarmpath.evidence.stats import describe

    ok = [m for m in runs if m.get("success") is True]
    lengths = _numbers(ok, "length")
    stats = describe(lengths) if lengths else None
    collisions = _numbers(runs, "collisions")
    return {
        "runs": len(runs),
        "success_rate": len(ok) / len(runs) if runs else None,
        "collisions": int(sum(collisions)) if collisions else (0 if runs else None),
        "length_mean": stats["avg"] if stats else None,
        "length_std": stats["std"] if stats else None,
        "error_mean": _mean(_numbers(runs, "error")),
        "seconds_mean": _mean(_numbers(runs, "seconds")),
        "cpu_seconds_mean": _mean(_numbers(runs, "cpu_seconds")),
        "gap_mean": _mean(_numbers(ok, "gap")),
        "travel_time_mean": _mean(_numbers(ok, "travel_time")),
        "min_clearance": min(_numbers(runs, "min_clearance"), default=None),
        **{key: _mean(_numbers(ok, key)) for key in PATH_METRICS},
        **{key: _total(runs, key) for key in ("robot_driven_contacts", "obstacle_driven_contacts")},
        # why the failed runs failed (planners.failures), JSON only (a dict is no CSV cell)
        "failure_classes": count_classes(m.get("failure_class") for m in runs
                                         if m.get("success") is False),
    }


def _map_indexes(maps: Sequence[Any]) -> dict[str, int]:
    """Map name -> its index in the job spec's ``maps`` (presets by name, inline scenarios and
    resolved uploads by their ``name``)."""
    out: dict[str, int] = {}
    for i, entry in enumerate(maps):
        name = entry if isinstance(entry, str) else (entry or {}).get("name")
        if isinstance(name, str):
            out.setdefault(name, i)
    return out


def _total(runs: Sequence[dict[str, Any]], key: str) -> int | None:
    values = _numbers(runs, key)
    return int(sum(values)) if values else (0 if runs else None)


def summary_to_csv(summary: dict[str, Any]) -> str:
    """A summary's rows as CSV (header = its columns; empty cells for missing values)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    columns = summary["columns"]
    writer.writerow(columns)
    for row in summary["rows"]:
        writer.writerow(["" if row.get(c) is None else row.get(c) for c in columns])
    return buf.getvalue()


class SummariesMixin(StoreBase):
    """Summaries: the statistics tables of a job, and CSV."""

    def summary(self, job_id: str) -> dict[str, Any] | None:
        """The tables of the CLI for a job (partial while it runs); None for unknown jobs.

        benchmark rows: algorithm, function, dim, runs, failed, min, max, avg, std, median, rank
        (rank of the avg among the algorithms at that function and dim; 1 = best), seconds_mean
        and cpu_seconds_mean (wall and CPU seconds per run; the CPU mean over the runs that
        have one, null when none has: stored before it was measured), marker, p,
        p_holm (Wilcoxon rank-sum test against the spec's reference, docs/statistics.md).
        map rows: planner, map, runs, failed, success_rate, collisions, length_mean, length_std,
        error_mean, seconds_mean, gap_mean (length and gap over successful runs), and per measure
        (success, length, seconds) its marker and Holm-adjusted p, and ``optimum_reason`` (why
        the cell has no exact optimum; null when it has one); a map summary's ``warnings`` are
        its stated trajectories through walls (:mod:`swarmpath.service.cell_notes`), a map row
        its MovingAI ``bucket`` (the spec's ``buckets``; null without one) and a map summary
        ``buckets``: success and gap per planner and bucket
        (:func:`swarmpath.evidence.buckets.bucket_rows`, the rows of ``swarmpath plan --scen``).
        ``statistics``: the tests' document (:mod:`swarmpath.service.summary_stats`)."""
        from swarmpath.evidence.stats import describe, rank

        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None:
                return None
            seq, kind = job["seq"], job["kind"]
            job_spec = json.loads(job["spec"])
            cells = db.execute(
                "SELECT idx, spec, failed FROM cells WHERE job_seq = ? ORDER BY idx", (seq,)
            ).fetchall()
            if kind == "benchmark":
                values: dict[int, list[float]] = {}
                times: dict[int, tuple[list[float], list[float]]] = {}  # wall, CPU
                for idx, value, seconds, cpu in db.execute(
                    "SELECT cell_idx, value, seconds, cpu_seconds FROM results WHERE job_seq = ?"
                    " AND status = 'ok' ORDER BY cell_idx, run",
                    (seq,),
                ):
                    values.setdefault(idx, []).append(math.inf if value is None else value)
                    wall, cpus = times.setdefault(idx, ([], []))
                    wall.append(seconds)
                    if cpu is not None:  # NULL: a run stored before CPU times were measured
                        cpus.append(cpu)
            else:
                metrics: dict[int, list[dict[str, Any]]] = {}
                for idx, m in db.execute(
                    "SELECT cell_idx, metrics FROM results WHERE job_seq = ? AND status = 'ok' "
                    "ORDER BY cell_idx, run",
                    (seq,),
                ):
                    metrics.setdefault(idx, []).append(json.loads(m))
        rows: list[dict[str, Any]] = []
        notes: list[CellNotes] = []
        if kind == "benchmark":
            groups: dict[tuple[str, int], dict[str, float]] = {}
            for c in cells:
                spec = json.loads(c["spec"])
                row: dict[str, Any] = {
                    "algorithm": spec["algorithm"], "function": spec["function"],
                    "dim": spec["dim"], "runs": len(values.get(c["idx"], ())),
                    "failed": c["failed"],
                    # means over the runs that have them (the CPU of older rows is missing)
                    "seconds_mean": _mean(times.get(c["idx"], ([], []))[0]),
                    "cpu_seconds_mean": _mean(times.get(c["idx"], ([], []))[1]),
                }
                if c["idx"] in values:
                    row.update(describe(values[c["idx"]]))
                    plain = (spec.get("transform") or "none") == "none" and not spec.get("shifted")
                    row["origin_suspect"] = (
                        origin_suspect(spec["function"], values[c["idx"]]) if plain else None
                    )
                    groups.setdefault((row["function"], row["dim"]), {})[row["algorithm"]] = row[
                        "avg"
                    ]
                rows.append(row)
            ranks = {g: rank(avgs) for g, avgs in groups.items()}
            for row in rows:
                if "avg" in row:
                    row["rank"] = ranks[(row["function"], row["dim"])][row["algorithm"]]
                else:
                    row.update(dict.fromkeys(
                        ("min", "max", "avg", "std", "median", "q1", "q3", "iqr", "rank",
                         "origin_suspect")
                    ))
            statistics = benchmark_statistics(
                rows, [values.get(c["idx"]) for c in cells], job_spec["algorithms"],
                job_spec.get("reference"),
            )
            race = self.race(job_id) if job_spec.get("racing") else None
            if race is not None:  # the race decided the markers (evidence.race_report)
                statistics.update(apply_race(rows, race, job_spec["algorithms"],
                                             job_spec.get("reference")))
        else:
            where = _map_indexes(job_spec.get("maps") or [])
            buckets = job_spec.get("buckets") or {}
            bucketed: list[dict[str, Any]] = []
            for c in cells:
                spec = json.loads(c["spec"])
                runs = metrics.get(c["idx"], [])
                note = cell_notes(runs, where.get(spec["map"]), spec["map"])
                notes.append(note)
                rows.append(
                    {"planner": spec["planner"], "map": spec["map"],
                     "bucket": buckets.get(spec["map"]), "failed": c["failed"],
                     **map_cell_summary(runs), "optimum_reason": note.optimum_reason}
                )
                if spec["map"] in buckets:
                    bucketed += [dict(m, planner=spec["planner"], map=spec["map"]) for m in runs]
            statistics = map_statistics(
                rows, [metrics.get(c["idx"], []) for c in cells], job_spec["planners"],
                job_spec.get("reference"),
            )
        return {
            "job_id": job_id,
            "kind": kind,
            "state": job["state"],
            "partial": job["runs_done"] + job["runs_failed"] < job["runs_total"],
            "runs_total": job["runs_total"],
            "runs_done": job["runs_done"],
            "runs_failed": job["runs_failed"],
            "columns": list(BENCHMARK_COLUMNS if kind == "benchmark" else MAP_COLUMNS) + (
                list(RACE_COLUMNS) if kind == "benchmark" and job_spec.get("racing") else []),
            "rows": [_safe(r) for r in rows],
            "statistics": statistics,
            **({} if kind == "benchmark" else {
                "warnings": job_warnings(notes),
                # success and gap per planner and MovingAI bucket, as swarmpath plan --scen
                "buckets": [_safe(r) for r in bucket_rows(bucketed, buckets)]}),
            "pins": json.loads(job["pins"] or "{}"),  # the code it ran (swarmpath.plugins.pins)
        }

    def summary_csv(self, job_id: str) -> str | None:
        s = self.summary(job_id)
        if s is None:
            return None
        return summary_to_csv(s)
