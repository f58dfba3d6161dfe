"""Exact 2D distance geometry for points, segments, circles and simple polygons (metres).

Pure numpy, no I/O, no global state. Every function broadcasts over leading dimensions: points
are float arrays of shape (..., 2) and results have the broadcast leading shape (...).

Collision rule of the product
-----------------------------
Obstacles are stored *without* the robot: an :class:`ObstacleSet` knows only the obstacle
surfaces. The robot is a disk of radius ``r`` centred on its reference point. Its body touches an
obstacle when the clearance of the centre (the distance from the centre, or from the swept centre
segment, to the nearest obstacle surface) is at most ``r``::

    collision  <=>  clearance <= robot_radius          (touching counts as a collision)

Use :func:`collides` rather than writing the comparison by hand, so that every part of the product
applies the same rule. Equivalently each obstacle is inflated by ``r`` (circles grow to radius
``R + r``; a polygon grows to its Minkowski sum with a disk of radius ``r``) and the centre must
stay strictly outside the inflated set.

Conventions
-----------
* Polygons are simple (non self-intersecting), any orientation, convex or not, given as (m, 2)
  vertex arrays without repeating the first vertex; a polygon is a closed solid region.
* Signed distances are negative inside an obstacle. For a point exactly on a boundary the
  in/out classification of :func:`points_in_polygon` is unspecified (floating point), but the
  signed distance is 0 there either way.
* Degenerate segments (A == B) behave as points.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

__all__ = [
    "ObstacleSet",
    "collides",
    "point_polygon_distance",
    "point_segment_distance",
    "points_in_polygon",
    "segment_polygon_distance",
    "segment_segment_distance",
]


_CHUNK_ELEMS = 1 << 20  # points x edges per batch: bounds the temporaries of big queries


def _f(x: ArrayLike) -> Array:
    return np.asarray(x, dtype=np.float64)


def _chunked(
    fn: Callable[..., NDArray[Any]], arrays: tuple[Array, ...], width: int, dtype: type
) -> NDArray[Any]:
    """Apply ``fn`` (flat (n, 2) inputs -> (n,)) to broadcast point arrays in bounded batches."""
    shape = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
    flat = [np.broadcast_to(a, (*shape, 2)).reshape(-1, 2) for a in arrays]
    n = flat[0].shape[0]
    step = max(1, _CHUNK_ELEMS // max(width, 1))
    if n <= step:
        return np.asarray(fn(*flat), dtype=dtype).reshape(shape)
    out: NDArray[Any] = np.empty(n, dtype=dtype)
    for lo in range(0, n, step):
        out[lo : lo + step] = fn(*(f[lo : lo + step] for f in flat))
    return out.reshape(shape)


def _cross(u: Array, v: Array) -> Array:
    return np.asarray(u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0], dtype=np.float64)


def _dot(u: Array, v: Array) -> Array:
    return np.asarray(u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1], dtype=np.float64)


def collides(clearance: ArrayLike, radius: ArrayLike) -> BoolArray:
    """The product's collision rule: the robot body touches an obstacle iff clearance <= radius."""
    return np.asarray(np.asarray(clearance) <= np.asarray(radius))


def point_segment_distance(P: ArrayLike, A: ArrayLike, B: ArrayLike) -> Array:
    """Euclidean distance from points P to the closed segments AB (shape (...))."""
    P, A, B = _f(P), _f(A), _f(B)
    d = B - A
    dd = _dot(d, d)
    safe = np.where(dd > 0.0, dd, 1.0)
    t = np.clip(_dot(P - A, d) / safe, 0.0, 1.0)
    t = np.where(dd > 0.0, t, 0.0)
    closest = A + t[..., None] * d
    return np.asarray(np.hypot(*np.moveaxis(P - closest, -1, 0)))


def _segments_cross(A: Array, B: Array, C: Array, D: Array) -> BoolArray:
    """True where the open segments cross properly (each strictly separates the other's ends)."""
    o1 = _cross(B - A, C - A)
    o2 = _cross(B - A, D - A)
    o3 = _cross(D - C, A - C)
    o4 = _cross(D - C, B - C)
    return np.asarray((o1 * o2 < 0.0) & (o3 * o4 < 0.0))


