"""Notes that explain a map cell's numbers: why its exact optimum gave up (a blank gap), and
stated trajectories of moving goals or obstacles that cross a static obstacle.

The worker, which builds the cell's scenario anyway, finds both once per lease (the optimum is
remembered per scenario and budget, :func:`swarmpath.planners.episode.optimum_of`; the
trajectory check, :func:`swarmpath.world.trajectories.trajectory_warnings`, 0.2-0.5 s, once per
scenario in :func:`scenario_warnings`) and puts them in each run's ``metrics`` as plain strings
(:func:`note_metrics`): ``optimum_reason`` only when the run has no optimum, and
``warning:<field>`` (``goal_motion`` or ``obstacles[k]``) per mover, so nothing is added to a run
whose optimum was found on a map without such movers. The run outcome itself
(:class:`~swarmpath.planners.episode.RunOutcome`, hashed by ``scripts/bench/plan_time.py``) is
not changed.

The coordinator stores the metrics as they come and trusts none of it: :func:`cell_notes`
reads a cell's runs back into a :class:`CellNotes` (the schema in
``schemas/cell_notes.schema.json``), keeping only strings, a known field name, at most
:data:`MAX_NOTE_CHARS` characters each and :data:`MAX_WARNINGS` warnings per map. Pure functions
(besides the worker's small cache), no I/O.
"""

from __future__ import annotations

import re
import threading
from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from pydantic import Field

from swarmpath.service.model import Model

#: a note's text is cut to this many characters (worker) and refused beyond it (coordinator)
MAX_NOTE_CHARS = 300
#: warnings kept per map (movers beyond it are left out), and per job summary
MAX_WARNINGS = 8
MAX_JOB_WARNINGS = 100
OPTIMUM_REASON = "optimum_reason"
WARNING_PREFIX = "warning:"
_FIELD = re.compile(r"(goal_motion|obstacles\[\d{1,7}\])")
_KEPT_SCENARIOS = 16  # scenarios whose warnings a worker process remembers


class TrajectoryWarning(Model):
    """A moving goal or obstacle whose stated path meets a static obstacle."""

    field: str = Field(max_length=48,
                       pattern=r"^maps\[\d{1,7}\]\.(goal_motion|obstacles\[\d{1,7}\])$",
                       description="the job spec's field: maps[i].goal_motion or "
                       "maps[i].obstacles[k]")
    map: str = Field(max_length=256, description="the map's name")
    message: str = Field(max_length=MAX_NOTE_CHARS)


class CellNotes(Model):
    """What a map cell's runs said about their map (``optimum_reason`` in the summary's map rows,
    ``warnings`` in its ``warnings``)."""

    optimum_reason: str | None = Field(
        default=None, max_length=MAX_NOTE_CHARS,
        description="why the cell has no exact optimum (so no gap): the time budget ran out "
        "(with its value), moving obstacles or goal, no path, ...; null when it has one")
    warnings: list[TrajectoryWarning] = Field(default_factory=list, max_length=MAX_WARNINGS)


def _clip(text: str) -> str:
    return text if len(text) <= MAX_NOTE_CHARS else text[:MAX_NOTE_CHARS - 3] + "..."


# ---------------------------------------------------------------------------------- worker side
def note_metrics(optimum_reason: str | None,
                 warnings: Sequence[tuple[str, str]]) -> dict[str, str]:
    """The metric entries of one run: ``optimum_reason`` (when given) and ``warning:<field>`` for
    the first MAX_WARNINGS warnings, each text cut to MAX_NOTE_CHARS."""
    out: dict[str, str] = {}
    if optimum_reason:
        out[OPTIMUM_REASON] = _clip(optimum_reason)
    for field, message in warnings:
        if len(out) - (OPTIMUM_REASON in out) >= MAX_WARNINGS:
            break
        if _FIELD.fullmatch(field):
            out[WARNING_PREFIX + field] = _clip(message)
    return out


_WARNINGS: OrderedDict[Any, list[tuple[str, str]]] = OrderedDict()
_LOCK = threading.Lock()


def scenario_warnings(scenario: Any) -> list[tuple[str, str]]:
    """:func:`~swarmpath.world.trajectories.trajectory_warnings` of a scenario, remembered for the
    last few scenarios of this process (a cell's leases share it). A check that fails warns of
    nothing (the run reports its own errors)."""
    with _LOCK:  # thread slots share the process
        found = _WARNINGS.get(scenario)
        if found is not None:
            _WARNINGS.move_to_end(scenario)
            return found
    from swarmpath.world.trajectories import trajectory_warnings

    try:
        found = trajectory_warnings(scenario)
    except Exception:
        found = []
    with _LOCK:
        _WARNINGS[scenario] = found
        while len(_WARNINGS) > _KEPT_SCENARIOS:
            _WARNINGS.popitem(last=False)
    return found


# ----------------------------------------------------------------------------- coordinator side
def cell_notes(runs: Iterable[Mapping[str, Any]], map_index: int | None,
               map_name: str) -> CellNotes:
    """The notes of one cell from its runs' metrics (as stored: untrusted). The first valid
    ``optimum_reason`` in run order; each valid ``warning:<field>`` once, named in the job spec
    as ``maps[map_index].<field>`` (no warnings without a map index)."""
    reason: str | None = None
    warnings: dict[str, str] = {}
    for m in runs:
        for key, value in m.items():
            if type(value) is not str or not value or len(value) > MAX_NOTE_CHARS:
                continue
            if key == OPTIMUM_REASON:
                if reason is None:
                    reason = value
            elif key.startswith(WARNING_PREFIX) and map_index is not None \
                    and len(warnings) < MAX_WARNINGS:
                field = key[len(WARNING_PREFIX):]
                if _FIELD.fullmatch(field) and field not in warnings:
                    warnings[field] = value
    return CellNotes(
        optimum_reason=reason,
        warnings=[TrajectoryWarning(field=f"maps[{map_index}].{f}", map=map_name[:256],
                                    message=msg) for f, msg in sorted(warnings.items())],
    )


def job_warnings(cells: Iterable[CellNotes]) -> list[dict[str, Any]]:
    """The warnings of a job's cells, each field once (every planner on a map shares them), at
    most MAX_JOB_WARNINGS."""
    seen: dict[str, dict[str, Any]] = {}
    for notes in cells:
        for w in notes.warnings:
            if len(seen) < MAX_JOB_WARNINGS:
                seen.setdefault(w.field, w.model_dump())
    return list(seen.values())


def note_lines(summary: Mapping[str, Any]) -> list[str]:
    """A map summary's notes as text lines (``swarmpath results`` prints them under the table):
    each map's reason for having no exact optimum once, then each warning."""
    lines: list[str] = []
    seen: set[str] = set()
    for row in summary.get("rows") or ():
        reason, name = row.get("optimum_reason"), str(row.get("map"))
        if isinstance(reason, str) and name not in seen:
            seen.add(name)
            lines.append(f"no exact optimum on {name} (blank gap): {reason}")
    for w in summary.get("warnings") or ():
        lines.append(f"warning: {w.get('field')} ({w.get('map')}): {w.get('message')}")
    return lines
