"""Leases: granting (sized, bundled, fair between jobs), heartbeats, requeues, releases;
active leases per worker."""

from __future__ import annotations

import json
import sqlite3
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from swarmpath.service.capability import new_capability, progress_ok
from swarmpath.service.protocol import (
    CELL_ADAPTER,
    Lease,
    LeaseState,
)
from swarmpath.service.scenarios import by_reference
from swarmpath.service.store.base import CellSpec, RunsFor, StoreBase, _dumps
from swarmpath.service.store.extensions import can_run, cell_pins

_STOP = object()  # _pick_runs: the sizer ends the bundle
#: lease_many's ``extensions`` default: lease any cell (callers that have no worker to ask)
ANY_WORKER = object()


class LeasesMixin(StoreBase):
    """Leases: granting (sized, bundled, fair between jobs), heartbeats, requeues, releases;
    active leases per worker."""

    def lease(
        self,
        worker: str,
        max_runs: int,
        now: float | None = None,
        lease_seconds: float = 60.0,
        heartbeat_seconds: float | None = None,
        runs_for: RunsFor | None = None,
    ) -> Lease | None:
        """Lease up to ``max_runs`` runs of one cell to ``worker``, or None if nothing is leasable
        (:meth:`lease_many` with one lease)."""
        leases = self.lease_many(worker, max_runs, now, lease_seconds, heartbeat_seconds,
                                 runs_for=runs_for)
        return leases[0] if leases else None

    def lease_many(
        self,
        worker: str,
        max_runs: int,
        now: float | None = None,
        lease_seconds: float = 60.0,
        heartbeat_seconds: float | None = None,
        *,
        max_leases: int = 1,
        runs_for: RunsFor | None = None,
        extensions: Mapping[str, str] | object | None = ANY_WORKER,
    ) -> list[Lease]:
        """Up to ``max_leases`` leases for ``worker`` in one transaction (a bundle), each of up to
        ``max_runs`` runs of one cell; empty when nothing is leasable.

        Jobs take turns (the job leased least recently goes first; new jobs in submission order);
        within a job, requeued runs go first, then the next unleased runs in cell order.
        ``runs_for(cell_spec, remaining, bundle)``, when given, sizes each lease: how many runs of
        the cell picked (``remaining``: the job's runs not leased yet, requeued ones included;
        ``bundle``: the leases already granted by this call); 0 ends the bundle (never asked for
        the first lease, which has at least one run). ``extensions``: what the worker advertised
        (swarmpath.plugins.pins; None: nothing, it runs the built-ins): only cells whose
        pinned extensions it has are leased (default: any cell, for callers without workers).

        The transaction is not waited on to reach the disk (``_tx(durable=False)``): after a
        power cut the lease may be gone, its runs are leased again, and the worker's results
        for it are ``stale`` - at least once, never twice."""
        if max_runs < 1:
            raise ValueError("max_runs must be >= 1")
        if max_leases < 1:
            raise ValueError("max_leases must be >= 1")
        now = time.time() if now is None else now
        hb = heartbeat_seconds or max(lease_seconds / 3.0, 0.1)
        out: list[Lease] = []
        with self._tx(durable=False) as db:
            while len(out) < max_leases:
                lease = self._lease_one(db, worker, max_runs, now, lease_seconds, hb, runs_for,
                                        out, extensions)
                if lease is None:
                    break
                out.append(lease)
        return out

    def _lease_one(
        self,
        db: sqlite3.Connection,
        worker: str,
        max_runs: int,
        now: float,
        lease_seconds: float,
        heartbeat_seconds: float,
        runs_for: RunsFor | None,
        bundle: list[Lease],
        extensions: Mapping[str, str] | object | None = ANY_WORKER,
    ) -> Lease | None:
        jobs = db.execute(
            "SELECT seq, id, runs_per_cell, spec, pins FROM jobs "
            "WHERE state IN ('queued', 'running') ORDER BY lease_turn, seq"
        ).fetchall()
        for job in jobs:
            seq = job["seq"]
            check = None
            if extensions is not ANY_WORKER:
                check = can_run(json.loads(job["pins"] or "{}"),
                                extensions)  # type: ignore[arg-type]
            picked = self._pick_runs(db, seq, max_runs, runs_for, bundle, check)
            if picked is _STOP:
                return None
            if picked is None:
                continue
            cell_idx, key, spec, runs = picked
            turn = self._bump(db, "lease_turn")
            self._bump(db, "leases")
            db.execute(
                "UPDATE jobs SET lease_turn = ?, state = 'running', "
                "started = COALESCE(started, ?) WHERE seq = ?",
                (turn, now, seq),
            )
            lease_id = uuid.uuid4().hex
            capability = new_capability()
            db.execute(
                "INSERT INTO leases (lease_id, worker, job_seq, cell_idx, runs, pending, created,"
                " deadline, state, capability) VALUES (?, ?, ?, ?, ?, ?, ?, ?, 'active', ?)",
                (lease_id, worker, seq, cell_idx, _dumps(runs), len(runs), now,
                 now + lease_seconds, capability),
            )
            self._remember_runs(lease_id, runs)
            return Lease(
                lease_id=lease_id,
                worker=worker,
                job_id=job["id"],
                cell=key,
                cell_index=cell_idx,
                runs_per_cell=job["runs_per_cell"],
                seed=json.loads(job["spec"])["seed"],
                runs=runs,
                spec=spec,
                deadline=now + lease_seconds,
                lease_seconds=lease_seconds,
                heartbeat_seconds=heartbeat_seconds,
                capability=capability,
                pins=cell_pins(json.loads(job["pins"] or "{}"), spec),
            )
        return None

    def _cell_spec(self, db: sqlite3.Connection, seq: int, cell_idx: int) -> tuple[str, CellSpec]:
        """(key, spec) of a cell as leases carry it (a map cell's large scenario replaced by its
        ScenarioRef, see swarmpath.service.scenarios); specs never change, so they are parsed
        once."""
        hit = self._cell_specs.get((seq, cell_idx))
        if hit is None:
            row = db.execute(
                "SELECT key, spec FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
            ).fetchone()
            if len(self._cell_specs) > 100_000:
                self._cell_specs.clear()
            hit = self._cell_specs[(seq, cell_idx)] = (  # a large scenario by reference
                row["key"], by_reference(CELL_ADAPTER.validate_json(row["spec"]))
            )
        return hit

    @staticmethod
    def _remaining(db: sqlite3.Connection, seq: int) -> int:
        """Runs of the job not leased yet (never leased, or requeued)."""
        fresh = db.execute(
            "SELECT COALESCE(SUM(runs - next_run), 0) FROM cells WHERE job_seq = ? "
            "AND next_run < runs", (seq,)
        ).fetchone()[0]
        again = db.execute("SELECT COUNT(*) FROM requeue WHERE job_seq = ?", (seq,)).fetchone()[0]
        return int(fresh) + int(again)

    def _pick_runs(
        self,
        db: sqlite3.Connection,
        seq: int,
        max_runs: int,
        runs_for: RunsFor | None = None,
        bundle: Sequence[Lease] = (),
        check: Callable[[CellSpec], bool] | None = None,
    ) -> tuple[int, str, CellSpec, list[int]] | object | None:
        """(cell index, key, spec, runs) to lease from job ``seq``; None when it has nothing
        leasable (that ``check`` accepts), ``_STOP`` when ``runs_for`` ends the bundle."""
        first = self._first_cell(db, seq, check, "SELECT DISTINCT cell_idx FROM requeue "
                                 "WHERE job_seq = ? ORDER BY cell_idx")
        if first is not None:
            cell_idx = first
        else:
            cell = self._first_cell(db, seq, check, "SELECT idx FROM cells WHERE job_seq = ? "
                                    "AND next_run < runs ORDER BY idx")
            if cell is None:
                return None
            cell_idx = cell
        key, spec = self._cell_spec(db, seq, cell_idx)
        if runs_for is not None:
            n = int(runs_for(spec, self._remaining(db, seq), bundle))
            if n < 1:
                if bundle:
                    return _STOP
                n = 1
            max_runs = min(max_runs, n)
        if first is not None:
            runs = [
                r[0]
                for r in db.execute(
                    "SELECT run FROM requeue WHERE job_seq = ? AND cell_idx = ? "
                    "ORDER BY run LIMIT ?",
                    (seq, cell_idx, max_runs),
                )
            ]
            db.executemany(
                "DELETE FROM requeue WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                [(seq, cell_idx, r) for r in runs],
            )
            return cell_idx, key, spec, runs
        row = db.execute(
            "SELECT next_run, runs FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
        ).fetchone()
        start = row["next_run"]
        stop = min(row["runs"], start + max_runs)
        db.execute(
            "UPDATE cells SET next_run = ? WHERE job_seq = ? AND idx = ?", (stop, seq, cell_idx)
        )
        return cell_idx, key, spec, list(range(start, stop))

    def _first_cell(self, db: sqlite3.Connection, seq: int,
                    check: Callable[[CellSpec], bool] | None, sql: str) -> int | None:
        """The first cell index ``sql`` lists (for job ``seq``) that ``check`` accepts."""
        if check is None:
            row = db.execute(sql + " LIMIT 1", (seq,)).fetchone()
            return None if row is None else int(row[0])
        for (idx,) in db.execute(sql, (seq,)).fetchall():
            if check(self._cell_spec(db, seq, idx)[1]):
                return int(idx)
        return None

    def heartbeat(
        self, lease_id: str, worker: str, now: float | None = None, lease_seconds: float = 60.0,
        *, seq: int, proof: str | None,
    ) -> LeaseState:
        """Renew an active lease of ``worker`` (deadline >= now + lease_seconds) when ``proof``
        is the lease's progress proof of ``seq`` and ``seq`` is above every seq taken before.
        Returns the lease's state ('unknown' for a wrong worker, proof or an old seq: nothing
        changes): anything but 'active' and 'unknown' tells the worker to drop it."""
        now = time.time() if now is None else now
        with self._tx(durable=False) as db:  # a lost renewal only means an earlier expiry
            row = db.execute(
                "SELECT worker, state, capability, beat FROM leases WHERE lease_id = ?",
                (lease_id,),
            ).fetchone()
            if row is None or row["worker"] != worker or seq <= row["beat"] \
                    or not progress_ok(row["capability"], lease_id, seq, proof):
                return "unknown"
            db.execute("UPDATE leases SET beat = ? WHERE lease_id = ?", (seq, lease_id))
            if row["state"] != "active":
                return row["state"]
            db.execute(
                "UPDATE leases SET deadline = MAX(deadline, ?) WHERE lease_id = ?",
                (now + lease_seconds, lease_id),
            )
            return "active"

    def capability(self, lease_id: str) -> str | None:
        """The lease's secret (None for an unknown lease)."""
        with self._read() as db:
            row = db.execute(
                "SELECT capability FROM leases WHERE lease_id = ?", (lease_id,)
            ).fetchone()
        return None if row is None or not row["capability"] else str(row["capability"])

    def cancelled_leases(self, job_id: str) -> list[tuple[str, str, str]]:
        """(lease id, worker, capability) of the job's leases ended by its cancellation."""
        with self._read() as db:
            rows = db.execute(
                "SELECT l.lease_id, l.worker, l.capability FROM leases l JOIN jobs j "
                "ON j.seq = l.job_seq WHERE j.id = ? AND l.state = 'cancelled' "
                "AND l.capability != ''",
                (job_id,),
            ).fetchall()
        return [(r[0], r[1], r[2]) for r in rows]

    def extend_active_leases(self, now: float | None = None, seconds: float = 60.0) -> int:
        """Give every active lease at least ``seconds`` from ``now``: call once when the
        coordinator restarts, since workers could not renew while it was down."""
        now = time.time() if now is None else now
        with self._tx() as db:
            return db.execute(
                "UPDATE leases SET deadline = MAX(deadline, ?) WHERE state = 'active'",
                (now + seconds,),
            ).rowcount

    def _end_leases(
        self, db: sqlite3.Connection, rows: Sequence[sqlite3.Row], state: str, now: float
    ) -> int:
        """Requeue the unfinished runs of active leases and mark them ``state``."""
        requeued = 0
        for lease in rows:
            seq, cell_idx = lease["job_seq"], lease["cell_idx"]
            runs = sorted(self._runs_of(lease["lease_id"], lease["runs"]))
            done = {
                r[0]
                for r in db.execute(
                    "SELECT run FROM results WHERE job_seq = ? AND cell_idx = ? "
                    "AND run BETWEEN ? AND ?",
                    (seq, cell_idx, runs[0], runs[-1]),
                )
            }
            todo = [r for r in runs if r not in done]
            job_state = db.execute("SELECT state FROM jobs WHERE seq = ?", (seq,)).fetchone()[0]
            if todo and job_state in ("queued", "running"):
                cur = db.executemany(
                    "INSERT OR IGNORE INTO requeue (job_seq, cell_idx, run, since) "
                    "VALUES (?, ?, ?, ?)",
                    [(seq, cell_idx, r, now) for r in todo],
                )
                requeued += max(cur.rowcount, 0)
            db.execute(
                "UPDATE leases SET state = ?, ended = ? WHERE lease_id = ?",
                (state, now, lease["lease_id"]),
            )
        if requeued:
            self._bump(db, "requeued_runs", requeued)
        return requeued

    def requeue_expired(self, now: float | None = None) -> int:
        """Requeue the unfinished runs of leases past their deadline; returns how many runs."""
        now = time.time() if now is None else now
        with self._tx() as db:
            rows = db.execute(
                "SELECT * FROM leases WHERE state = 'active' AND deadline < ?", (now,)
            ).fetchall()
            return self._end_leases(db, rows, "expired", now)

    def requeue_worker(self, worker: str, now: float | None = None) -> int:
        """The worker is gone (liveliness lost): requeue the unfinished runs of its leases."""
        now = time.time() if now is None else now
        with self._tx() as db:
            rows = db.execute(
                "SELECT * FROM leases WHERE state = 'active' AND worker = ?", (worker,)
            ).fetchall()
            return self._end_leases(db, rows, "released", now)

    def release(self, lease_id: str, worker: str, now: float | None = None) -> int:
        """The worker gives a lease back (e.g. shutting down): requeue its unfinished runs."""
        now = time.time() if now is None else now
        with self._tx() as db:
            rows = db.execute(
                "SELECT * FROM leases WHERE state = 'active' AND lease_id = ? AND worker = ?",
                (lease_id, worker),
            ).fetchall()
            return self._end_leases(db, rows, "released", now)

    def active_leases(self, worker: str | None = None) -> list[dict[str, Any]]:
        sql = (
            "SELECT l.lease_id, l.worker, l.cell_idx, l.runs, l.deadline, l.created,"
            " j.id AS job_id, j.runs_per_cell FROM leases l JOIN jobs j ON j.seq = l.job_seq"
            " WHERE l.state = 'active'"
        )
        args: tuple[Any, ...] = ()
        if worker is not None:
            sql += " AND l.worker = ?"
            args = (worker,)
        with self._read() as db:
            rows = db.execute(sql, args).fetchall()
        out = []
        for r in rows:
            runs = sorted(self._runs_of(r["lease_id"], r["runs"]))
            out.append({
                "lease_id": r["lease_id"], "worker": r["worker"], "job_id": r["job_id"],
                "cell_index": r["cell_idx"], "runs": runs,
                "run_ids": [r["cell_idx"] * r["runs_per_cell"] + x for x in runs],
                "deadline": r["deadline"], "created": r["created"],
            })
        return out

    def worker_activity(self) -> dict[str, dict[str, Any]]:
        """Per worker: current runs ('<job>:<run_id>') and runs done (all jobs)."""
        out: dict[str, dict[str, Any]] = {}
        for lease in self.active_leases():
            entry = out.setdefault(lease["worker"], {"current_runs": [], "runs_done": 0})
            entry["current_runs"] += [f"{lease['job_id']}:{i}" for i in lease["run_ids"]]
        with self._read() as db:
            for worker, n in db.execute(
                "SELECT worker, COUNT(*) FROM results GROUP BY worker"
            ):
                out.setdefault(worker, {"current_runs": [], "runs_done": 0})["runs_done"] = n
        return out

    def queue_depth(self) -> int:
        """Runs of queued/running jobs not leased yet (never leased, or requeued)."""
        with self._read() as db:
            fresh = db.execute(
                "SELECT COALESCE(SUM(c.runs - c.next_run), 0) FROM cells c JOIN jobs j "
                "ON j.seq = c.job_seq WHERE j.state IN ('queued', 'running') "
                "AND c.next_run < c.runs"
            ).fetchone()[0]
            again = db.execute(
                "SELECT COUNT(*) FROM requeue q JOIN jobs j ON j.seq = q.job_seq "
                "WHERE j.state IN ('queued', 'running')"
            ).fetchone()[0]
        return int(fresh) + int(again)
