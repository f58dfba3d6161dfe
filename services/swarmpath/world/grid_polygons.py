"""Blocked cells of an occupancy grid as a few simple orthogonal polygons (exact geometry).

:func:`grid_polygons` turns a boolean mask (row 0 at the bottom, cell ``(r, c)`` the square
``[c, c + 1] x [r, r + 1]`` in cell units) into simple polygons whose union is exactly the union
of the blocked cells:

1. The grid is cut into ``tile x tile`` windows (so that no polygon has more than a few hundred
   vertices, which keeps every per-polygon computation downstream cheap).
2. In each window the blocked cells are split into 4-connected components. A component that
   encloses free cells (a *hole*, free cells not 4-connected to the outside of the component's
   bounding box) is cut along the grid line at the left edge of each hole and the parts are
   examined again, until no part has a hole. A 4-connected part without holes has no pinch
   vertex (two of its cells meeting only at a corner would enclose one of the other two cells),
   so its boundary is one simple closed curve.
3. That curve is traced along the cell edges (counter-clockwise) and only the vertices where it
   turns are kept.

The parts are disjoint sets of cells, so the polygons may touch (along cut lines and at corners)
but never overlap. The cut lines and touching corners are interior to the union or on straight
parts of its boundary; :func:`swarmpath.world.optimum.shortest_path` ignores such vertices.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

__all__ = ["DEFAULT_TILE", "blocked_components", "grid_polygons"]

DEFAULT_TILE = 64
_CROSS = ndimage.generate_binary_structure(2, 1)


def blocked_components(blocked: NDArray[np.bool_]) -> int:
    """Number of 4-connected components of blocked cells: a lower bound on the polygon count."""
    return int(ndimage.label(blocked, structure=_CROSS)[1])


def _hole_free_parts(mask: NDArray[np.bool_]) -> list[tuple[NDArray[np.bool_], int, int]]:
    """4-connected parts of ``mask`` without holes, as (sub-mask, row offset, col offset)."""
    out: list[tuple[NDArray[np.bool_], int, int]] = []
    work = [(mask, 0, 0)]
    while work:
        sub, r0, c0 = work.pop()
        labels, _ = ndimage.label(sub, structure=_CROSS)
        for k, sl in enumerate(ndimage.find_objects(labels), start=1):
            if sl is None:
                continue
            part = labels[sl] == k
            pr, pc = r0 + sl[0].start, c0 + sl[1].start
            holes = ndimage.binary_fill_holes(part) & ~part
            if not holes.any():
                out.append((part, pr, pc))
                continue
            hl, _ = ndimage.label(holes, structure=_CROSS)
            cuts = sorted({int(s[1].start) for s in ndimage.find_objects(hl) if s is not None})
            edges = [0, *cuts, part.shape[1]]
            for a, b in itertools.pairwise(edges):
                if b > a and part[:, a:b].any():
                    work.append((part[:, a:b], pr, pc + a))
    return out


def _trace(part: NDArray[np.bool_]) -> NDArray[np.int64]:
    """Counter-clockwise boundary of a hole-free 4-connected part: turning vertices (x, y)."""
    p = np.pad(part, 1)
    inner = p[1:-1, 1:-1]
    cols = part.shape[1]
    starts: list[NDArray[np.int64]] = []
    ends: list[NDArray[np.int64]] = []
    # side of a cell -> its directed edge (interior on the left), in cell-corner coordinates
    for nb, d0, d1 in (
        (p[:-2, 1:-1], (0, 0), (1, 0)),  # bottom: (c, r) -> (c + 1, r)
        (p[1:-1, 2:], (1, 0), (1, 1)),  # right
        (p[2:, 1:-1], (1, 1), (0, 1)),  # top
        (p[1:-1, :-2], (0, 1), (0, 0)),  # left
    ):
        r, c = np.nonzero(inner & ~nb)
        starts.append(np.stack([c + d0[0], r + d0[1]], axis=1))
        ends.append(np.stack([c + d1[0], r + d1[1]], axis=1))
    s = np.concatenate(starts)
    e = np.concatenate(ends)
    width = cols + 1
    skey = s[:, 1] * width + s[:, 0]
    ekey = e[:, 1] * width + e[:, 0]
    order = np.argsort(skey)
    nxt = order[np.searchsorted(skey[order], ekey)]
    seq = np.empty(len(s), dtype=np.int64)
    i = 0
    for k in range(len(s)):
        seq[k] = i
        i = int(nxt[i])
    if i != 0 or len(np.unique(seq)) != len(s):
        raise AssertionError("boundary of a hole-free part is not one cycle")
    pts = s[seq]
    d_in = pts - np.roll(pts, 1, axis=0)
    d_out = np.roll(pts, -1, axis=0) - pts
    turn = np.any(d_in != d_out, axis=1)
    return np.asarray(pts[turn], dtype=np.int64)


def grid_polygons(
    blocked: NDArray[np.bool_], tile: int = DEFAULT_TILE,
    progress: Callable[[float], None] | None = None,
) -> list[NDArray[np.int64]]:
    """Simple counter-clockwise polygons (vertices in cell units) covering exactly the blocked
    cells; ordered by tile (rows of tiles from the bottom), then by position. ``progress`` gets
    the fraction of tile rows done."""
    b = np.asarray(blocked, dtype=bool)
    if tile < 1:
        raise ValueError(f"tile must be >= 1, got {tile}")
    out: list[NDArray[np.int64]] = []
    for r0 in range(0, b.shape[0], tile):
        if progress is not None:
            progress(r0 / b.shape[0])
        for c0 in range(0, b.shape[1], tile):
            window = b[r0 : r0 + tile, c0 : c0 + tile]
            if not window.any():
                continue
            parts = _hole_free_parts(window)
            parts.sort(key=lambda q: (q[1], q[2]))
            for part, pr, pc in parts:
                out.append(_trace(part) + np.array([c0 + pc, r0 + pr], dtype=np.int64))
    return out
