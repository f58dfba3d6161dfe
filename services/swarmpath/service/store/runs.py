"""Runs as REST and MCAP read them: one item per run, one run, records for the recorder."""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Iterator
from typing import Any

import orjson

from swarmpath.service.store.base import StoreBase, _safe
from swarmpath.service.store.series import decode_series


class RunViewsMixin(StoreBase):
    """Runs as REST and MCAP read them: one item per run, one run, records for the recorder."""

    @staticmethod
    def _identity(kind: str, spec: dict[str, Any], buckets: dict[str, Any]) -> dict[str, Any]:
        """A run's cell identity; a map run's MovingAI ``bucket`` (the job spec's ``buckets``:
        a .scen pair's, None without one) beside its map."""
        if kind == "benchmark":
            return {
                "algorithm": spec["algorithm"], "function": spec["function"], "dim": spec["dim"],
            }
        return {"planner": spec["planner"], "map": spec["map"],
                "bucket": buckets.get(spec["map"])}

    def _item(
        self,
        job: sqlite3.Row,
        job_spec: dict[str, Any],
        cell_idx: int,
        key: str,
        cell_spec: dict[str, Any],
        run: int,
        result: sqlite3.Row | None,
        state: str,
        worker: str | None,
    ) -> dict[str, Any]:
        item: dict[str, Any] = {
            "run_id": cell_idx * job["runs_per_cell"] + run,
            "run": run,
            "cell": key,
            **self._identity(job["kind"], cell_spec, job_spec.get("buckets") or {}),
            "seed": job_spec["seed"],
            "state": state,
            "worker": worker,
        }
        if result is not None:
            metrics = json.loads(result["metrics"])
            item.update({k: v for k, v in metrics.items() if k not in item})
            item["seconds"] = metrics.get("seconds", result["seconds"])
            # a map run's own (the planner's, RunOutcome), else the run's; None: not measured
            item["cpu_seconds"] = metrics.get("cpu_seconds", result["cpu_seconds"])
            item["failure"] = result["failure"]
            item["lease_id"] = result["lease_id"]
            item["completed"] = result["created"]
        return _safe(item)

    def runs(
        self, job_id: str, limit: int = 100, offset: int = 0, series: bool = False
    ) -> list[dict[str, Any]] | None:
        """One item per run in run_id order (all runs, finished or not); None for unknown jobs.
        ``series``: each item also holds its cell's ``spec`` and its series (curve and
        best_position, or path) as :meth:`run` gives them."""
        limit, offset = max(0, int(limit)), max(0, int(offset))
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None:
                return None
            seq = job["seq"]
            positions = self._run_positions(db, job, offset, offset + limit)
            if not positions:
                return []
            (first_cell, first_run), (last_cell, last_run) = positions[0], positions[-1]
            job_spec = json.loads(job["spec"])
            cells = {
                c["idx"]: (c["key"], json.loads(c["spec"]))
                for c in db.execute(
                    "SELECT idx, key, spec FROM cells WHERE job_seq = ? AND idx BETWEEN ? AND ?",
                    (seq, first_cell, last_cell),
                )
            }
            results = {
                (r["cell_idx"], r["run"]): r
                for r in db.execute(
                    "SELECT cell_idx, run, lease_id, worker, status, failure, seconds,"
                    f" cpu_seconds, metrics, created{', series' if series else ''}"
                    " FROM results WHERE job_seq = ? AND (cell_idx, run) >= (?, ?)"
                    " AND (cell_idx, run) <= (?, ?)",
                    (seq, first_cell, first_run, last_cell, last_run),
                )
            }
            leased = self._leased_runs(db, seq)
        items = []
        for cell_idx, run in positions:
            key, cell_spec = cells[cell_idx]
            res = results.get((cell_idx, run))
            state, worker = self._run_state(job["state"], cell_idx, run, res, leased)
            item = self._item(job, job_spec, cell_idx, key, cell_spec, run, res, state, worker)
            if series:
                item["spec"] = cell_spec
                if res is not None and res["series"] is not None:
                    item.update(decode_series(res["series"]))
            items.append(item)
        return items

    def iter_runs(
        self, job_id: str, series: bool = True, batch: int = 500
    ) -> Iterator[dict[str, Any]]:
        """Every run of a job in run_id order (see :meth:`runs`), read in batches without holding
        the lock in between: for streaming exports of any size."""
        offset = 0
        while True:
            items = self.runs(job_id, batch, offset, series=series)
            if not items:
                return
            yield from items
            offset += len(items)

    @staticmethod
    def _run_positions(db: sqlite3.Connection, job: sqlite3.Row, lo: int, hi: int) -> list[
            tuple[int, int]]:
        """(cell index, run) of the job's runs number ``lo`` to ``hi`` - 1 in run_id order. Every
        cell has ``runs_per_cell`` runs, except in a raced job, whose cells have the runs their
        race gave them (``cells.runs``): there the run ids have gaps."""
        rpc = job["runs_per_cell"]
        lo, hi = max(lo, 0), min(hi, job["runs_total"])
        if lo >= hi:
            return []
        if job["runs_total"] == job["cells_total"] * rpc:
            return [divmod(position, rpc) for position in range(lo, hi)]
        out: list[tuple[int, int]] = []
        start = 0  # the position of the cell's first run
        for idx, runs in db.execute("SELECT idx, runs FROM cells WHERE job_seq = ? ORDER BY idx",
                                    (job["seq"],)):
            if start + runs > lo:
                out.extend((idx, start_run) for start_run in range(
                    max(lo - start, 0), min(hi - start, runs)))
            start += runs
            if start >= hi:
                break
        return out

    @staticmethod
    def _has_run(db: sqlite3.Connection, job: sqlite3.Row | None, run_id: int) -> bool:
        """Whether ``run_id`` names a run of the job (a raced cell has only its race's runs)."""
        if job is None or not 0 <= run_id < job["cells_total"] * job["runs_per_cell"]:
            return False
        cell_idx, run = divmod(run_id, job["runs_per_cell"])
        row = db.execute("SELECT runs FROM cells WHERE job_seq = ? AND idx = ?",
                         (job["seq"], cell_idx)).fetchone()
        return row is not None and run < row["runs"]

    def _leased_runs(self, db: sqlite3.Connection, seq: int) -> dict[tuple[int, int], str]:
        out: dict[tuple[int, int], str] = {}
        for lease in db.execute(
            "SELECT lease_id, worker, cell_idx, runs FROM leases WHERE job_seq = ? "
            "AND state = 'active'",
            (seq,),
        ):
            for r in self._runs_of(lease["lease_id"], lease["runs"]):
                out[(lease["cell_idx"], r)] = lease["worker"]
        return out

    @staticmethod
    def _run_state(
        job_state: str,
        cell_idx: int,
        run: int,
        result: sqlite3.Row | None,
        leased: dict[tuple[int, int], str],
    ) -> tuple[str, str | None]:
        """done/failed (has a result), cancelled, leased (in an active lease) or queued."""
        if result is not None:
            return ("done" if result["status"] == "ok" else "failed"), result["worker"]
        if job_state == "cancelled":
            return "cancelled", None
        if (cell_idx, run) in leased:
            return "leased", leased[(cell_idx, run)]
        return "queued", None

    def run(self, job_id: str, run_id: int) -> dict[str, Any] | None:
        """One run's item plus its series (curve and best_position, or path); None if unknown."""
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None or not self._has_run(db, job, run_id):
                return None
            seq = job["seq"]
            cell_idx, run = divmod(run_id, job["runs_per_cell"])
            cell = db.execute(
                "SELECT key, spec FROM cells WHERE job_seq = ? AND idx = ?", (seq, cell_idx)
            ).fetchone()
            res = db.execute(
                "SELECT * FROM results WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                (seq, cell_idx, run),
            ).fetchone()
            leased = self._leased_runs(db, seq)
        job_spec = json.loads(job["spec"])
        state, worker = self._run_state(job["state"], cell_idx, run, res, leased)
        item = self._item(
            job, job_spec, cell_idx, cell["key"], json.loads(cell["spec"]), run, res, state, worker
        )
        if res is not None and res["series"] is not None:
            item.update(decode_series(res["series"]))
        return item

    def last_result_rowid(self) -> int:
        """The position of the newest stored result of any job (0: none), for
        ``iter_run_records(after=...)``."""
        with self._read() as db:
            row = db.execute("SELECT MAX(rowid) FROM results").fetchone()
        return int(row[0] or 0)

    def iter_run_records(
        self, job_id: str, batch: int = 2000, after: int = 0, upto: int | None = None
    ) -> Iterator[dict[str, Any]]:
        """Every stored result of a job (those after position ``after`` and, with ``upto``, up to
        that position, see :meth:`last_result_rowid`), in acceptance order, as recorder records
        (raw numbers, series included). Reads in batches without holding the lock in between
        (without ``upto`` it may also yield results stored while it reads)."""
        context = self._record_contexts.get(job_id)
        if context is None or not after:  # (a catch-up of a known job: no transaction here)
            with self._read() as db:
                if context is None:  # what a job's records share: read once per job and store
                    job = self._job_row(db, job_id)
                    if job is None:
                        return
                    seq = job["seq"]
                    context = (seq, job["runs_per_cell"], job["kind"],
                               json.loads(job["spec"])["seed"], {
                        c["idx"]: (c["key"], json.loads(c["spec"])) for c in db.execute(
                            "SELECT idx, key, spec FROM cells WHERE job_seq = ?", (seq,))})
                    if len(self._record_contexts) >= 256:  # bounded: a long-lived store
                        self._record_contexts.clear()
                    self._record_contexts[job_id] = context
                if not after:  # from the job's first result (its index entries, no row read)
                    first = db.execute("SELECT min(rowid) FROM results WHERE job_seq = ?",
                                       (context[0],)).fetchone()[0]
                    if first is None:
                        return
                    after = first - 1
        seq, rpc, kind, seed, cells = context
        last = after
        # read along the rowid (+job_seq: not the job's index entries, which are in run order
        # and would make every batch sort the job's remaining results); plain tuples, not Rows
        while True:
            with self._read() as db:
                cur = db.cursor()
                cur.row_factory = None
                rows = cur.execute(
                    f"SELECT rowid, {', '.join(_RECORD_COLUMNS)} FROM results "
                    "WHERE +job_seq = ? AND rowid > ? AND rowid <= ? ORDER BY rowid LIMIT ?",
                    (seq, last, _MAX_ROWID if upto is None else upto, batch),
                ).fetchall()
            for row in rows:
                yield _record_of(job_id, kind, seed, rpc, row, cells)
            if len(rows) < batch:  # the last (a catch-up's only) batch: no query for nothing
                return
            last = rows[-1][0]

    def run_record(self, job_id: str, run_id: int) -> dict[str, Any] | None:
        """The recorder record of one finished run (None if unknown or not finished)."""
        with self._read() as db:
            job = self._job_row(db, job_id)
            if job is None or not self._has_run(db, job, run_id):
                return None
            cell_idx, run = divmod(run_id, job["runs_per_cell"])
            r = db.execute(
                "SELECT * FROM results WHERE job_seq = ? AND cell_idx = ? AND run = ?",
                (job["seq"], cell_idx, run),
            ).fetchone()
            cell = db.execute(
                "SELECT key, spec FROM cells WHERE job_seq = ? AND idx = ?",
                (job["seq"], cell_idx),
            ).fetchone()
        if r is None:
            return None
        seed = json.loads(job["spec"])["seed"]
        return self._record(
            job_id, job["kind"], seed, job["runs_per_cell"], r, cell["key"],
            json.loads(cell["spec"]),
        )

    @staticmethod
    def _record(
        job_id: str, kind: str, seed: int, rpc: int, r: sqlite3.Row, key: str, spec: dict[str, Any]
    ) -> dict[str, Any]:
        series = decode_series(r["series"], arrays=("curve",))
        return {
            "job_id": job_id,
            "kind": kind,
            "run_id": r["cell_idx"] * rpc + r["run"],
            "cell_index": r["cell_idx"],
            "cell": key,
            "spec": spec,
            "run": r["run"],
            "seed": seed,
            "worker": r["worker"],
            "lease_id": r["lease_id"],
            "status": r["status"],
            "failure": r["failure"],
            "seconds": r["seconds"],
            "cpu_seconds": r["cpu_seconds"],
            "metrics": _metrics(r["metrics"]),
            "created": r["created"],
            **series,
        }


