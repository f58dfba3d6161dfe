"""Shared pieces of :mod:`swarmpath.world.optimum`: the tangency tolerance, array types and the
small vectorized helpers (arc and segment distances, CSR expansion, batching)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from swarmpath.world.geometry import point_segment_distance

#: s of wall time the exact optimum may take (a loaded machine shares its cores); here, not in
#: :mod:`swarmpath.world.optimum`, so that the CLI can name it without loading scipy.sparse.
DEFAULT_BUDGET = 30.0

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

TOL = 1e-9
TWO_PI = 2.0 * math.pi
_CHUNK = 1 << 18  # work items (pair x obstacle or pair x edge) per numpy batch

World = tuple[float, float, float, float]


def _cross(u: Array, v: Array) -> Array:
    return np.asarray(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0], dtype=np.float64)


def _dot(u: Array, v: Array) -> Array:
    return np.asarray(u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1], dtype=np.float64)


def _norm(u: Array) -> Array:
    return np.asarray(np.hypot(u[..., 0], u[..., 1]), dtype=np.float64)


def _in_arc(phi: Array, th0: Array, dth: Array) -> BoolArray:
    """Angle phi lies on the arc starting at th0 and sweeping dth >= 0 counter-clockwise."""
    return np.asarray(np.mod(phi - th0, TWO_PI) <= dth + 1e-12)


def _on_circle(c: Array, rho: Array, th: Array) -> Array:
    return np.asarray(c + rho[..., None] * np.stack([np.cos(th), np.sin(th)], axis=-1))


def _point_arc_distance(q: Array, c: Array, rho: Array, th0: Array, dth: Array) -> Array:
    """Exact distance from points q to arcs (centre c, radius rho, from th0 sweeping dth ccw)."""
    w = q - c
    r = _norm(w)
    phi = np.arctan2(w[..., 1], w[..., 0])
    d_end = np.minimum(_norm(q - _on_circle(c, rho, th0)), _norm(q - _on_circle(c, rho, th0 + dth)))
    radial = np.where(_in_arc(phi, th0, dth), np.abs(r - rho), np.inf)
    return np.asarray(np.minimum(d_end, radial))


def _arc_segment_distance(
    c: Array, rho: Array, th0: Array, dth: Array, a: Array, b: Array
) -> Array:
    """Exact distance between arcs and closed segments ab (all inputs broadcast together).

    The minimum is attained either at an end of one of the two curves, at an intersection (0), or
    at the foot f of the perpendicular from the centre onto the segment paired with the arc
    point on the ray c->f. Every candidate below is the distance of a real pair of points, so the
    minimum over them is exact.
    """
    e0 = _on_circle(c, rho, th0)
    e1 = _on_circle(c, rho, th0 + dth)
    best = np.minimum(
        np.minimum(
            _point_arc_distance(a, c, rho, th0, dth), _point_arc_distance(b, c, rho, th0, dth)
        ),
        np.minimum(point_segment_distance(e0, a, b), point_segment_distance(e1, a, b)),
    )
    e = b - a
    ee = _dot(e, e)
    safe = np.where(ee > 0.0, ee, 1.0)
    t = np.clip(_dot(c - a, e) / safe, 0.0, 1.0)
    f = a + t[..., None] * e
    wf = f - c
    rf = _norm(wf)
    ok = _in_arc(np.arctan2(wf[..., 1], wf[..., 0]), th0, dth) & (rf > 0.0)
    best = np.minimum(best, np.where(ok, np.abs(rf - rho), np.inf))
    # Intersections of the segment with the full circle, kept if they lie on the arc.
    ac = a - c
    bq = 2.0 * _dot(e, ac)
    cq = _dot(ac, ac) - rho * rho
    disc = bq * bq - 4.0 * ee * cq
    has = (ee > 0.0) & (disc >= 0.0)
    sq = np.sqrt(np.where(has, disc, 0.0))
    for sign in (-1.0, 1.0):
        tt = (-bq + sign * sq) / (2.0 * safe)
        p = a + tt[..., None] * e - c
        hit = has & (tt >= 0.0) & (tt <= 1.0) & _in_arc(np.arctan2(p[..., 1], p[..., 0]), th0, dth)
        best = np.where(hit, 0.0, best)
    return np.asarray(best)


def _expand_csr(
    items: IntArray, counts: IntArray, first: IntArray, col: IntArray
) -> tuple[IntArray, IntArray]:
    """Pairs (item, col[first[i] + r]) for r < counts[i]: a CSR row gather, vectorised."""
    rep = np.repeat(items, counts)
    starts = np.repeat(first - (np.cumsum(counts) - counts), counts)
    return rep, col[starts + np.arange(len(rep))]


def _chunks_by_weight(weights: IntArray, budget: int) -> list[slice]:
    """Split range(len(weights)) into consecutive slices whose weight sums stay near budget."""
    if len(weights) == 0:
        return []
    cum = np.cumsum(weights)
    out: list[slice] = []
    lo = 0
    while lo < len(weights):
        base = cum[lo - 1] if lo else 0
        hi = int(np.searchsorted(cum, base + budget, side="right"))
        hi = max(hi, lo + 1)
        out.append(slice(lo, hi))
        lo = hi
    return out

