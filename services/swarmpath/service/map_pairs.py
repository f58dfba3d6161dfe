"""MovingAI pairs of an uploaded map: the ``.scen`` sent with ``POST /maps`` (read by
:mod:`swarmpath.world.movingai_scen`, as ``swarmpath plan --scen`` reads it) and the
expansion of a job's ``{"map": id, "scen": {...}}`` into one map per pair with its bucket.

Plain functions (no HTTP). :func:`scen_rows` runs in the bounded import process (the coordinator
never parses an upload); :func:`expand_pairs` runs on ``POST /jobs`` over the rows stored then.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from swarmpath.service.jobspec_map import MapRef
from swarmpath.service.model import MAX_SCENARIO_BYTES
from swarmpath.service.spec_checks import Loc
from swarmpath.world.movingai_scen import ScenChoiceError, ScenRow, choose_rows, parse_scen


def scen_rows(text: str, name: str, scenario: dict[str, Any], resolution: float
              ) -> dict[str, Any]:
    """What the store keeps of an uploaded ``.scen``: the grid's ``width``, ``height`` (cells)
    and ``resolution`` (m) and ``rows`` ``[bucket, sx, sy, gx, gy, octile]`` in file order.
    Raises :class:`~swarmpath.world.movingai_scen.ScenError` (a row stated for another size, a
    cell outside the grid, more than MAX_SCEN_ROWS rows: ``ScenLimitError``)."""
    width = round(float(scenario["size"][0]) / resolution)
    height = round(float(scenario["size"][1]) / resolution)
    rows = parse_scen(text, f"{name}.scen", (width, height))
    return {"width": width, "height": height, "resolution": resolution,
            "rows": [[r.bucket, *r.start, *r.goal, r.octile] for r in rows]}


def scen_info(pairs: dict[str, Any] | None) -> dict[str, Any] | None:
    """``GET /maps``' view of a map's stored pairs: how many, and how many per bucket."""
    if pairs is None:
        return None
    counts: dict[int, int] = {}
    for row in pairs["rows"]:
        counts[int(row[0])] = counts.get(int(row[0]), 0) + 1
    return {"pairs": len(pairs["rows"]),
            "buckets": {str(b): n for b, n in sorted(counts.items())}}


def _rows(pairs: dict[str, Any]) -> list[ScenRow]:
    return [ScenRow(k, int(b), (int(sx), int(sy)), (int(gx), int(gy)), float(length))
            for k, (b, sx, sy, gx, gy, length) in enumerate(pairs["rows"])]


def expand_pairs(entry: MapRef, stored: dict[str, Any], pairs: dict[str, Any] | None,
                 name: str, doc: dict[str, Any]
                 ) -> tuple[list[dict[str, Any]], dict[str, int], dict[str, float],
                            list[tuple[Loc, str]]]:
    """The maps of ``entry``'s ``scen`` choice: copies of ``doc`` (the uploaded map's
    scenario as the job names it) named ``NAME#row``, start and goal at the pair's cell
    centres, with each map's bucket and octile optimum (m) by name; problems located below
    the entry (``scen.rows.2``, ``scen.buckets.0``, ``scen``)."""
    from swarmpath.world.importers import movingai_cell_center
    from swarmpath.world.scenario import scenario_problems
    from swarmpath.world.scenario_io import ScenarioError, scenario_from_dict

    choice = entry.scen
    assert choice is not None
    if pairs is None:
        return [], {}, {}, [(("scen",), f"map {entry.map} was uploaded without a .scen "
                             "(POST /maps with 'scen': the .scen text)")]
    try:
        chosen = choose_rows(_rows(pairs), choice.rows, choice.buckets, choice.per_bucket)
    except ScenChoiceError as exc:
        loc: Loc = ("scen", exc.field) if exc.index is None else ("scen", exc.field, exc.index)
        return [], {}, {}, [(loc, str(exc))]
    size = len(json.dumps(stored))
    if size * len(chosen) > MAX_SCENARIO_BYTES:  # every pair is a copy of the map in the job
        return [], {}, {}, [(("scen",), f"{len(chosen)} pairs of a {size:,}-byte map are "
                             f"{size * len(chosen):,} bytes of maps, over "
                             f"MAX_SCENARIO_BYTES={MAX_SCENARIO_BYTES:,}: choose fewer pairs")]
    height, res = int(pairs["height"]), float(pairs["resolution"])
    docs: list[dict[str, Any]] = []
    buckets: dict[str, int] = {}
    octile: dict[str, float] = {}
    problems: list[tuple[Loc, str]] = []
    field = "rows" if choice.rows is not None else "buckets"
    for r in chosen:
        pair = dict(doc, name=f"{name}#{r.row}",
                    start=list(movingai_cell_center(*r.start, height, res)),
                    goal=list(movingai_cell_center(*r.goal, height, res)),
                    description=f"{doc.get('description', '')}; .scen row {r.row}, bucket "
                    f"{r.bucket}")
        try:
            found = scenario_problems(scenario_from_dict(pair))
        except ScenarioError as exc:
            found = list(exc.problems)
        at: Loc = ("scen", field, _index(choice.rows, choice.buckets, r))
        problems += [(at, f"row {r.row}: {f}: {m}") for f, m in found if f in ("start", "goal")]
        docs.append(pair)
        buckets[pair["name"]] = r.bucket
        if r.octile > 0:
            octile[pair["name"]] = r.octile * res
    return docs, buckets, octile, problems


def _index(rows: Sequence[int] | None, buckets: Sequence[int] | None, r: ScenRow) -> int:
    """Where in the choice a pair came from: its place in ``rows``, or its bucket's in
    ``buckets``."""
    if rows is not None:
        return list(rows).index(r.row)
    assert buckets is not None
    return list(buckets).index(r.bucket)
