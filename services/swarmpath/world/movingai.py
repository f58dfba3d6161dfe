"""Import of MovingAI benchmark grids (``.map``) into an :class:`ImportedMap` (frames, defaults
and limits: :mod:`swarmpath.world.importers`)."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from swarmpath.world.grid_import import (
    ENDPOINT_MARGIN,
    MAX_CELLS,
    MAX_OBSTACLES,
    ImportedMap,
    MapImportError,
    MapLimitError,
    _build,
)
from swarmpath.world.raster import FREE, OCCUPIED
from swarmpath.world.scenario import (
    MAX_METRES,
    RobotSpec,
)

MOVINGAI_PASSABLE = frozenset(".GS")
MOVINGAI_BLOCKED = frozenset("@OTW")
_MOVINGAI_KIND = np.full(256, 2, dtype=np.int8)  # byte -> 0 passable, 1 blocked, 2 unknown
_MOVINGAI_KIND[[ord(ch) for ch in MOVINGAI_PASSABLE]] = 0
_MOVINGAI_KIND[[ord(ch) for ch in MOVINGAI_BLOCKED]] = 1


def parse_movingai_map(
    text: str, source: str = "<map>", max_cells: int = MAX_CELLS
) -> NDArray[np.bool_]:
    """Blocked mask of a MovingAI ``.map`` in *text* order (row 0 = top line of the grid)."""
    lines = text.splitlines()
    header: dict[str, str] = {}
    i = 0
    while i < len(lines):
        line = lines[i].strip()
        i += 1
        if not line:
            continue
        if line.lower() == "map":
            break
        key, _, value = line.partition(" ")
        header[key.lower()] = value.strip()
    else:
        raise MapImportError(f"{source}: missing the 'map' line before the grid")
    for key in ("type", "height", "width"):
        if key not in header:
            raise MapImportError(f"{source}: header: '{key}' line required")
    try:
        height, width = int(header["height"]), int(header["width"])
    except ValueError:
        raise MapImportError(f"{source}: header: height and width must be integers") from None
    if height < 1 or width < 1:
        raise MapImportError(f"{source}: header: height and width must be >= 1")
    if height * width > max_cells:
        raise MapLimitError(
            f"{source}: {width} x {height} = {height * width:,} cells exceed "
            f"max_cells={max_cells:,} (raise it with max_cells= / --max-cells)"
        )
    grid = [ln.rstrip() for ln in lines[i : i + height]]  # trailing blanks are no terrain
    if len(grid) < height:
        raise MapImportError(
            f"{source}: the header says height {height} but the grid has {len(grid)} lines")
    for r, row in enumerate(grid):
        if len(row) != width:
            raise MapImportError(
                f"{source}: line {i + r + 1}: {len(row)} characters, but the header says "
                f"width {width}: the header and the grid disagree"
            )
    extra = next((k for k in range(i + height, len(lines)) if lines[k].strip()), None)
    if extra is not None:
        raise MapImportError(
            f"{source}: line {extra + 1}: more grid lines than the header's height {height}: "
            "the header and the grid disagree"
        )
    raw = "".join(grid).encode("utf-8", errors="replace")
    codes = np.frombuffer(raw, dtype=np.uint8)
    if len(codes) != height * width:  # a multi-byte character somewhere: find it
        for r, row in enumerate(grid):
            for c, ch in enumerate(row):
                if ch not in MOVINGAI_BLOCKED and ch not in MOVINGAI_PASSABLE:
                    raise MapImportError(
                        f"{source}: line {i + r + 1}, column {c + 1}: unknown terrain {ch!r}"
                    )
    kind = _MOVINGAI_KIND[codes].reshape(height, width)
    bad = np.flatnonzero(kind.ravel() == 2)
    if len(bad):
        r, c = divmod(int(bad[0]), width)
        raise MapImportError(
            f"{source}: line {i + r + 1}, column {c + 1}: unknown terrain {grid[r][c]!r}"
        )
    return np.asarray(kind == 1)


def movingai_cell_center(
    x: int, y: int, height: int, resolution: float = 1.0
) -> tuple[float, float]:
    """Scenario-frame centre of MovingAI cell (x, y): x = column, y = row from the top (.scen)."""
    return ((x + 0.5) * resolution, (height - y - 0.5) * resolution)


def load_movingai_map(
    path: str | os.PathLike[str],
    *,
    resolution: float = 1.0,
    start: Sequence[float] | None = None,
    goal: Sequence[float] | None = None,
    robot: RobotSpec | None = None,
    name: str | None = None,
    sensors: str | None = None,
    time_step: float = 0.1,
    max_cells: int = MAX_CELLS,
    max_obstacles: int = MAX_OBSTACLES,
    endpoint_margin: float = ENDPOINT_MARGIN,
    progress: Callable[[float], None] | None = None,
) -> ImportedMap:
    """Import a MovingAI ``.map`` grid; each cell is ``resolution`` metres wide.

    ``start``/``goal`` in the scenario frame (use :func:`movingai_cell_center` for .scen cells).
    ``robot`` defaults to ``turtlebot3-burger``.
    """
    p = Path(path)
    if not (resolution > 0):
        raise MapImportError(f"{p}: resolution must be > 0")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise MapImportError(f"{p}: not a text file (UTF-8)") from None
    blocked_text = parse_movingai_map(text, str(p), max_cells)
    rows, cols = blocked_text.shape
    if max(rows, cols) * resolution > MAX_METRES:
        raise MapImportError(
            f"{p}: {cols} x {rows} cells of resolution={resolution:g} m make a map "
            f"{cols * resolution:g} x {rows * resolution:g} m, more than {MAX_METRES:g} m across"
        )
    data = np.where(blocked_text[::-1], OCCUPIED, FREE).astype(np.int8)
    return _build(
        name or p.stem,
        data,
        float(resolution),
        start=start,
        goal=goal,
        robot=robot,
        unknown_as_occupied=True,
        sensors=sensors,
        time_step=time_step,
        source=str(p),
        meta={"format": "movingai", "height": data.shape[0], "width": data.shape[1]},
        max_obstacles=max_obstacles,
        endpoint_margin=endpoint_margin,
        progress=progress,
    )
