"""Results: fencing and storing what workers report.

A batch is stored in one transaction; inside it, the results of each lease are checked run by
run against that lease (its worker, its job and cell, its runs, its capability) and the lease,
cell and job rows are read and updated once per lease, not once per run."""

from __future__ import annotations

import hmac
import math
import sqlite3
import time
from collections.abc import Iterable, Sequence
from typing import Any

import orjson

from swarmpath.service.capability import result_ok
from swarmpath.service.incoming import Incoming
from swarmpath.service.protocol import (
    AckStatus,
    RunResult,
)
from swarmpath.service.store.base import FINAL_STATES, StoreBase, _dumps
from swarmpath.service.store.columns import ResultColumns, from_incoming


class ResultsMixin(StoreBase):
    """Results: fencing and storing what workers report."""

    def accept_result(self, result: RunResult | Incoming, now: float | None = None) -> AckStatus:
        """Store one result under the fencing rules (module docstring); never double-counts."""
        return self.accept_results([result], now)[0]

    def accept_results(
        self, results: Iterable[RunResult | Incoming], now: float | None = None
    ) -> list[AckStatus]:
        """Several results in one transaction (one fsync); statuses in input order.

        An :class:`Incoming` counts as proven when its ``capability`` (the secret its proof was
        checked with) is the lease's; a :class:`RunResult` has its proof checked here."""
        now = time.time() if now is None else now
        items = list(results)
        out: list[AckStatus] = ["stale"] * len(items)
        with self._tx() as db:
            incoming = [r if isinstance(r, Incoming) else self._proven_json(db, r)
                        for r in items]
            groups, indexes = from_incoming(incoming)
            for statuses, where in zip(self._accept_all(db, groups, now), indexes, strict=True):
                for i, status in zip(where, statuses, strict=True):
                    out[i] = status
        return out

    def accept_columns(
        self, batch: Sequence[ResultColumns], now: float | None = None
    ) -> list[list[AckStatus]]:
        """Results as columns (one lease each), all in one transaction (one fsync); each one's
        statuses run by run."""
        now = time.time() if now is None else now
        with self._tx() as db:
            return self._accept_all(db, batch, now)

    def _accept_all(self, db: sqlite3.Connection, batch: Sequence[ResultColumns],
                    now: float) -> list[list[AckStatus]]:
        out = [self._accept_lease(db, cols, now) for cols in batch]
        counts = {"accepted": 0, "duplicate": 0, "stale": 0}
        for statuses in out:
            for status in counts:
                counts[status] += statuses.count(status)  # type: ignore[arg-type]
        for status, counter in (
            ("accepted", "results_accepted"), ("duplicate", "duplicates"), ("stale", "stale")
        ):
            if counts[status]:
                self._bump(db, counter, counts[status])
        return out

    @staticmethod
    def _proven_json(db: sqlite3.Connection, r: RunResult) -> Incoming:
        """A JSON result as an Incoming, proven (``capability`` set) when its proof holds for
        its lease's secret."""
        row = db.execute("SELECT capability FROM leases WHERE lease_id = ?",
                         (r.lease_id,)).fetchone()
        cap = None if row is None or not row["capability"] else str(row["capability"])
        return Incoming.from_result(r, cap if cap is not None and result_ok(cap, r) else None)

    def _accept_lease(
        self, db: sqlite3.Connection, c: ResultColumns, now: float,
    ) -> list[AckStatus]:
        """One lease's results, fenced run by run."""
        out: list[AckStatus] = ["stale"] * len(c.runs)
        lease_id = c.lease_id
        if c.capability is None:
            return out
        lease = db.execute(
            "SELECT worker, job_seq, cell_idx, runs, state, capability FROM leases "
            "WHERE lease_id = ?", (lease_id,)).fetchone()
        if lease is None or lease["state"] == "cancelled" or not lease["capability"] \
                or lease["worker"] != c.worker \
                or not hmac.compare_digest(c.capability, lease["capability"]):
            return out
        job = db.execute(
            "SELECT id, kind, state FROM jobs WHERE seq = ?", (lease["job_seq"],)
        ).fetchone()
        if job["state"] == "cancelled" or job["id"] != c.job_id:
            return out
        seq, cell_idx = lease["job_seq"], lease["cell_idx"]
        key = db.execute(
            "SELECT key FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
        ).fetchone()["key"]
        if c.cell != key:
            return out
        runs = self._runs_of(lease_id, lease["runs"])
        fresh: dict[int, int] = {}  # run -> index in the columns of its first valid result
        for k, run in enumerate(c.runs):
            if run not in runs:
                continue
            if run in fresh:
                out[k] = "duplicate"
            else:
                fresh[run] = k
        if not fresh:
            return out
        lo, hi = min(fresh), max(fresh)
        stored = {row[0] for row in db.execute(
            "SELECT run FROM results WHERE job_seq = ? AND cell_idx = ? AND run BETWEEN ? AND ?",
            (seq, cell_idx, lo, hi))}
        benchmark = job["kind"] == "benchmark"
        new = [k for run, k in fresh.items() if run not in stored]
        for run, k in fresh.items():
            out[k] = "duplicate" if run in stored else "accepted"
        status, metrics = c.status, c.metrics
        failed = sum(1 for k in new if status[k] != "ok")
        worker, failure, seconds, series = c.worker, c.failure, c.seconds, c.series
        rows = [(seq, cell_idx, c.runs[k], lease_id, worker, status[k], failure[k],
                 _value(metrics[k]) if benchmark else None, seconds[k], c.cpu(k),
                 _metrics_json(metrics[k]), series[k], now) for k in new]
        if not rows:
            return out
        db.executemany(
            "INSERT INTO results (job_seq, cell_idx, run, lease_id, worker, status,"
            " failure, value, seconds, cpu_seconds, metrics, series, created)"
            " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)", rows)
        accepted = {row[2] for row in rows}
        requeued = [row[0] for row in db.execute(
            "SELECT run FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run BETWEEN ? AND ?",
            (seq, cell_idx, lo, hi)) if row[0] in accepted]
        if requeued:
            db.executemany(
                "DELETE FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                [(seq, cell_idx, run) for run in requeued])
        done = len(rows) - failed
        db.execute("UPDATE cells SET done = done + ?, failed = failed + ? "
                   "WHERE job_seq = ? AND idx = ?", (done, failed, seq, cell_idx))
        # every active lease holding these runs (their own, or the one they were requeued into)
        for active in db.execute(
            "SELECT lease_id, runs FROM leases WHERE job_seq = ? AND cell_idx = ? "
            "AND state = 'active'", (seq, cell_idx),
        ).fetchall():
            held = self._runs_of(active["lease_id"], active["runs"])
            n = len(accepted & held) if len(held) < len(accepted) else \
                sum(1 for run in accepted if run in held)
            if n:
                db.execute(
                    "UPDATE leases SET pending = pending - ?, "
                    "state = CASE WHEN pending <= ? THEN 'done' ELSE state END, "
                    "ended = CASE WHEN pending <= ? THEN ? ELSE ended END WHERE lease_id = ?",
                    (n, n, n, now, active["lease_id"]),
                )
        self._race_step(db, seq, cell_idx, now)  # may give a raced job's cells another round
        db.execute("UPDATE jobs SET runs_done = runs_done + ?, runs_failed = runs_failed + ? "
                   "WHERE seq = ?", (done, failed, seq))
        row = db.execute(
            "SELECT runs_done, runs_failed, runs_total, state FROM jobs WHERE seq = ?", (seq,)
        ).fetchone()
        if row["runs_done"] + row["runs_failed"] >= row["runs_total"] and row["state"] not in (
            FINAL_STATES
        ):
            final = "failed" if row["runs_done"] == 0 else "done"
            db.execute(
                "UPDATE jobs SET state = ?, finished = ? WHERE seq = ?", (final, now, seq)
            )
            db.execute(
                "UPDATE leases SET state = 'done', ended = ? WHERE job_seq = ? "
                "AND state = 'active'",
                (now, seq),
            )
        return out


def _metrics_json(metrics: dict[str, Any]) -> str:
    """The metrics column: compact JSON (orjson; the general encoder when a value is not a
    finite float or a 64-bit integer, e.g. ``Infinity``, which orjson would write as null)."""
    for v in metrics.values():
        if (isinstance(v, float) and not math.isfinite(v)) or \
                (isinstance(v, int) and not -2**63 <= v < 2**64):
            return _dumps(metrics)
    return orjson.dumps(metrics).decode()


def _value(metrics: dict[str, Any]) -> float | None:
    """The ``value`` column: a benchmark run's best_fitness when it is a number."""
    raw = metrics.get("best_fitness")
    return float(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) else None