def segment_segment_distance(A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike) -> Array:
    """Distance between closed segments AB and CD; 0 where they intersect or touch.

    Two segments that do not cross properly are closest at an endpoint of one of them, so the
    distance is the smallest of four point-segment distances; touching and collinear overlap give
    0 through that minimum (an endpoint lies on the other segment).
    """
    A, B, C, D = _f(A), _f(B), _f(C), _f(D)
    d = np.minimum(
        np.minimum(point_segment_distance(A, C, D), point_segment_distance(B, C, D)),
        np.minimum(point_segment_distance(C, A, B), point_segment_distance(D, A, B)),
    )
    return np.asarray(np.where(_segments_cross(A, B, C, D), 0.0, d))


def _edges(poly: Array) -> tuple[Array, Array]:
    return poly, np.roll(poly, -1, axis=0)


def _crossings(P: Array, E0: Array, E1: Array) -> BoolArray:
    """Even-odd ray casting (ray towards +x): for points P (..., 2) and edges (M, 2) -> (..., M)."""
    px = P[..., None, 0]
    py = P[..., None, 1]
    ax, ay, bx, by = E0[:, 0], E0[:, 1], E1[:, 0], E1[:, 1]
    straddle = (ay > py) != (by > py)
    dy = by - ay
    safe = np.where(dy != 0.0, dy, 1.0)
    x_at = ax + (py - ay) * (bx - ax) / safe
    return np.asarray(straddle & (px < x_at))


def _parity_inside(P: Array, e0: Array, e1: Array) -> BoolArray:
    return np.asarray(np.count_nonzero(_crossings(P, e0, e1), axis=-1) % 2 == 1)


def points_in_polygon(P: ArrayLike, poly: ArrayLike) -> BoolArray:
    """True where P lies inside the simple polygon ``poly`` (m, 2) (even-odd rule)."""
    e0, e1 = _edges(_f(poly))
    return _chunked(lambda p: _parity_inside(p, e0, e1), (_f(P),), len(e0), bool)


def _signed_polygon(P: Array, e0: Array, e1: Array) -> Array:
    d = np.min(point_segment_distance(P[:, None, :], e0, e1), axis=-1)
    return np.asarray(np.where(_parity_inside(P, e0, e1), -d, d))


def point_polygon_distance(P: ArrayLike, poly: ArrayLike) -> Array:
    """Signed distance from P to the boundary of ``poly``: positive outside, negative inside."""
    e0, e1 = _edges(_f(poly))
    return _chunked(lambda p: _signed_polygon(p, e0, e1), (_f(P),), len(e0), np.float64)


def _segment_polygon(A: Array, B: Array, e0: Array, e1: Array) -> Array:
    d = np.min(segment_segment_distance(A[:, None, :], B[:, None, :], e0, e1), axis=-1)
    return np.asarray(np.where(_parity_inside(A, e0, e1), 0.0, d))


def segment_polygon_distance(A: ArrayLike, B: ArrayLike, poly: ArrayLike) -> Array:
    """Distance from segment AB to the solid polygon; 0 if it touches, crosses or lies inside."""
    e0, e1 = _edges(_f(poly))
    return _chunked(
        lambda a, b: _segment_polygon(a, b, e0, e1), (_f(A), _f(B)), len(e0), np.float64
    )


def _empty_circles() -> Array:
    return np.zeros((0, 3))


