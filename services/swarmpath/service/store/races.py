"""Raced jobs in the store: a block's next round is decided in the transaction that stores the
result completing its current one, so a coordinator killed at any point restarts with the same
allowances and decisions (they are a pure function of the stored results: evidence.racing)."""

from __future__ import annotations

import json
import logging
import sqlite3
from typing import Any

import numpy as np

from swarmpath.evidence.race_report import block_json, close_race, first_round_json
from swarmpath.evidence.racing import RaceSettings, race_block
from swarmpath.service.racing import Blocks, RacingSpec, group_blocks
from swarmpath.service.store.base import StoreBase, _dumps

log = logging.getLogger("swarmpath.store")

#: Jobs whose race context (settings, blocks) is kept in memory; beyond, it is read again.
RACE_CONTEXTS = 256

RaceContext = tuple[RaceSettings, Blocks]


class RacesMixin(StoreBase):
    """Rounds of raced benchmark jobs (see :mod:`swarmpath.service.racing`)."""

    def _race_context(self, db: sqlite3.Connection, seq: int) -> RaceContext | None:
        """The job's race settings and blocks, or None for a job that does not race."""
        cache: dict[int, RaceContext | None] = self._race_contexts
        if seq in cache:
            return cache[seq]
        row = db.execute("SELECT kind, spec, runs_per_cell FROM jobs WHERE seq = ?",
                         (seq,)).fetchone()
        ctx: RaceContext | None = None
        spec = json.loads(row["spec"]) if row is not None and row["kind"] == "benchmark" else {}
        if spec.get("racing"):
            racing = RacingSpec.model_validate(spec["racing"])
            cells = [(r["idx"], json.loads(r["spec"])) for r in db.execute(
                "SELECT idx, spec FROM cells WHERE job_seq = ? ORDER BY idx", (seq,))]
            blocks = group_blocks(cells, spec.get("reference"), racing.pairs)
            ctx = (racing.settings(int(row["runs_per_cell"])), blocks)
        if len(cache) >= RACE_CONTEXTS:
            cache.clear()
        cache[seq] = ctx
        return ctx

    def _race_step(self, db: sqlite3.Connection, seq: int, cell_idx: int, now: float) -> None:
        """After results of ``cell_idx`` were stored: if they complete its block's round, decide
        the block's next round (raise the allowance of the cells still racing, in ``cells.runs``
        and the job's ``runs_total``) and store the block's race."""
        ctx = self._race_context(db, seq)
        if ctx is None:
            return
        settings, blocks = ctx
        block = blocks.of[cell_idx]
        members = blocks.members[block]
        idx = [i for i, _ in members]
        marks = ",".join("?" * len(idx))
        counts = {r["idx"]: (r["runs"], r["done"] + r["failed"]) for r in db.execute(
            f"SELECT idx, runs, done, failed FROM cells WHERE job_seq = ? AND idx IN ({marks})",
            (seq, *idx))}
        if any(finished < runs for runs, finished in counts.values()):
            return  # the round is still running
        stored = db.execute("SELECT finished FROM races WHERE job_seq = ? AND block = ?",
                            (seq, block)).fetchone()
        if stored is not None and stored["finished"]:
            return
        values: dict[int, np.ndarray] = {i: np.full(counts[i][0], np.nan) for i in idx}
        for r in db.execute(
            f"SELECT cell_idx, run, value, status FROM results WHERE job_seq = ? "
            f"AND cell_idx IN ({marks})", (seq, *idx)):
            if r["status"] == "ok" and r["run"] < counts[r["cell_idx"]][0]:
                # as the summary counts them: a run without a number is the worst run
                values[r["cell_idx"]][r["run"]] = np.inf if r["value"] is None else r["value"]
        names = blocks.names(block)
        by_name = {name: values[i] for i, name in members}
        try:
            race = race_block(by_name, names, settings, blocks.comparisons,
                              memo=self._look_memo)
        except Exception:  # a result must never be lost to a bug here: stop racing the block
            log.exception("race of job %s block %s failed; its cells stop", seq, block)
            race = None
        total = 0
        for i, name in members:
            allowance = counts[i][0] if race is None else race.allowance[name]
            if allowance != counts[i][0]:
                db.execute("UPDATE cells SET runs = ? WHERE job_seq = ? AND idx = ?",
                           (allowance, seq, i))
                total += allowance - counts[i][0]
        if total:
            db.execute("UPDATE jobs SET runs_total = runs_total + ? WHERE seq = ?", (total, seq))
        doc = block_json(race, members) if race is not None else {"error": True}
        db.execute(
            "INSERT INTO races (job_seq, block, state, finished, updated) VALUES (?, ?, ?, ?, ?) "
            "ON CONFLICT (job_seq, block) DO UPDATE SET state = excluded.state, "
            "finished = excluded.finished, updated = excluded.updated",
            (seq, block, _dumps(doc), int(race is None or race.finished), now))

    def race(self, job_id: str) -> dict[str, Any] | None:
        """The race of a raced job: its settings and, per block, the rounds, each cell's runs and
        state, and the comparisons; None for an unknown job or one that does not race."""
        with self._read() as db:
            row = db.execute("SELECT seq FROM jobs WHERE id = ?", (job_id,)).fetchone()
            if row is None:
                return None
            ctx = self._race_context(db, row["seq"])
            if ctx is None:
                return None
            states = {r["block"]: json.loads(r["state"]) for r in db.execute(
                "SELECT block, state FROM races WHERE job_seq = ?", (row["seq"],))}
            runs = {r["idx"]: (r["key"], r["done"] + r["failed"]) for r in db.execute(
                "SELECT idx, key, done, failed FROM cells WHERE job_seq = ?", (row["seq"],))}
        settings, blocks = ctx
        out = []
        for block, members in blocks.members.items():
            state = states.get(block) or first_round_json(settings, members)
            for cell in state.get("cells", []):
                cell["key"], cell["finished_runs"] = runs[cell["cell"]]
            out.append({"block": json.loads(block), **state})
        # the closing rank-sum look spans blocks: taken over the stored blocks on each read
        return close_race({"settings": settings.to_json(), "comparisons": blocks.comparisons,
                           "blocks": out})

