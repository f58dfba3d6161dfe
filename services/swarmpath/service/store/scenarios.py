"""The scenario of a lease's cell, for the coordinator's ``scenarios/<sha256>`` queryable
(:func:`swarmpath.service.scenarios.answer`)."""

from __future__ import annotations

import json
from typing import Any

from swarmpath.service.protocol import MapCell, ScenarioRef
from swarmpath.service.store.leases import LeasesMixin


class ScenariosMixin(LeasesMixin):
    def lease_scenario_ref(self, lease_id: str) -> tuple[str, str, str, ScenarioRef | None] | None:
        """(worker, capability, state, the ScenarioRef its lease carries or None), or None for
        an unknown lease."""
        with self._read() as db:
            row = db.execute(
                "SELECT worker, capability, state, job_seq, cell_idx FROM leases "
                "WHERE lease_id = ?", (lease_id,)).fetchone()
            if row is None:
                return None
            _key, spec = self._cell_spec(db, row["job_seq"], row["cell_idx"])
        ref = spec.scenario_ref if isinstance(spec, MapCell) else None
        return row["worker"], str(row["capability"] or ""), row["state"], ref

    def lease_scenario(self, lease_id: str) -> dict[str, Any] | None:
        """The full scenario of a lease's cell (None for a preset or an unknown lease)."""
        with self._read() as db:
            row = db.execute(
                "SELECT c.spec FROM leases l JOIN cells c ON c.job_seq = l.job_seq "
                "AND c.idx = l.cell_idx WHERE l.lease_id = ?", (lease_id,)).fetchone()
        if row is None:
            return None
        scenario = json.loads(row[0]).get("scenario")
        return scenario if isinstance(scenario, dict) else None