@dataclass(frozen=True, eq=False)
class ObstacleSet:
    """Static snapshot of obstacles: circles (k, 3) rows [cx, cy, r] and simple polygons.

    The robot radius is *not* part of the set (see the module docstring for the collision rule).
    Instances are immutable (arrays are copied and made read-only); equality is identity.
    """

    circles: Array = field(default_factory=_empty_circles)
    polygons: tuple[Array, ...] = ()
    # Derived, concatenated polygon edges for vectorised queries over all polygons at once.
    _e0: Array = field(init=False, repr=False, compare=False)
    _e1: Array = field(init=False, repr=False, compare=False)
    _starts: NDArray[np.intp] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        circles = np.array(self.circles, dtype=np.float64).reshape(-1, 3)
        if np.any(circles[:, 2] < 0.0):
            raise ValueError("circle radii must be >= 0")
        polys = []
        for p in self.polygons:
            q = np.array(p, dtype=np.float64)
            if q.ndim != 2 or q.shape[1] != 2 or q.shape[0] < 3:
                raise ValueError(f"polygon must be an (m>=3, 2) array, got shape {q.shape}")
            q.setflags(write=False)
            polys.append(q)
        circles.setflags(write=False)
        object.__setattr__(self, "circles", circles)
        object.__setattr__(self, "polygons", tuple(polys))
        if polys:
            e0 = np.concatenate(polys)
            e1 = np.concatenate([np.roll(q, -1, axis=0) for q in polys])
            starts = np.cumsum([0] + [len(q) for q in polys[:-1]]).astype(np.intp)
        else:
            e0 = e1 = np.zeros((0, 2))
            starts = np.zeros(0, dtype=np.intp)
        for a in (e0, e1, starts):
            a.setflags(write=False)
        object.__setattr__(self, "_e0", e0)
        object.__setattr__(self, "_e1", e1)
        object.__setattr__(self, "_starts", starts)

    @classmethod
    def empty(cls) -> ObstacleSet:
        return cls(np.zeros((0, 3)), ())

    @property
    def is_empty(self) -> bool:
        return self.circles.shape[0] == 0 and not self.polygons

    def _inside_any_polygon(self, P: Array) -> tuple[BoolArray, BoolArray]:
        """Per-polygon inside flags (..., p) and their union (...)."""
        cr = _crossings(P, self._e0, self._e1).astype(np.intp)
        per = np.add.reduceat(cr, self._starts, axis=-1) % 2 == 1
        return per, np.any(per, axis=-1)

    def point_clearance(self, P: ArrayLike) -> Array:
        """Signed distance from P to the nearest obstacle surface (< 0 inside; +inf if none)."""
        width = self.circles.shape[0] + self._e0.shape[0]
        return _chunked(self._point_clearance, (_f(P),), width, np.float64)

    def _point_clearance(self, P: Array) -> Array:
        out = np.full(P.shape[:-1], np.inf)
        c = self.circles
        if c.shape[0]:
            dc = np.hypot(P[..., None, 0] - c[:, 0], P[..., None, 1] - c[:, 1]) - c[:, 2]
            out = np.minimum(out, np.min(dc, axis=-1))
        if self.polygons:
            d = point_segment_distance(P[..., None, :], self._e0, self._e1)
            per_d = np.minimum.reduceat(d, self._starts, axis=-1)
            per_in, _ = self._inside_any_polygon(P)
            out = np.minimum(out, np.min(np.where(per_in, -per_d, per_d), axis=-1))
        return out

    def segment_clearance(self, A: ArrayLike, B: ArrayLike) -> Array:
        """Min distance from segment AB to any obstacle (0 if touching, crossing or inside).

        +inf if there are no obstacles. AB is the closed segment (a swept centre); A == B: a point.
        """
        width = self.circles.shape[0] + self._e0.shape[0]
        return _chunked(self._segment_clearance, (_f(A), _f(B)), width, np.float64)

    def _segment_clearance(self, A: Array, B: Array) -> Array:
        out = np.full(A.shape[:-1], np.inf)
        c = self.circles
        if c.shape[0]:
            dc = point_segment_distance(c[:, :2], A[..., None, :], B[..., None, :]) - c[:, 2]
            out = np.minimum(out, np.maximum(np.min(dc, axis=-1), 0.0))
        if self.polygons:
            d = segment_segment_distance(A[..., None, :], B[..., None, :], self._e0, self._e1)
            dmin = np.min(d, axis=-1)
            _, inside = self._inside_any_polygon(A)
            out = np.minimum(out, np.where(inside, 0.0, dmin))
        return out

    def translated(self, offsets_circles: ArrayLike, offsets_polygons: ArrayLike) -> ObstacleSet:
        """A copy with circle i moved by offsets_circles[i] and polygon j by offsets_polygons[j]."""
        oc = _f(offsets_circles).reshape(-1, 2)
        op = _f(offsets_polygons).reshape(-1, 2)
        if oc.shape[0] != self.circles.shape[0] or op.shape[0] != len(self.polygons):
            raise ValueError(
                f"expected {self.circles.shape[0]} circle and {len(self.polygons)} polygon "
                f"offsets, got {oc.shape[0]} and {op.shape[0]}"
            )
        circles = self.circles.copy()
        circles[:, :2] += oc
        return ObstacleSet(circles, tuple(p + o for p, o in zip(self.polygons, op, strict=True)))
