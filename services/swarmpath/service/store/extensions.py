"""Which workers can run which cells: a job's pinned extensions against what the live workers
advertise (swarmpath.plugins.pins), for leasing and for a job's ``waiting`` state."""

from __future__ import annotations

import sqlite3
from collections.abc import Callable, Mapping

from swarmpath.plugins.pins import missing, requirements, runnable
from swarmpath.service.store.base import CellSpec, StoreBase

#: What a worker advertised (requirement key -> digest prefix), or None for a worker that
#: advertised nothing (it runs the built-ins, as before pins).
Advertised = Mapping[str, str] | None


def runs_on(needs: list[str] | tuple[str, ...], pins: Mapping[str, Mapping[str, str]],
            ads: Advertised) -> bool:
    """Whether a worker advertising ``ads`` runs a cell needing ``needs``, as pinned."""
    if ads is None:  # no advertisement: built-ins only, at their pinned digests
        return all(pins.get(k, {}).get("source", "built-in") == "built-in" for k in needs)
    return runnable(needs, pins, ads)


def can_run(pins: Mapping[str, Mapping[str, str]], ads: Advertised) -> Callable[[CellSpec], bool]:
    """Whether a worker advertising ``ads`` may be leased a cell of a job pinned to ``pins``."""
    return lambda cell: runs_on(requirements(cell), pins, ads)


def cell_pins(pins: Mapping[str, Mapping[str, str]], cell: CellSpec) -> dict[str, str]:
    """The digests a lease of ``cell`` carries: its requirements' pinned ones."""
    return {k: pins[k]["digest"] for k in requirements(cell) if pins.get(k, {}).get("digest")}


class ExtensionsMixin(StoreBase):
    """A job's ``waiting`` reason (see :meth:`_waiting`)."""

    def _open_cells(self, db: sqlite3.Connection, seq: int) -> list[int]:
        """Cells of the job with runs still to lease (never leased, or requeued)."""
        fresh = [r[0] for r in db.execute(
            "SELECT idx FROM cells WHERE job_seq = ? AND next_run < runs ORDER BY idx", (seq,))]
        again = [r[0] for r in db.execute(
            "SELECT DISTINCT cell_idx FROM requeue WHERE job_seq = ?", (seq,))]
        return sorted(set(fresh) | set(again))

    def _waiting(self, row: sqlite3.Row, pins: Mapping[str, Mapping[str, str]],
                 live: Mapping[str, Advertised]) -> str | None:
        """Why no live worker can run any of the job's open cells, or None when one can (or when
        the job has a lease running, or nothing left to lease). With no live worker at all, a
        job needing only built-ins is just queued, as before; one needing a plugin waits."""
        with self._read() as db:
            active = db.execute("SELECT 1 FROM leases WHERE job_seq = ? AND state = 'active' "
                                "LIMIT 1", (row["seq"],)).fetchone()
            if active is not None:
                return None
            cells = [self._cell_spec(db, row["seq"], i)[1]  # type: ignore[attr-defined]
                     for i in self._open_cells(db, row["seq"])]
        needs = list(dict.fromkeys(tuple(requirements(c)) for c in cells))
        if not needs:
            return None
        if any(runs_on(need, pins, ads) for need in needs for ads in live.values()):
            return None
        if not live and all(pins.get(k, {}).get("source", "built-in") == "built-in"
                            for need in needs for k in need):
            return None
        ads = {w: (a if a is not None else {}) for w, a in live.items()}
        reasons = list(dict.fromkeys(r for need in needs for r in missing(need, pins, ads)))
        return "; ".join(reasons) or "no live worker can run its cells"