_MAX_ROWID = 2**63 - 1  # SQLite's largest rowid
#: The results columns a recorder record is made of, in the order :func:`_record_of` reads them.
_RECORD_COLUMNS = ("cell_idx", "run", "worker", "lease_id", "status", "failure", "seconds",
                   "cpu_seconds", "metrics", "created", "series")


def _record_of(job_id: str, kind: str, seed: int, rpc: int, row: tuple[Any, ...],
               cells: dict[int, tuple[str, dict[str, Any]]]) -> dict[str, Any]:
    """:meth:`RunsMixin._record` of a tuple ``(rowid, *_RECORD_COLUMNS)``."""
    (_, cell_idx, run, worker, lease_id, status, failure, seconds, cpu_seconds, metrics, created,
     blob) = row
    key, spec = cells[cell_idx]
    out = {
        "job_id": job_id, "kind": kind, "run_id": cell_idx * rpc + run, "cell_index": cell_idx,
        "cell": key, "spec": spec, "run": run, "seed": seed, "worker": worker,
        "lease_id": lease_id, "status": status, "failure": failure, "seconds": seconds,
        "cpu_seconds": cpu_seconds, "metrics": _metrics(metrics), "created": created,
    }
    out.update(decode_series(blob, arrays=("curve",)))
    return out


def _metrics(text: str) -> dict[str, Any]:
    """A metrics column (orjson; json for the ``Infinity``/``NaN`` orjson does not read)."""
    try:
        out: dict[str, Any] = orjson.loads(text)
    except orjson.JSONDecodeError:
        out = json.loads(text)
    return out
