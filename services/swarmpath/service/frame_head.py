"""The hot-path check of a result record's head (the small JSON fields of a binary result frame,
:mod:`swarmpath.service.result_frame`), without building a pydantic model per run.

:func:`fast_head` accepts only heads that
:class:`~swarmpath.service.result_frame.RunResultHead` certainly accepts, with the values it
would produce: every field of the exact JSON type (no coercion from strings or booleans), no
unknown field, identifiers matching :data:`~swarmpath.service.model.ID_PATTERN`, every bound of
the schema. For anything else it returns None, and the caller validates that head with the
pydantic model, which then either accepts it (for example a metric written as ``NaN``, which the
fast parser does not read) or rejects it naming the field. So the fast path never widens what is
accepted, and every rejection keeps the model's reason. Pure functions, no I/O.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import orjson

from swarmpath.service.model import ID_PATTERN, MAX_LEASE_RUNS

_ID = re.compile(ID_PATTERN)
_IDS = ("lease_id", "job_id", "worker")
_FIELDS = frozenset({"lease_id", "job_id", "cell", "run", "worker", "status", "failure",
                     "seconds", "metrics", "arrays"})
_REQUIRED = frozenset({"lease_id", "job_id", "cell", "run", "worker", "seconds"})
_NAMES = frozenset({"curve", "best_position", "path"})
_SCALARS = frozenset({bool, int, float, str, type(None)})
_STATUSES = frozenset({"ok", "failed"})
_EMPTY: dict[str, Any] = {}
_EMPTY_LIST: list[Any] = []
#: (lease_id, job_id, worker, cell) tuples found valid lately (bounded: cleared when full)
_CHECKED: set[tuple[Any, ...]] = set()
MAX_CHECKED = 4096
_HUGE = 2.0**63
MAX_CELL = 256
MAX_FAILURE = 20_000
MAX_ARRAYS = 3


@dataclass(slots=True, eq=False)
class RunFields:
    """The small fields of one reported run, shared by a record head and an
    :class:`~swarmpath.service.incoming.Incoming` (same order: both are built positionally)."""

    lease_id: str
    job_id: str
    cell: str
    run: int
    worker: str
    status: str
    failure: str | None
    seconds: float
    metrics: dict[str, Any]


@dataclass(slots=True, eq=False)
class RecordHead(RunFields):
    """A checked record head: the fields of a ``RunResultHead`` as plain attributes."""

    arrays: list[tuple[str, str, list[int]]]

    def fields(self) -> dict[str, Any]:
        """The small fields (without ``arrays``), as ``RunResultHead.model_dump`` gives them."""
        return {"lease_id": self.lease_id, "job_id": self.job_id, "cell": self.cell,
                "run": self.run, "worker": self.worker, "status": self.status,
                "failure": self.failure, "seconds": self.seconds, "metrics": dict(self.metrics)}


def fast_head(text: bytes) -> RecordHead | None:
    """The head in ``text`` when it is plainly valid (see the module docstring), else None."""
    try:
        d = orjson.loads(text)
    except orjson.JSONDecodeError:
        return None
    if type(d) is not dict:
        return None
    keys = d.keys()
    if keys != _FIELDS and not _REQUIRED <= keys <= _FIELDS:
        return None
    names = (d["lease_id"], d["job_id"], d["worker"], d["cell"])
    for value in names:
        if type(value) is not str:  # (a list or a dict could not even be looked up below)
            return None
    if names not in _CHECKED:  # the same lease, job, worker and cell come run after run
        if not _names_ok(names):
            return None
        if len(_CHECKED) >= MAX_CHECKED:
            _CHECKED.clear()
        _CHECKED.add(names)
    run, seconds = d["run"], d["seconds"]
    if type(run) is not int or run < 0:
        return None
    if type(seconds) is float:
        if not seconds >= 0:  # NaN included
            return None
    elif type(seconds) is int and seconds >= 0:
        seconds = float(seconds)
    else:
        return None
    status = d.get("status", "ok")
    failure = d.get("failure")
    if type(status) is not str or status not in _STATUSES:
        return None
    if failure is not None and (type(failure) is not str or len(failure) > MAX_FAILURE):
        return None
    metrics = d.get("metrics", _EMPTY)
    if type(metrics) is not dict:
        return None
    for value in metrics.values():
        kind = type(value)
        if kind not in _SCALARS or (kind is float and abs(value) >= _HUGE):
            return None  # orjson reads an integer past 64 bits as a float; the model, an int
    arrays = _arrays(d.get("arrays", _EMPTY_LIST))
    if arrays is None:
        return None
    return RecordHead(names[0], names[1], names[3], run, names[2], status, failure,
                      seconds, metrics if metrics is not _EMPTY else {}, arrays)


def _names_ok(names: tuple[Any, ...]) -> bool:
    """lease_id, job_id and worker identifiers, cell at most MAX_CELL characters (strings)."""
    return all(_ID.fullmatch(value) is not None for value in names[:3]) and \
        len(names[3]) <= MAX_CELL


def _arrays(value: Any) -> list[tuple[str, str, list[int]]] | None:
    if type(value) is not list or len(value) > MAX_ARRAYS:
        return None
    out = []
    for item in value:
        if type(item) is not list or len(item) != 3:
            return None
        name, dtype, shape = item
        if type(name) is not str or name not in _NAMES or dtype != "<f8" \
                or type(dtype) is not str or type(shape) is not list:
            return None
        for n in shape:
            if type(n) is not int:
                return None
        out.append((name, dtype, shape))
    return out


def fast_count(text: bytes) -> tuple[str, int] | None:
    """(worker, count) of a frame head when it is plainly valid, else None (as above)."""
    try:
        d = orjson.loads(text)
    except orjson.JSONDecodeError:
        return None
    if type(d) is not dict or d.keys() != {"worker", "count"}:
        return None
    worker, count = d["worker"], d["count"]
    if type(worker) is not str or _ID.fullmatch(worker) is None or type(count) is not int \
            or not 1 <= count <= MAX_LEASE_RUNS:
        return None
    return worker, count
