"""MovingAI scenario files (``.scen``): start/goal pairs of a grid map with their difficulty
bucket and octile optimum, and the choice of some of them (by row or by bucket).

One reader for ``swarmpath plan --scen`` and for ``.scen`` files uploaded with a map to the
service. Rows (Sturtevant 2012, "Benchmarks for Grid-Based Pathfinding", IEEE TCIAIG 4(2)):
``bucket  map  width  height  start-x  start-y  goal-x  goal-y  optimal-length``, tab- or
blank-separated, after a ``version 1`` line; cells count from the top-left corner (x right, y
down), as :func:`swarmpath.world.movingai.movingai_cell_center` converts them. Errors are
:class:`ScenError` (with the 1-based line) and :class:`ScenChoiceError` (naming the choice's
field and index); the callers say which option or body field they concern.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

#: Rows read from one ``.scen`` (the MovingAI sets have at most a few thousand per map).
MAX_SCEN_ROWS = 100_000
#: The highest bucket read (bucket b holds octile lengths in [4b, 4b + 4): 100,000 is a path of
#: 400,000 cells, more than any grid within the importer's cell limit).
MAX_BUCKET = 100_000


@dataclass(frozen=True)
class ScenRow:
    """One pair: its 0-based row in the file, bucket, start and goal cells (x, y from the top
    left) and octile optimal length (cells)."""

    row: int
    bucket: int
    start: tuple[int, int]
    goal: tuple[int, int]
    octile: float


class ScenError(ValueError):
    """A ``.scen`` that cannot be read; the message names the file and line."""


class ScenLimitError(ScenError):
    """A ``.scen`` over :data:`MAX_SCEN_ROWS`."""


class ScenChoiceError(ValueError):
    """A choice of rows that the file does not have: ``field`` (``rows`` / ``buckets`` /
    ``per_bucket``) and the index in that list (None for the whole field)."""

    def __init__(self, field: str, index: int | None, message: str):
        super().__init__(message)
        self.field = field
        self.index = index


def parse_scen(text: str, source: str = "<scen>", shape: tuple[int, int] | None = None,
               max_rows: int = MAX_SCEN_ROWS) -> list[ScenRow]:
    """Every pair of a ``.scen`` text; with ``shape`` (the map's width, height in cells) a row
    stated for another size, or whose cells lie outside it, is refused."""
    lines = text.splitlines()
    if not lines or not lines[0].lower().startswith("version"):
        raise ScenError(f"{source}: first line must be 'version 1' (a MovingAI .scen)")
    rows: list[ScenRow] = []
    for k, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        if len(rows) >= max_rows:
            raise ScenLimitError(f"{source}: more than {max_rows:,} pairs (at most "
                                 f"{max_rows:,} are read from one .scen)")
        line = line.strip()
        cols = line.split("\t") if "\t" in line else line.split()
        try:
            if len(cols) < 9:
                raise ValueError
            bucket = int(cols[0])
            width, height, sx, sy, gx, gy = (int(c) for c in cols[2:8])
            octile = float(cols[8])
        except ValueError:
            raise ScenError(f"{source}: line {k}: expected 9 columns (bucket map width height "
                            "sx sy gx gy length), the bucket and the cells integers") from None
        if not 0 <= bucket <= MAX_BUCKET:
            raise ScenError(f"{source}: line {k}: bucket {bucket} is not in 0-{MAX_BUCKET:,}")
        if not (math.isfinite(octile) and octile >= 0):
            raise ScenError(f"{source}: line {k}: the optimal length must be a finite number "
                            ">= 0")
        if shape is not None:
            if (width, height) != tuple(shape):
                raise ScenError(f"{source}: line {k}: a pair of a {width} x {height} map "
                                f"({cols[1][:100]}), but the map is {shape[0]} x {shape[1]}")
            if not all(0 <= x < width and 0 <= y < height for x, y in ((sx, sy), (gx, gy))):
                raise ScenError(f"{source}: line {k}: a cell outside the {width} x {height} "
                                "grid")
        rows.append(ScenRow(len(rows), bucket, (sx, sy), (gx, gy), octile))
    return rows


def choose_rows(rows: Sequence[ScenRow], ids: Sequence[int] | None = None,
                buckets: Sequence[int] | None = None, per_bucket: int = 1) -> list[ScenRow]:
    """The pairs chosen by row (``ids``, 0 = the first pair, in the order given) or by bucket
    (the first ``per_bucket`` pairs of each bucket in ``buckets``, in file order; a bucket with
    fewer pairs gives all it has, one with none is an error)."""
    if ids is not None:
        out = []
        for k, i in enumerate(ids):
            if not 0 <= i < len(rows):
                raise ScenChoiceError("rows", k, f"{i} is beyond the {len(rows)} pairs of the "
                                      ".scen (0 = first)")
            out.append(rows[i])
        return out
    if buckets is None:
        return list(rows)
    if per_bucket < 1:
        raise ScenChoiceError("per_bucket", None, "must be >= 1")
    taken: dict[int, list[ScenRow]] = {b: [] for b in buckets}
    for r in rows:
        chosen = taken.get(r.bucket)
        if chosen is not None and len(chosen) < per_bucket:
            chosen.append(r)
    have = sorted({r.bucket for r in rows})
    for k, b in enumerate(buckets):
        if not taken[b]:
            raise ScenChoiceError("buckets", k, f"the .scen has no pair in bucket {b} (its "
                                  f"buckets: {_spans(have)})")
    return [r for b in dict.fromkeys(buckets) for r in taken[b]]


def bucket_counts(rows: Sequence[ScenRow]) -> dict[int, int]:
    """Pairs per bucket, buckets ascending."""
    counts: dict[int, int] = {}
    for r in rows:
        counts[r.bucket] = counts.get(r.bucket, 0) + 1
    return dict(sorted(counts.items()))


def _spans(values: Sequence[int]) -> str:
    """``0-15, 20`` for sorted integers (short even for a thousand buckets)."""
    if not values:
        return "none"
    parts: list[str] = []
    start = prev = values[0]
    for v in [*values[1:], None]:
        if v is not None and v == prev + 1:
            prev = v
            continue
        parts.append(str(start) if start == prev else f"{start}-{prev}")
        if v is not None:
            start = prev = v
    return ", ".join(parts)
