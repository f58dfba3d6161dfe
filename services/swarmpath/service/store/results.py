"""Results: fencing and storing what workers report."""

from __future__ import annotations

import sqlite3
import time
from collections.abc import Iterable

from swarmpath.service.capability import result_ok
from swarmpath.service.protocol import (
    AckStatus,
    RunResult,
)
from swarmpath.service.store.base import FINAL_STATES, StoreBase, _dumps
from swarmpath.service.store.series import encode_series


class ResultsMixin(StoreBase):
    """Results: fencing and storing what workers report."""

    def accept_result(self, result: RunResult, now: float | None = None) -> AckStatus:
        """Store one result under the fencing rules (module docstring); never double-counts."""
        return self.accept_results([result], now)[0]

    def accept_results(
        self, results: Iterable[RunResult], now: float | None = None
    ) -> list[AckStatus]:
        """Several results in one transaction (one fsync); statuses in input order."""
        now = time.time() if now is None else now
        with self._tx() as db:
            out = [self._accept(db, r, now) for r in results]
            counts = {s: out.count(s) for s in ("accepted", "duplicate", "stale")}
            for status, counter in (
                ("accepted", "results_accepted"), ("duplicate", "duplicates"), ("stale", "stale")
            ):
                if counts[status]:
                    self._bump(db, counter, counts[status])
        return out

    def _accept(self, db: sqlite3.Connection, r: RunResult, now: float) -> AckStatus:
        lease = db.execute("SELECT * FROM leases WHERE lease_id = ?", (r.lease_id,)).fetchone()
        if lease is None or lease["worker"] != r.worker or not result_ok(lease["capability"], r):
            return "stale"
        job = db.execute(
            "SELECT seq, id, kind, state, runs_total FROM jobs WHERE seq = ?", (lease["job_seq"],)
        ).fetchone()
        if job["id"] != r.job_id or job["state"] == "cancelled" or lease["state"] == "cancelled":
            return "stale"
        cell = db.execute(
            "SELECT idx FROM cells WHERE job_seq = ? AND key = ?", (job["seq"], r.cell)
        ).fetchone()
        if cell is None or cell["idx"] != lease["cell_idx"]:
            return "stale"
        if r.run not in self._runs_of(r.lease_id, lease["runs"]):
            return "stale"
        seq, cell_idx = job["seq"], cell["idx"]
        ok = r.status == "ok"
        raw = r.metrics.get("best_fitness") if job["kind"] == "benchmark" else None
        value = float(raw) if isinstance(raw, int | float) and not isinstance(raw, bool) else None
        series = {"curve": r.curve, "best_position": r.best_position, "path": r.path}
        cur = db.execute(
            "INSERT OR IGNORE INTO results (job_seq, cell_idx, run, lease_id, worker, status,"
            " failure, value, seconds, metrics, series, created)"
            " VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (
                seq, cell_idx, r.run, r.lease_id, r.worker, r.status, r.failure, value,
                r.seconds, _dumps(r.metrics),
                encode_series(series),
                now,
            ),
        )
        if cur.rowcount == 0:
            return "duplicate"
        db.execute(
            "DELETE FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run = ?",
            (seq, cell_idx, r.run),
        )
        column = "done" if ok else "failed"
        db.execute(
            f"UPDATE cells SET {column} = {column} + 1 WHERE job_seq = ? AND idx = ?",
            (seq, cell_idx),
        )
        # every active lease holding this run (its own, or the one it was requeued into)
        for active in db.execute(
            "SELECT lease_id, runs FROM leases WHERE job_seq = ? AND cell_idx = ? "
            "AND state = 'active'",
            (seq, cell_idx),
        ).fetchall():
            if r.run in self._runs_of(active["lease_id"], active["runs"]):
                db.execute(
                    "UPDATE leases SET pending = pending - 1, "
                    "state = CASE WHEN pending <= 1 THEN 'done' ELSE state END, "
                    "ended = CASE WHEN pending <= 1 THEN ? ELSE ended END WHERE lease_id = ?",
                    (now, active["lease_id"]),
                )
        column = "runs_done" if ok else "runs_failed"
        db.execute(f"UPDATE jobs SET {column} = {column} + 1 WHERE seq = ?", (seq,))
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
        return "accepted"
