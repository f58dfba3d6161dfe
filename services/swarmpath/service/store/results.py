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
from swarmpath.service.store.series import encode_series


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
        groups: dict[str, list[int]] = {}
        for i, r in enumerate(items):
            groups.setdefault(r.lease_id, []).append(i)
        with self._tx() as db:
            for lease_id, indexes in groups.items():
                statuses = self._accept_lease(db, lease_id, [items[i] for i in indexes], now)
                for i, status in zip(indexes, statuses, strict=True):
                    out[i] = status
            for status, counter in (
                ("accepted", "results_accepted"), ("duplicate", "duplicates"), ("stale", "stale")
            ):
                n = out.count(status)
                if n:
                    self._bump(db, counter, n)
        return out

    def _accept_lease(
        self, db: sqlite3.Connection, lease_id: str, rs: Sequence[RunResult | Incoming],
        now: float,
    ) -> list[AckStatus]:
        """The results of one lease (all with ``lease_id``), fenced run by run."""
        out: list[AckStatus] = ["stale"] * len(rs)
        lease = db.execute(
            "SELECT worker, job_seq, cell_idx, runs, state, capability FROM leases "
            "WHERE lease_id = ?", (lease_id,)).fetchone()
        if lease is None or lease["state"] == "cancelled" or not lease["capability"]:
            return out
        job = db.execute(
            "SELECT id, kind, state FROM jobs WHERE seq = ?", (lease["job_seq"],)
        ).fetchone()
        if job["state"] == "cancelled":
            return out
        seq, cell_idx, cap = lease["job_seq"], lease["cell_idx"], lease["capability"]
        key = db.execute(
            "SELECT key FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
        ).fetchone()["key"]
        runs = self._runs_of(lease_id, lease["runs"])
        fresh: dict[int, int] = {}  # run -> index in rs of its first valid result
        for k, r in enumerate(rs):
            if (r.worker != lease["worker"] or r.job_id != job["id"] or r.cell != key
                    or r.run not in runs or not _proven(cap, r)):
                continue
            if r.run in fresh:
                out[k] = "duplicate"
            else:
                fresh[r.run] = k
        if not fresh:
            return out
        lo, hi = min(fresh), max(fresh)
        stored = {row[0] for row in db.execute(
            "SELECT run FROM results WHERE job_seq = ? AND cell_idx = ? AND run BETWEEN ? AND ?",
            (seq, cell_idx, lo, hi))}
        benchmark = job["kind"] == "benchmark"
        rows = []
        ok_runs: list[int] = []
        failed = 0
        for run, k in fresh.items():
            if run in stored:
                out[k] = "duplicate"
                continue
            out[k] = "accepted"
            r = rs[k]
            ok = r.status == "ok"
            if ok:
                ok_runs.append(run)
            else:
                failed += 1
            raw = r.metrics.get("best_fitness") if benchmark else None
            value = float(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) \
                else None
            blob = r.stored_series if isinstance(r, Incoming) else None
            if blob is None:
                blob = encode_series(
                    {"curve": r.curve, "best_position": r.best_position, "path": r.path})
            rows.append((seq, cell_idx, run, lease_id, r.worker, r.status, r.failure, value,
                         r.seconds, _metrics_json(r.metrics), blob, now))
        if not rows:
            return out
        db.executemany(
            "INSERT INTO results (job_seq, cell_idx, run, lease_id, worker, status,"
            " failure, value, seconds, metrics, series, created)"
            " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)", rows)
        accepted = {row[2] for row in rows}
        requeued = [row[0] for row in db.execute(
            "SELECT run FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run BETWEEN ? AND ?",
            (seq, cell_idx, lo, hi)) if row[0] in accepted]
        if requeued:
            db.executemany(
                "DELETE FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                [(seq, cell_idx, run) for run in requeued])
        done = len(ok_runs)
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


def _proven(capability: str, r: RunResult | Incoming) -> bool:
    """``r`` proved ``capability`` (the lease's secret, never empty here)."""
    if isinstance(r, Incoming):
        return r.capability is not None and hmac.compare_digest(r.capability, capability)
    return result_ok(capability, r)
