"""The checks behind the job specs' validation: problems located inside a field
(:class:`FieldProblems`), bounded parameter numbers, unknown and repeated names, the runs
limit, inline scenarios read by the world layer."""

from __future__ import annotations

import importlib
import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from pydantic import (
    ValidationInfo,
)

from swarmpath.service.model import (
    MAX_RUNS_PER_JOB,
)

# ------------------------------------------------------------------------------------ validation
Loc = tuple[str | int, ...]


class FieldProblems(ValueError):
    """Problems inside one field, each at its own place: ``(location below the field,
    message)``. The REST error handler (:mod:`swarmpath.service.errors`) gives each its own
    detail item, so that ``loc`` reaches the field (``maps.0.obstacles.2.radius``)."""

    def __init__(self, problems: Sequence[tuple[Loc, str]]):
        self.problems = list(problems)
        super().__init__("; ".join(
            f"{'.'.join(str(p) for p in loc)}: {msg}" if loc else msg for loc, msg in problems))


#: Parameter numbers: integers within 64 bits, floats finite (anything else would only fail later,
#: inside numpy, with numpy's words).
INT64 = 2**63


def _bounded_numbers(value: Any) -> Any:
    """Every number inside job parameters, checked before the parameters' own validation:
    integers within +-2**63, floats finite; each problem at its place (``GWO.a_max``)."""
    problems: list[tuple[Loc, str]] = []
    todo: list[tuple[Loc, Any]] = [((), value)]
    while todo and len(problems) < 20:
        loc, v = todo.pop()
        if isinstance(v, bool) or v is None or isinstance(v, str):
            continue
        if isinstance(v, int):
            if not -INT64 <= v < INT64:
                digits = len(str(abs(v))) if abs(v) < 10**4300 else 4300
                problems.append((loc, f"an integer of {digits} digits is out of range "
                                      f"(parameters are 64-bit: |value| < 9.22e18)"))
        elif isinstance(v, float):
            if not math.isfinite(v):
                problems.append((loc, f"must be a finite number, got {v}"))
        elif isinstance(v, dict):
            if len(loc) < 8:
                todo += [((*loc, k), x) for k, x in v.items()]
        elif isinstance(v, list | tuple) and len(loc) < 8:
            todo += [((*loc, i), x) for i, x in enumerate(v)]
    if problems:
        raise FieldProblems(problems)
    return value


def _scenario_loc(path: str) -> Loc:
    """``obstacles[2].radius`` (the world layer's paths) -> ``('obstacles', 2, 'radius')``."""
    parts: list[str | int] = []
    for token in re.findall(r"\[(\d+)\]|([^.\[\]]+)", path):
        parts.append(int(token[0]) if token[0] else token[1])
    return tuple(parts)


def _unknown_names(v: Sequence[str], valid: Sequence[str], kind: str) -> None:
    from swarmpath.names import unknown

    problems: list[tuple[Loc, str]] = [
        ((i,), unknown(kind, name, valid)) for i, name in enumerate(v) if name not in valid
    ]
    if problems:
        raise FieldProblems(problems)


def _unique(values: Sequence[Any], what: str) -> None:
    seen: set[Any] = set()
    for v in values:
        key = json.dumps(v, sort_keys=True) if isinstance(v, dict) else v
        if key in seen:
            raise ValueError(f"duplicate {what} {v!r}")
        seen.add(key)


def _check_total(info: ValidationInfo, runs: int, axes: Sequence[str]) -> int:
    """The 1,000,000-runs-per-job limit, raised on ``runs`` (a field the user can change)."""
    sizes = []
    for axis in axes:
        value = info.data.get(axis)
        if value is None:  # that field failed its own validation: its error is reported already
            return runs
        sizes.append(len(value))
    total = runs * math.prod(sizes)
    if total > MAX_RUNS_PER_JOB:
        shape = " x ".join(f"{n} {axis}" for n, axis in zip(sizes, axes, strict=True))
        raise ValueError(
            f"{shape} x {runs} runs = {total} runs; a job may have at most {MAX_RUNS_PER_JOB}"
        )
    return runs


def _planner_registry() -> Any:
    """``swarmpath.planners``, imported on first use (it pulls in the whole planning stack)."""
    return importlib.import_module("swarmpath.planners")


def _map_names() -> list[str]:
    from swarmpath.world.presets import list_maps

    return list(list_maps())


def _inline_scenario_problems(scenario: Mapping[str, Any]) -> list[tuple[Loc, str]]:
    """Full validation of an inline scenario by the world layer's JSON reader: each problem at
    its place inside the scenario."""
    from swarmpath.world.scenario_io import ScenarioError, scenario_from_dict

    try:
        scenario_from_dict(dict(scenario))
    except ScenarioError as exc:
        return [(_scenario_loc(path), msg) for path, msg in exc.problems]
    except (ValueError, TypeError, KeyError) as exc:
        return [((), str(exc))]
    return []


def _reference(v: str | None, members: list[str] | None) -> str | None:
    """A reference among the job's members (case-insensitive, stored as registered)."""
    if v is None or members is None:  # no reference, or the members failed their validation
        return v
    from swarmpath.evidence.stats import resolve_reference

    return resolve_reference(members, v)


def _params_of_members(
    v: dict[str, Any], members: list[str] | None, what: str, resolve: Callable[[str, Any], Any]
) -> dict[str, Any]:
    """Per-member parameters: only for the job's own members, each accepted by its resolver."""
    from swarmpath.names import did_you_mean

    if members is None:  # the member list itself failed validation: that error is reported
        return v
    problems: list[tuple[Loc, str]] = []
    for name, params in v.items():
        if name not in members:
            problems.append(((name,), f"not one of the job's {what}{did_you_mean(name, members)}"
                             f" ({', '.join(members)})"))
            continue
        keyed = False
        for key, value in params.items():  # each parameter on its own: loc params.NAME.KEY
            try:
                resolve(name, {key: value})
            except (ValueError, TypeError, KeyError, ArithmeticError) as exc:
                problems.append(((name, key), str(exc.args[0]) if exc.args else str(exc)))
                keyed = True
        if not keyed:  # then together (a rule across parameters)
            try:
                resolve(name, params)
            except (ValueError, TypeError, KeyError, ArithmeticError) as exc:
                problems.append(((name,), str(exc.args[0]) if exc.args else str(exc)))
    if problems:
        raise FieldProblems(problems)
    return v
