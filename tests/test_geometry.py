"""swarmpath.world.geometry cross-checked against shapely (property-based) plus edge cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, Point, Polygon

from swarmpath.world import geometry
from swarmpath.world.geometry import (
    ObstacleSet,
    collides,
    point_polygon_distance,
    point_segment_distance,
    points_in_polygon,
    segment_polygon_distance,
    segment_segment_distance,
)

TOL = 1e-9
SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# Rounded to 1e-7 m: shapely (GEOS) itself misbehaves on subnormal coordinates.
coord = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False).map(lambda v: round(v, 7))
# Small integer grids produce many exact degeneracies (collinear, shared endpoints, touching).
icoord = st.integers(-4, 4).map(float)
point = st.tuples(coord, coord)
ipoint = st.tuples(icoord, icoord)
any_point = st.one_of(point, ipoint)


@st.composite
def star_polygon(draw: st.DrawFn) -> np.ndarray:
    """A random simple polygon: star-shaped around a centre, vertices at sorted distinct angles."""
    n = draw(st.integers(3, 12))
    cx, cy = draw(st.tuples(st.floats(-3, 3), st.floats(-3, 3)))
    raw = draw(st.lists(st.floats(0.0, 1.0), min_size=n, max_size=n))
    # Spread sorted angles with a minimum gap so no two vertices coincide.
    gaps = np.asarray(raw) + 0.15
    ang = np.cumsum(gaps) / np.sum(gaps) * 2 * math.pi
    radii = np.asarray(draw(st.lists(st.floats(0.3, 4.0), min_size=n, max_size=n)))
    poly = np.column_stack([cx + radii * np.cos(ang), cy + radii * np.sin(ang)])
    # An angular gap above pi lets an edge pass behind the centre: keep only simple polygons.
    assume(np.max(gaps) / np.sum(gaps) < 0.45 and Polygon(poly).is_valid)
    if draw(st.booleans()):
        poly = poly[::-1].copy()  # clockwise orientation too
    return poly


def _shp(poly: np.ndarray) -> Polygon:
    p = Polygon(poly)
    assert p.is_valid
    return p


def _seg(a: tuple[float, float], b: tuple[float, float]) -> LineString | Point:
    return Point(a) if a == b else LineString([a, b])


# ---------------------------------------------------------------- property tests vs shapely


@SETTINGS
@given(any_point, any_point, any_point)
def test_point_segment_distance_matches_shapely(p, a, b) -> None:
    got = float(point_segment_distance(np.array(p), np.array(a), np.array(b)))
    assert got == pytest.approx(Point(p).distance(_seg(a, b)), abs=TOL)


@SETTINGS
@given(any_point, any_point, any_point, any_point)
def test_segment_segment_distance_matches_shapely(a, b, c, d) -> None:
    got = float(segment_segment_distance(*map(np.array, (a, b, c, d))))
    s1, s2 = _seg(a, b), _seg(c, d)
    want = s1.distance(s2)
    assert got == pytest.approx(want, abs=TOL)
    if s1.intersects(s2):
        assert got <= TOL
    assert got >= 0.0


@SETTINGS
@given(star_polygon(), st.lists(point, min_size=1, max_size=20))
def test_points_in_polygon_and_signed_distance_match_shapely(poly, pts) -> None:
    shp = _shp(poly)
    P = np.asarray(pts)
    inside = points_in_polygon(P, poly)
    signed = point_polygon_distance(P, poly)
    assert inside.shape == signed.shape == (len(pts),)
    for k, p in enumerate(pts):
        bd = shp.exterior.distance(Point(p))
        assert abs(signed[k]) == pytest.approx(bd, abs=TOL)
        if bd > 1e-9:  # on the boundary the classification is unspecified
            assert bool(inside[k]) == shp.contains(Point(p))
            assert (signed[k] < 0) == shp.contains(Point(p))


@SETTINGS
@given(star_polygon(), any_point, any_point)
def test_segment_polygon_distance_matches_shapely(poly, a, b) -> None:
    got = float(segment_polygon_distance(np.array(a), np.array(b), poly))
    assert got == pytest.approx(_shp(poly).distance(_seg(a, b)), abs=TOL)


@SETTINGS
@given(
    st.lists(st.tuples(coord, coord, st.floats(0.0, 3.0)), min_size=0, max_size=4),
    st.lists(star_polygon(), min_size=0, max_size=3),
    any_point,
    any_point,
)
def test_obstacle_set_matches_shapely(circles, polys, a, b) -> None:
    obs = ObstacleSet(np.asarray(circles, dtype=float).reshape(-1, 3), tuple(polys))
    pc = float(obs.point_clearance(np.array(a)))
    sc = float(obs.segment_clearance(np.array(a), np.array(b)))
    if not circles and not polys:
        assert pc == math.inf and sc == math.inf
        return
    want_p, want_s = math.inf, math.inf
    for cx, cy, r in circles:
        want_p = min(want_p, math.dist(a, (cx, cy)) - r)
        want_s = min(want_s, max(_seg(a, b).distance(Point(cx, cy)) - r, 0.0))
    for poly in polys:
        shp = _shp(poly)
        bd = shp.exterior.distance(Point(a))
        want_p = min(want_p, -bd if shp.contains(Point(a)) else bd)
        want_s = min(want_s, shp.distance(_seg(a, b)))
    assert pc == pytest.approx(want_p, abs=TOL)
    assert sc == pytest.approx(want_s, abs=TOL)
    assert sc >= 0.0
    assert sc <= max(pc, 0.0) + TOL  # the segment contains A


# ---------------------------------------------------------------- broadcasting


def test_broadcasting_shapes_and_values() -> None:
    rng = np.random.default_rng(0)
    P = rng.uniform(-5, 5, (3, 4, 2))
    A = rng.uniform(-5, 5, (4, 2))
    B = rng.uniform(-5, 5, (1, 4, 2))
    d = point_segment_distance(P, A, B)
    assert d.shape == (3, 4)
    for i in range(3):
        for j in range(4):
            want = Point(P[i, j]).distance(LineString([A[j], B[0, j]]))
            assert d[i, j] == pytest.approx(want, abs=TOL)
    C = rng.uniform(-5, 5, (5, 1, 2))
    D = rng.uniform(-5, 5, (5, 1, 2))
    assert segment_segment_distance(A, B, C, D).shape == (5, 4)
    poly = np.array([[0, 0], [4, 0], [4, 4], [2, 1], [0, 4]], dtype=float)  # non-convex
    assert points_in_polygon(P, poly).shape == (3, 4)
    assert point_polygon_distance(P, poly).shape == (3, 4)
    assert segment_polygon_distance(P, A, poly).shape == (3, 4)
    obs = ObstacleSet(np.array([[0.0, 0.0, 1.0], [3.0, 3.0, 0.5]]), (poly,))
    assert obs.point_clearance(P).shape == (3, 4)
    assert obs.segment_clearance(P, A).shape == (3, 4)
    assert obs.point_clearance(np.zeros(2)).shape == ()


def test_obstacle_set_vectorised_equals_elementwise() -> None:
    rng = np.random.default_rng(1)
    polys = (
        np.array([[0, 0], [2, 0], [2, 2], [0, 2]], dtype=float),
        np.array([[5, 5], [7, 5], [6, 8]], dtype=float),
        np.array([[-4, -4], [-1, -4], [-1, -1], [-2, -3], [-4, -1]], dtype=float),
    )
    obs = ObstacleSet(np.array([[3.0, -3.0, 1.0]]), polys)
    A = rng.uniform(-6, 8, (50, 2))
    B = rng.uniform(-6, 8, (50, 2))
    pc, sc = obs.point_clearance(A), obs.segment_clearance(A, B)
    for k in range(50):
        assert pc[k] == obs.point_clearance(A[k])
        assert sc[k] == obs.segment_clearance(A[k], B[k])


# ---------------------------------------------------------------- edge cases


def test_degenerate_zero_length_segments() -> None:
    p = np.array([3.0, 4.0])
    o = np.zeros(2)
    assert point_segment_distance(p, o, o) == pytest.approx(5.0)
    assert segment_segment_distance(o, o, p, p) == pytest.approx(5.0)
    assert segment_segment_distance(o, o, o, o) == 0.0
    # a point lying on a segment
    on = np.array([1.0, 1.0])
    assert segment_segment_distance(on, on, o, 2 * np.ones(2)) == 0
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    assert segment_polygon_distance(np.array([0.5, 0.5]), np.array([0.5, 0.5]), sq) == 0.0
    assert segment_polygon_distance(np.array([3.0, 0.5]), np.array([3.0, 0.5]), sq) == 2.0


def test_collinear_overlap_and_disjoint() -> None:
    a, b = np.array([0.0, 0.0]), np.array([2.0, 0.0])
    assert segment_segment_distance(a, b, np.array([1.0, 0.0]), np.array([3.0, 0.0])) == 0.0
    assert segment_segment_distance(a, b, np.array([3.0, 0.0]), np.array([5.0, 0.0])) == 1.0
    # contained
    assert segment_segment_distance(a, b, np.array([0.5, 0.0]), np.array([1.5, 0.0])) == 0.0
    # parallel offset
    assert segment_segment_distance(a, b, np.array([0.5, 0.3]), np.array([1.5, 0.3])) == 0.3


def test_touching_at_a_vertex_and_crossing() -> None:
    a, b = np.array([0.0, 0.0]), np.array([1.0, 1.0])
    assert segment_segment_distance(a, b, b, np.array([2.0, 0.0])) == 0.0  # shared endpoint
    assert segment_segment_distance(a, b, np.array([0.5, 0.5]), np.array([2.0, 0.0])) == 0.0  # T
    assert segment_segment_distance(a, b, np.array([0.0, 1.0]), np.array([1.0, 0.0])) == 0.0  # X
    tri = np.array([[0, 0], [2, 0], [1, 2]], dtype=float)
    # segment touching the polygon only at its apex vertex
    assert segment_polygon_distance(np.array([0.0, 2.0]), np.array([2.0, 2.0]), tri) == 0.0
    # segment passing through the polygon without endpoints inside
    assert segment_polygon_distance(np.array([-1.0, 0.5]), np.array([3.0, 0.5]), tri) == 0.0
    # entirely inside
    assert segment_polygon_distance(np.array([0.9, 0.5]), np.array([1.1, 0.6]), tri) == 0.0
    # ray-casting through a vertex at the query height must not double count
    assert bool(points_in_polygon(np.array([-1.0, 2.0]), tri)) is False
    assert bool(points_in_polygon(np.array([0.5, 0.0 + 1e-12]), tri)) is True
    diamond = np.array([[0, -1], [1, 0], [0, 1], [-1, 0]], dtype=float)
    assert bool(points_in_polygon(np.array([-2.0, 0.0]), diamond)) is False
    assert bool(points_in_polygon(np.array([0.0, 0.0]), diamond)) is True


def test_non_convex_polygon_and_orientation() -> None:
    u = np.array([[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], dtype=float)
    for poly in (u, u[::-1]):
        assert bool(points_in_polygon(np.array([1.5, 2.0]), poly)) is False  # in the notch
        assert bool(points_in_polygon(np.array([0.5, 2.0]), poly)) is True
        assert point_polygon_distance(np.array([1.5, 2.0]), poly) == pytest.approx(0.5)
        assert point_polygon_distance(np.array([0.5, 2.0]), poly) == pytest.approx(-0.5)
        # a segment down the notch does not touch the U
        assert segment_polygon_distance(
            np.array([1.5, 3.5]), np.array([1.5, 1.25]), poly
        ) == pytest.approx(0.25)


def test_circle_tangency_counts_as_collision() -> None:
    obs = ObstacleSet(np.array([[0.0, 0.0, 1.0]]), ())
    # segment tangent to the circle grown by r = 0.5
    c = obs.segment_clearance(np.array([-2.0, 1.5]), np.array([2.0, 1.5]))
    assert c == pytest.approx(0.5)
    assert bool(collides(c, 0.5))
    assert not bool(collides(c, 0.4999))
    assert obs.point_clearance(np.array([0.0, 0.0])) == -1.0
    assert obs.segment_clearance(np.array([-0.1, 0.0]), np.array([0.1, 0.0])) == 0.0
    assert collides(np.array([0.1, 0.6]), 0.5).tolist() == [True, False]


def test_empty_and_translated() -> None:
    e = ObstacleSet.empty()
    assert e.is_empty
    assert e.circles.shape == (0, 3)
    assert e.point_clearance(np.zeros((4, 2))).tolist() == [math.inf] * 4
    assert e.segment_clearance(np.zeros(2), np.ones(2)) == math.inf
    assert e.translated(np.zeros((0, 2)), np.zeros((0, 2))).is_empty
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    obs = ObstacleSet(np.array([[5.0, 5.0, 1.0]]), (sq,))
    moved = obs.translated(np.array([[1.0, 0.0]]), np.array([[0.0, 2.0]]))
    assert moved.circles.tolist() == [[6.0, 5.0, 1.0]]
    assert moved.polygons[0].tolist() == (sq + np.array([0.0, 2.0])).tolist()
    assert obs.circles.tolist() == [[5.0, 5.0, 1.0]]  # original untouched
    assert moved.point_clearance(np.array([0.5, 2.5])) == pytest.approx(-0.5)
    with pytest.raises(ValueError):
        obs.translated(np.zeros((2, 2)), np.zeros((1, 2)))
    with pytest.raises(ValueError):
        obs.circles[0, 0] = 1.0  # read-only


def test_invalid_inputs() -> None:
    with pytest.raises(ValueError):
        ObstacleSet(np.array([[0.0, 0.0, -1.0]]), ())
    with pytest.raises(ValueError):
        ObstacleSet(np.zeros((0, 3)), (np.zeros((2, 2)),))


def test_large_queries_are_batched_consistently(monkeypatch: pytest.MonkeyPatch) -> None:
    # with a small batch size every query below is split: results must not depend on it
    monkeypatch.setattr(geometry, "_CHUNK_ELEMS", 1000)
    rng = np.random.default_rng(2)
    star = np.array(
        [[3 * math.cos(a) * (1 + (i % 2)), 3 * math.sin(a) * (1 + (i % 2))]
         for i, a in enumerate(np.linspace(0, 2 * math.pi, 9, endpoint=False))]
    )  # fmt: skip
    sq = np.array([[5, 5], [6, 5], [6, 6], [5, 6]], dtype=float)
    obs = ObstacleSet(np.array([[-5.0, 5.0, 1.0], [4.0, -4.0, 0.5]]), (star, sq))
    P = rng.uniform(-8, 8, (40, 50, 2))
    B = rng.uniform(-8, 8, (50, 2))
    pc, sc = obs.point_clearance(P), obs.segment_clearance(P, B)
    inside, signed = points_in_polygon(P, star), point_polygon_distance(P, star)
    seg = segment_polygon_distance(P, B, star)
    assert pc.shape == sc.shape == inside.shape == signed.shape == seg.shape == (40, 50)
    idx = rng.integers(0, 40, 30), rng.integers(0, 50, 30)
    for i, j in zip(*idx, strict=True):
        assert pc[i, j] == obs.point_clearance(P[i, j])
        assert sc[i, j] == obs.segment_clearance(P[i, j], B[j])
        assert inside[i, j] == points_in_polygon(P[i, j], star)
        assert signed[i, j] == point_polygon_distance(P[i, j], star)
        assert seg[i, j] == segment_polygon_distance(P[i, j], B[j], star)
