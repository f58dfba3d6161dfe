"""A reported run as the coordinator handles it after decoding: :class:`Incoming`.

Whatever the wire form (a binary result frame, :mod:`swarmpath.service.result_frame`, or a JSON
:class:`~swarmpath.service.protocol.RunResult`), a result becomes one slotted object holding its
small fields and its series as float64 numpy arrays, so the store, the MCAP recorder and the
dashboard read the same arrays without converting them to Python lists. ``capability`` is the
lease secret the result's proof was checked against (None: not checked yet); the store accepts a
result only when that is the secret it holds for the lease.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swarmpath.service.protocol import RunResult
from swarmpath.service.result_frame import RunFields

#: The series a result may carry, in their wire and store order, with their row widths
#: (curve and best_position are vectors; path rows are [x, y, t]).
SERIES: dict[str, int | None] = {"curve": None, "best_position": None, "path": 3}


@dataclass(slots=True, eq=False)
class Incoming(RunFields):
    """One reported run (see the module docstring)."""

    curve: np.ndarray | None = None
    best_position: np.ndarray | None = None
    path: np.ndarray | None = None
    capability: str | None = field(default=None, repr=False)
    #: the series as the store keeps them (``results.series``), when the wire gave them so
    stored_series: bytes | None = field(default=None, repr=False)

    @classmethod
    def from_result(cls, r: RunResult, capability: str | None = None) -> Incoming:
        """A JSON-decoded result (its lists become float64 arrays)."""
        return cls(
            r.lease_id, r.job_id, r.cell, r.run, r.worker, r.status, r.failure, r.seconds,
            dict(r.metrics),
            None if r.curve is None else np.asarray(r.curve, dtype=np.float64),
            None if r.best_position is None else np.asarray(r.best_position, dtype=np.float64),
            None if r.path is None else np.asarray(r.path, dtype=np.float64).reshape(-1, 3),
            capability, cpu_seconds=r.cpu_seconds,
        )

    def series(self) -> dict[str, np.ndarray]:
        """The series present, by name (in :data:`SERIES` order)."""
        out = {}
        for name in SERIES:
            value = getattr(self, name)
            if value is not None:
                out[name] = value
        return out
