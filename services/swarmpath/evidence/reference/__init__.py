"""The seed papers' result tables as data, and the reviewed reasons for cells that differ.

Each reproducible table is one YAML file in this package (transcribed by hand from the seed
texts; see each file's ``source`` and ``notes``). A benchmark table holds, per function and
algorithm, the printed ``[min, max, avg, std]``; a map table holds, per planner and map, the
printed runs and mean row. A value the seed text does not let us read is ``illegible`` and loads
as ``None``.

``reasons.yaml`` maps a cell key -- ``<table>/<algorithm>/<function>/<dim>`` for benchmark
tables, ``<table>/<planner>/<map>`` for map tables -- to ``{direction, reason, evidence}`` and
optionally ``exceedance``: the verdict the reason explains (``better``, ``worse`` or ``not
comparable``), why the measured value differs from the published one in that direction, the
command that shows the cause, and for a tail the runs beyond the published range it explains
(``none``, ``above``, ``below``). ``same_as: <key>`` takes another cell's reason (a column a
paper copied from another). A benchmark table's ``derived`` names columns that are not
measurements (e.g. a scaled copy of another column), with the evidence.

Pure: reads package data only (no network, no global state besides the read-only files).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

import yaml

#: The reproducible tables, in the order ``swarmpath reproduce --list`` names them.
TABLES: tuple[str, ...] = (
    "icoot-table2",
    "icoot-table3",
    "icoot-table4",
    "ihpo-table2",
    "icoot-maps",
    "ihpo-maps",
    "rfogwo-maps",
    "mfb-maps",
    "jso-cec2017-d10",
    "jso-cec2017-d30",
    "cmaes-pycma-bbob-d5",
    "lshade-reference-cec2017-d10",
)
ILLEGIBLE = "illegible"
REASONS_FILE = "reasons.yaml"


class ReferenceError(ValueError):
    """A malformed reference file (names the file and the entry)."""


@dataclass(frozen=True)
class BenchmarkTable:
    name: str
    source: dict[str, Any]
    setting: dict[str, Any]
    algorithms: tuple[str, ...]
    functions: tuple[str, ...]
    stats: tuple[str, ...]
    notes: tuple[str, ...]
    cell_notes: dict[str, str]
    #: (function, algorithm) -> {stat: value or None when illegible}
    cells: dict[tuple[str, str], dict[str, float | None]]
    kind: str = "benchmark"
    #: algorithm -> why its published column is not a measurement (its cells: not comparable)
    derived: dict[str, str] = field(default_factory=dict)
    #: "function/algorithm" -> how the print contradicts itself where the legible values alone
    #: do not show it (e.g. both readings of an illegible min exceed the avg)
    contradicts: dict[str, str] = field(default_factory=dict)

    @property
    def dim(self) -> int:
        (d,) = self.setting["dims"]
        return int(d)

    def cell_keys(self) -> list[str]:
        return [
            cell_key(self.name, a, f, self.dim) for f in self.functions for a in self.algorithms
        ]

    def note_for(self, function: str, algorithm: str) -> str | None:
        return self.cell_notes.get(f"{function}/{algorithm}")


@dataclass(frozen=True)
class MapCell:
    planner: str
    map: str
    #: column -> the printed runs (empty when only a mean is printed)
    runs: dict[str, list[float]] = field(default_factory=dict)
    #: column -> the printed mean (the mean of the runs when the table prints none)
    mean: dict[str, float] = field(default_factory=dict)
    printed_mean: bool = True


@dataclass(frozen=True)
class MapTable:
    name: str
    source: dict[str, Any]
    setting: dict[str, Any]
    columns: dict[str, str]
    compare: str
    notes: tuple[str, ...]
    cells: dict[tuple[str, str], MapCell]
    extra: dict[str, Any] = field(default_factory=dict)
    kind: str = "map"

    @property
    def planners(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(p for p, _ in self.cells))

    @property
    def maps(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(m for _, m in self.cells))

    def cell_keys(self) -> list[str]:
        return [cell_key(self.name, p, m) for p, m in self.cells]


Table = BenchmarkTable | MapTable


DIRECTIONS = ("better", "worse", "not comparable")
EXCEEDANCES = ("none", "above", "below")


@dataclass(frozen=True)
class Reason:
    """A reviewed reason: the verdict it explains (``direction``), the text, the command that
    shows the cause, and optionally the exceedance it explains (``none``: no departure from the
    published range; ``above``/``below``: runs beyond the published max/min)."""

    reason: str
    evidence: str
    direction: str
    exceedance: str | None = None


def cell_key(table: str, who: str, where: str, dim: int | None = None) -> str:
    """``icoot-table2/PSO/F2/30`` (benchmark) or ``icoot-maps/ICOOT/icoot-map1`` (map)."""
    return f"{table}/{who}/{where}" if dim is None else f"{table}/{who}/{where}/{dim}"


def _read(filename: str) -> Any:
    text = resources.files(__name__).joinpath(filename).read_text(encoding="utf-8")
    return yaml.safe_load(text)


def _value(raw: Any, where: str) -> float | None:
    if raw == ILLEGIBLE:
        return None
    if isinstance(raw, bool) or not isinstance(raw, int | float):
        raise ReferenceError(f"{where}: {raw!r} is neither a number nor {ILLEGIBLE!r}")
    value = float(raw)
    if not math.isfinite(value):
        raise ReferenceError(f"{where}: {raw!r} is not finite")
    return value


def _benchmark(name: str, doc: dict[str, Any]) -> BenchmarkTable:
    stats = tuple(doc["stats"])
    algorithms = tuple(doc["algorithms"])
    cells: dict[tuple[str, str], dict[str, float | None]] = {}
    for function, row in doc["cells"].items():
        if tuple(row) != algorithms:
            raise ReferenceError(f"{name}.yaml: {function}: algorithms {list(row)} != {algorithms}")
        for algorithm, values in row.items():
            where = f"{name}.yaml: {function}/{algorithm}"
            if not isinstance(values, list) or len(values) != len(stats):
                raise ReferenceError(f"{where}: expected {len(stats)} values {list(stats)}")
            cells[(function, algorithm)] = {
                s: _value(v, f"{where}/{s}") for s, v in zip(stats, values, strict=True)
            }
    derived = {str(k): " ".join(str(v).split()) for k, v in (doc.get("derived") or {}).items()}
    for algorithm in derived:
        if algorithm not in algorithms:
            raise ReferenceError(f"{name}.yaml: derived: {algorithm!r} is not a column")
    contradicts = {str(k): " ".join(str(v).split())
                   for k, v in (doc.get("contradicts") or {}).items()}
    for key in contradicts:
        if tuple(key.split("/")) not in cells:
            raise ReferenceError(f"{name}.yaml: contradicts: {key!r} is not a cell")
    return BenchmarkTable(
        name=name, source=doc["source"], setting=doc["setting"], algorithms=algorithms,
        functions=tuple(doc["cells"]), stats=stats, notes=_notes(name, doc),
        cell_notes=dict(doc.get("cell_notes") or {}), cells=cells, derived=derived,
        contradicts=contradicts,
    )


def _map(name: str, doc: dict[str, Any]) -> MapTable:
    columns = dict(doc["columns"])
    cells: dict[tuple[str, str], MapCell] = {}
    for key, entry in doc["cells"].items():
        planner, _, map_name = str(key).partition("/")
        where = f"{name}.yaml: {key}"
        clean: dict[str, list[float]] = {}
        for c, raw in (entry.get("runs") or {}).items():
            values = [_value(v, f"{where}/{c}") for v in raw]
            if c not in columns:
                raise ReferenceError(f"{where}: unknown column {c!r}")
            clean[c] = [v for v in values if v is not None]
            if len(clean[c]) != len(values):
                raise ReferenceError(f"{where}: an illegible run of {c!r}")
        printed = "mean" in entry
        if printed:
            mean = {c: float(v) for c, v in entry["mean"].items() if _value(v, where) is not None}
        else:
            mean = {c: sum(vs) / len(vs) for c, vs in clean.items()}
        if doc["compare"] not in mean:
            raise ReferenceError(f"{where}: no {doc['compare']!r} value")
        cells[(planner, map_name)] = MapCell(planner, map_name, clean, mean, printed)
    extra = {k: v for k, v in doc.items() if k not in {
        "table", "kind", "source", "setting", "columns", "compare", "notes", "cells"}}
    return MapTable(
        name=name, source=doc["source"], setting=doc["setting"], columns=columns,
        compare=doc["compare"], notes=_notes(name, doc), cells=cells, extra=extra,
    )


def _notes(name: str, doc: dict[str, Any]) -> tuple[str, ...]:
    notes = doc.get("notes") or []
    if not all(isinstance(n, str) for n in notes):
        raise ReferenceError(f"{name}.yaml: every note must be a string (quote it)")
    return tuple(notes)


def load(name: str) -> Table:
    """The table ``name`` (one of :data:`TABLES`); KeyError naming the valid ones otherwise."""
    if name not in TABLES:
        raise KeyError(f"unknown table {name!r}; reproducible: {', '.join(TABLES)}")
    doc = _read(f"{name}.yaml")
    if doc.get("table") != name:
        raise ReferenceError(f"{name}.yaml: 'table' is {doc.get('table')!r}")
    if doc["kind"] == "benchmark":
        return _benchmark(name, doc)
    if doc["kind"] == "map":
        return _map(name, doc)
    raise ReferenceError(f"{name}.yaml: unknown kind {doc['kind']!r}")


def list_tables() -> list[str]:
    return list(TABLES)


def load_reasons() -> dict[str, Reason]:
    """Every entry of ``reasons.yaml``, ``same_as`` resolved (ReferenceError on a malformed
    entry)."""
    doc = _read(REASONS_FILE) or {}
    if not isinstance(doc, dict):
        raise ReferenceError(f"{REASONS_FILE}: expected a mapping of cell keys")
    out: dict[str, Reason] = {}
    for key, entry in doc.items():
        out[str(key)] = _reason(str(key), entry, doc)
    return out


def _reason(key: str, entry: Any, doc: dict[str, Any]) -> Reason:
    where = f"{REASONS_FILE}: {key}"
    if isinstance(entry, dict) and set(entry) == {"same_as"}:
        target = entry["same_as"]
        other = doc.get(target)
        if not isinstance(other, dict) or "same_as" in other:
            raise ReferenceError(f"{where}: same_as {target!r} is not a reason of its own")
        return _reason(str(target), other, doc)
    fields = {"direction", "reason", "evidence"}
    if not isinstance(entry, dict) or not fields <= set(entry) <= fields | {"exceedance"}:
        raise ReferenceError(f"{where}: expected direction, reason, evidence (and optionally "
                             "exceedance), or same_as")
    for name in ("reason", "evidence"):
        if not (isinstance(entry[name], str) and entry[name].strip()):
            raise ReferenceError(f"{where}: empty {name}")
    if entry["direction"] not in DIRECTIONS:
        raise ReferenceError(f"{where}: direction {entry['direction']!r} is not one of "
                             f"{', '.join(DIRECTIONS)}")
    exceedance = entry.get("exceedance")
    if exceedance is not None and exceedance not in EXCEEDANCES:
        raise ReferenceError(f"{where}: exceedance {exceedance!r} is not one of "
                             f"{', '.join(EXCEEDANCES)}")
    return Reason(" ".join(entry["reason"].split()), " ".join(entry["evidence"].split()),
                  entry["direction"], exceedance)


def all_cell_keys() -> set[str]:
    """The key of every cell of every table (what a reason may be attached to)."""
    return {k for name in TABLES for k in load(name).cell_keys()}
