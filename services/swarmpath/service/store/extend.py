"""A finished job extended to more runs per cell: a new job of the same spec whose runs the old
job already computed are taken over, not run again.

Run r of a cell is a pure function of (cell spec, seed, r), so the old job's result of run r *is*
the new job's run r: it is copied as stored. A raced job (or a job extended into a race) replays
its race over the copied runs (:func:`swarmpath.evidence.racing.race_block`): comparisons the old
race decided stay decided, cells it stopped at its ``max_runs`` race on. Its planned looks are the
old race's: looks at every round become the old job's rounds, written out (the looks' levels,
spent over those run counts, are then the old race's; re-planned over the new ``max_runs`` they
would be smaller and could reopen what a look decided), so the new rounds have no look.
"""

from __future__ import annotations

import json
import time
from typing import Any

from swarmpath.evidence.racing import EVERY_ROUND
from swarmpath.service.protocol import BenchmarkJobSpec, MapJobSpec, parse_job_spec
from swarmpath.service.racing import RacingSpec
from swarmpath.service.store.base import FINAL_STATES, StoreBase, StoreError


class ExtendError(ValueError):
    """The job cannot be extended as asked; the message says why (the field is ``runs``)."""


class ExtendMixin(StoreBase):
    """:meth:`extend_job`."""

    def extend_job(self, job_id: str, runs: int, now: float | None = None) -> tuple[str, int]:
        """A new job: ``job_id``'s spec with ``runs`` runs per cell (a raced job's ``max_runs``),
        holding copies of every result the old job has. Returns (new id, results reused).
        Raises KeyError for an unknown job and :class:`ExtendError` when the old job has not
        ended or ``runs`` is below its runs."""
        now = time.time() if now is None else now
        with self._tx() as db:
            old = self._job_row(db, job_id)
            if old is None:
                raise KeyError(job_id)
            if old["state"] not in FINAL_STATES:
                raise ExtendError(f"job {job_id} is {old['state']}: extend it once it has ended")
            if runs < old["runs_per_cell"]:
                raise ExtendError(f"job {job_id} has {old['runs_per_cell']} runs per cell: "
                                  f"extend it to at least that many, not {runs}")
            spec = _with_runs(json.loads(old["spec"]), runs)
            pins = json.loads(old["pins"] or "{}")  # the same code as the job it extends
            new_id, seq = self._insert_job(db, spec, now, pins)  # type: ignore[attr-defined]
            if [r[0] for r in db.execute("SELECT key FROM cells WHERE job_seq = ? ORDER BY idx",
                                         (old["seq"],))] != [
                    r[0] for r in db.execute("SELECT key FROM cells WHERE job_seq = ? ORDER BY idx",
                                             (seq,))]:  # pragma: no cover - same spec, same cells
                raise StoreError(f"job {job_id}'s cells changed: cannot extend it")
            reused = db.execute(
                "INSERT INTO results (job_seq, cell_idx, run, lease_id, worker, status, failure,"
                " value, seconds, cpu_seconds, metrics, series, created) SELECT ?, cell_idx,"
                " run, lease_id, worker, status, failure, value, seconds, cpu_seconds, metrics,"
                " series, created FROM results"
                " WHERE job_seq = ?", (seq, old["seq"])).rowcount
            self._take_over(db, seq, spec, now)
        return new_id, max(reused, 0)

    def _take_over(self, db: Any, seq: int, spec: BenchmarkJobSpec | MapJobSpec,
                   now: float) -> None:
        """Counts, cursors and requeues of the copied runs; a race replayed; the job done when
        nothing is left to run."""
        raced = getattr(spec, "racing", None) is not None
        done = failed = 0
        for idx, ok, bad, top in db.execute(
                "SELECT cell_idx, SUM(status = 'ok'), SUM(status != 'ok'), MAX(run) + 1 "
                "FROM results WHERE job_seq = ? GROUP BY cell_idx", (seq,)).fetchall():
            have = {r[0] for r in db.execute(
                "SELECT run FROM results WHERE job_seq = ? AND cell_idx = ?", (seq, idx))}
            db.executemany(  # a cancelled job's holes are run again, before anything new
                "INSERT INTO requeue (job_seq, cell_idx, run, since) VALUES (?, ?, ?, ?)",
                [(seq, idx, r, now) for r in range(top) if r not in have])
            db.execute(
                "UPDATE cells SET done = ?, failed = ?, next_run = ?, runs = MAX(runs, ?) "
                "WHERE job_seq = ? AND idx = ?",
                (ok, bad, top, top if raced else 0, seq, idx))
            done, failed = done + ok, failed + bad
        total = db.execute("SELECT SUM(runs) FROM cells WHERE job_seq = ?", (seq,)).fetchone()[0]
        db.execute("UPDATE jobs SET runs_done = ?, runs_failed = ?, runs_total = ? WHERE seq = ?",
                   (done, failed, total, seq))
        if raced:
            ctx = self._race_context(db, seq)  # type: ignore[attr-defined]
            for members in ctx[1].members.values():
                self._race_step(db, seq, members[0][0], now)
        row = db.execute("SELECT runs_done, runs_failed, runs_total FROM jobs WHERE seq = ?",
                         (seq,)).fetchone()
        if row["runs_done"] + row["runs_failed"] >= row["runs_total"]:
            db.execute("UPDATE jobs SET state = ?, started = ?, finished = ? WHERE seq = ?",
                       ("failed" if row["runs_done"] == 0 else "done", now, now, seq))


def _with_runs(spec: dict[str, Any], runs: int) -> BenchmarkJobSpec | MapJobSpec:
    """The stored spec with ``runs`` (and a race's ``max_runs``), validated again."""
    old_runs, spec = spec["runs"], {**spec, "runs": runs}
    if spec.get("racing"):
        spec["racing"] = {**spec["racing"], "max_runs": runs}
        if spec["racing"].get("looks") == EVERY_ROUND:  # the old rounds' looks (module text)
            old = RacingSpec.model_validate(spec["racing"]).settings(old_runs)
            spec["racing"]["looks"] = list(old.look_runs)
            spec["racing"]["look_share"] = old.look_share if old.look_runs else 0.0
    try:
        return parse_job_spec(spec)
    except ValueError as exc:
        raise ExtendError(f"the job's spec with runs {runs} is not valid: {exc}") from None
