"""swarmpath.world.optimum: analytic cases, a grid A* cross-check and the MFB static map."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from swarmpath.world.geometry import ObstacleSet, point_segment_distance
from swarmpath.world.optimum import OptimalPath, _sorted_csr, shortest_path

# The MFB paper's static map (Ajeil et al. 2020, Table 3): ten circles of radius 0.5.
MFB_CENTRES = [
    (2, 2.3), (5.8, 4.3), (8.5, 2), (2, 6.5), (8.5, 5),
    (7.7, 8), (3, 9), (5, 1), (3, 4.5), (5, 7.2),
]  # fmt: skip
MFB_BEST_REPORTED = 14.6268  # the paper's best path (Hybrid PSO-MFB, Table 4, run 10)
MFB_OPTIMUM = 14.482999744658636  # this module's exact value, recorded in docs/metrics.md


def _circles(rows: list[tuple[float, float, float]]) -> ObstacleSet:
    return ObstacleSet(np.asarray(rows, dtype=float).reshape(-1, 3), ())


def _polyline_length(P: np.ndarray) -> float:
    return float(np.sum(np.hypot(*np.diff(P, axis=0).T)))


def _check_polyline(res: OptimalPath, obs: ObstacleSet, margin: float, start, goal) -> None:
    P = res.points
    assert np.allclose(P[0], start) and np.allclose(P[-1], goal)
    assert float(obs.segment_clearance(P[:-1], P[1:]).min()) >= margin - 1e-6
    # chords of the sampled arcs are a little shorter than the arcs
    assert _polyline_length(P) == pytest.approx(res.length, abs=1e-5)
    assert res.length >= math.dist(start, goal) - 1e-12


# ----------------------------------------------------------------------------- analytic cases


def test_straight_line_when_free() -> None:
    obs = _circles([(5.0, 3.0, 1.0), (2.0, -2.0, 0.5)])
    res = shortest_path((0.0, 0.0), (10.0, 0.0), obs, 0.5, (-1, -5, 11, 5))
    assert res.exact and res.reason is None
    assert res.length == 10.0
    assert res.points.tolist() == [[0.0, 0.0], [10.0, 0.0]]
    empty = shortest_path((1.0, 2.0), (4.0, 6.0), ObstacleSet.empty(), 0.3)
    assert empty.length == 5.0


def test_line_grazing_an_inflated_circle_is_allowed() -> None:
    # clearance exactly margin: the infimum touches the inflated obstacle
    obs = _circles([(5.0, 1.0, 0.5)])
    res = shortest_path((0.0, 0.0), (10.0, 0.0), obs, 0.5)
    assert res.length == pytest.approx(10.0, abs=1e-12)


def _around_circle(s, g, c, rho) -> float:
    """Tangent + arc + tangent around one circle, on the side of the smaller angle."""
    ds, dg = math.dist(s, c), math.dist(g, c)
    us = np.subtract(s, c) / ds
    ug = np.subtract(g, c) / dg
    theta = math.acos(float(np.clip(us @ ug, -1.0, 1.0)))
    arc = theta - math.acos(rho / ds) - math.acos(rho / dg)
    return math.sqrt(ds**2 - rho**2) + math.sqrt(dg**2 - rho**2) + rho * arc


def test_single_circle_analytic() -> None:
    R, m = 1.0, 0.5
    rho = R + m
    res = shortest_path((-5.0, 0.0), (5.0, 0.0), _circles([(0.0, 0.0, R)]), m)
    want = 2 * math.sqrt(25 - rho**2) + rho * (math.pi - 2 * math.acos(rho / 5))
    assert res.length == pytest.approx(want, abs=1e-9)
    assert res.exact
    _check_polyline(res, _circles([(0.0, 0.0, R)]), m, (-5.0, 0.0), (5.0, 0.0))


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.0, 2 * math.pi),
    st.floats(0.0, 2 * math.pi),
    st.floats(2.0, 6.0),
    st.floats(2.0, 6.0),
    st.floats(0.3, 1.5),
    st.floats(0.0, 0.5),
)
def test_single_circle_analytic_random(a1, a2, d1, d2, R, m) -> None:
    s = (d1 * math.cos(a1), d1 * math.sin(a1))
    g = (d2 * math.cos(a2), d2 * math.sin(a2))
    obs = _circles([(0.0, 0.0, R)])
    res = shortest_path(s, g, obs, m)
    if float(point_segment_distance(np.zeros(2), np.array(s), np.array(g))) >= R + m:
        assert res.length == pytest.approx(math.dist(s, g), abs=1e-9)
        return
    assert res.length == pytest.approx(_around_circle(s, g, (0.0, 0.0), R + m), abs=1e-9)


def test_square_margin_zero_visibility_graph() -> None:
    sq = np.array([[1, -1], [3, -1], [3, 1], [1, 1]], dtype=float)
    obs = ObstacleSet(np.zeros((0, 3)), (sq,))
    res = shortest_path((0.0, 0.0), (4.0, 0.0), obs, 0.0)
    assert res.length == pytest.approx(2 + 2 * math.sqrt(2), abs=1e-12)
    assert res.exact
    # the chord through the square's interior is not used
    res2 = shortest_path((0.5, -1.5), (3.5, 1.5), obs, 0.0)
    # through one corner: (3, -1) or, symmetrically, (1, 1)
    want = math.dist((0.5, -1.5), (3, -1)) + math.dist((3, -1), (3.5, 1.5))
    assert res2.length == pytest.approx(want, abs=1e-12)
    assert res2.length > math.dist((0.5, -1.5), (3.5, 1.5)) + 0.1
    assert len(res2.points) == 3


def test_non_convex_polygon_margin_zero() -> None:
    # A U open at the top; from below into the notch: around the right arm, along its edges.
    u = np.array([[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], dtype=float)
    for poly in (u, u[::-1].copy()):
        obs = ObstacleSet(np.zeros((0, 3)), (poly,))
        res = shortest_path((1.5, -1.0), (1.5, 2.0), obs, 0.0)
        want = math.sqrt(3.25) + 3 + 1 + math.sqrt(1.25)
        assert res.length == pytest.approx(want, abs=1e-12)
        right = [[1.5, -1.0], [3.0, 0.0], [3.0, 3.0], [2.0, 3.0], [1.5, 2.0]]
        left = [[1.5, -1.0], [0.0, 0.0], [0.0, 3.0], [1.0, 3.0], [1.5, 2.0]]
        assert res.points.tolist() in (right, left)


def test_square_with_margin_analytic() -> None:
    sq = np.array([[1, -1], [3, -1], [3, 1], [1, 1]], dtype=float)
    obs = ObstacleSet(np.zeros((0, 3)), (sq,))
    m = 0.5
    res = shortest_path((0.0, 0.0), (4.0, 0.0), obs, m)
    d = math.sqrt(2.0)
    arc = 0.75 * math.pi - math.acos(m / d)  # from the tangent point up to the top of the disk
    want = 2 * (math.sqrt(d * d - m * m) + m * arc) + 2.0
    assert res.length == pytest.approx(want, abs=1e-9)
    _check_polyline(res, obs, m, (0.0, 0.0), (4.0, 0.0))


def test_touching_rectangles_act_as_one_obstacle() -> None:
    a = np.array([[1, -1], [2, -1], [2, 1], [1, 1]], dtype=float)
    b = np.array([[2, -1], [3, -1], [3, 1], [2, 1]], dtype=float)
    merged = np.array([[1, -1], [3, -1], [3, 1], [1, 1]], dtype=float)
    split = shortest_path((0.0, 0.0), (4.0, 0.0), ObstacleSet(np.zeros((0, 3)), (a, b)), 0.3)
    whole = shortest_path((0.0, 0.0), (4.0, 0.0), ObstacleSet(np.zeros((0, 3)), (merged,)), 0.3)
    assert split.length == pytest.approx(whole.length, abs=1e-9)


def test_margin_zero_does_not_squeeze_between_touching_polygons() -> None:
    # two rectangles sharing the edge x = 5, 2 <= y <= 3: no passage along it
    tall = np.array([[4, 2], [5, 2], [5, 6], [4, 6]], dtype=float)
    low = np.array([[5, 2], [6, 2], [6, 3], [5, 3]], dtype=float)
    obs = ObstacleSet(np.zeros((0, 3)), (tall, low))
    res = shortest_path((5.0, 0.0), (5.5, 4.0), obs, 0.0)
    want = math.dist((5, 0), (6, 2)) + 1.0 + math.dist((6, 3), (5.5, 4))
    assert res.length == pytest.approx(want, abs=1e-12)


def test_mixed_circle_and_polygon_margin_zero() -> None:
    # a circle resting in front of a wall: at margin 0 the path wraps the circle, not the wall
    wall = np.array([[4, -3], [4.2, -3], [4.2, 3], [4, 3]], dtype=float)
    obs = ObstacleSet(np.array([[2.0, 0.0, 1.0]]), (wall,))
    res = shortest_path((0.0, 0.0), (6.0, 0.0), obs, 0.0)
    alone = shortest_path((0.0, 0.0), (6.0, 0.0), ObstacleSet(np.zeros((0, 3)), (wall,)), 0.0)
    assert res.length >= alone.length - 1e-12
    _check_polyline(res, obs, 0.0, (0.0, 0.0), (6.0, 0.0))


@pytest.mark.parametrize("seed", range(10))
def test_margin_zero_agrees_with_a_tiny_margin(seed: int) -> None:
    """The margin-0 special cases (visibility graph, interior tests) against the general path."""
    rng = np.random.default_rng(100 + seed)
    polys = []
    for _ in range(4):
        c, n = rng.uniform(1.5, 8.5, 2), int(rng.integers(3, 7))
        ang = np.linspace(0, 2 * math.pi, n, endpoint=False) + rng.uniform(0, 1)
        r = rng.uniform(0.4, 1.4, n)
        polys.append(c + np.column_stack([r * np.cos(ang), r * np.sin(ang)]))
    polys.append(np.array([[4, 2], [5, 2], [5, 6], [4, 6]], dtype=float))  # two rectangles
    polys.append(np.array([[5, 2], [6, 2], [6, 3], [5, 3]], dtype=float))  # sharing an edge
    circles = np.column_stack([rng.uniform(1.5, 8.5, (2, 2)), rng.uniform(0.3, 0.8, 2)])
    obs = ObstacleSet(circles, tuple(polys))
    ends = [p for p in rng.uniform(0, 10, (50, 2)) if obs.point_clearance(p) > 1e-3]
    start, goal = ends[0], ends[1]
    exact0 = shortest_path(start, goal, obs, 0.0)
    tiny = shortest_path(start, goal, obs, 1e-6)
    assert exact0.length <= tiny.length + 1e-9
    assert tiny.length - exact0.length < 1e-4
    _check_polyline(exact0, obs, 0.0, start, goal)


def test_reversal_symmetry() -> None:
    obs = _circles([(c[0], c[1], 0.5) for c in MFB_CENTRES])
    a = shortest_path((0.0, 0.0), (10.0, 10.0), obs, 0.5, (0, 0, 10, 10))
    b = shortest_path((10.0, 10.0), (0.0, 0.0), obs, 0.5, (0, 0, 10, 10))
    assert a.length == pytest.approx(b.length, abs=1e-9)


# ----------------------------------------------------------------------------- world box, errors


def test_world_box_forces_the_other_side() -> None:
    obs = _circles([(5.0, 1.2, 0.5)])
    free = shortest_path((0.0, 1.0), (10.0, 1.0), obs, 0.0)
    boxed = shortest_path((0.0, 1.0), (10.0, 1.0), obs, 0.0, (0.0, 0.75, 10.0, 3.0))
    # the lower route (shorter) needs y down to 0.7 < 0.75: a wall under the circle is equivalent
    wall = np.array([[4.5, -5], [5.5, -5], [5.5, 0.75], [4.5, 0.75]], dtype=float)
    walled = shortest_path((0.0, 1.0), (10.0, 1.0), ObstacleSet(obs.circles, (wall,)), 0.0)
    assert boxed.length > free.length + 1e-3
    assert boxed.length == pytest.approx(walled.length, abs=1e-9)
    assert boxed.points[:, 1].min() >= 0.75 - 1e-12
    assert boxed.exact


def test_world_box_closes_the_passage() -> None:
    obs = _circles([(5.0, 0.6, 0.5)])
    res = shortest_path((0.0, 1.0), (10.0, 1.0), obs, 0.2, (0.0, 0.0, 10.0, 1.25))
    assert res.length == math.inf and res.exact and res.points.shape == (0, 2)


def test_no_path_when_goal_enclosed() -> None:
    ring = [(5 + 2 * math.cos(a), 5 + 2 * math.sin(a), 0.6) for a in np.linspace(0, 6.28, 12)]
    res = shortest_path((0.0, 0.0), (5.0, 5.0), _circles(ring), 0.1)
    assert res.length == math.inf
    assert res.reason is not None


def test_start_or_goal_inside_raises() -> None:
    obs = ObstacleSet(
        np.array([[5.0, 5.0, 1.0]]), (np.array([[0, 8], [2, 8], [2, 9], [0, 9]], dtype=float),)
    )
    with pytest.raises(ValueError, match=r"start .*circle 0"):
        shortest_path((5.0, 6.2), (0.0, 0.0), obs, 0.5)
    with pytest.raises(ValueError, match=r"goal .*polygon 0"):
        shortest_path((0.0, 0.0), (1.0, 7.8), obs, 0.5)
    with pytest.raises(ValueError, match=r"goal .*outside the world"):
        shortest_path((0.0, 0.0), (11.0, 7.8), obs, 0.5, (0, 0, 10, 10))
    with pytest.raises(ValueError, match="margin"):
        shortest_path((0.0, 0.0), (1.0, 1.0), obs, -0.1)


def test_complexity_cap() -> None:
    polys = tuple(
        np.array([[x, y], [x + 0.5, y], [x + 0.5, y + 0.5], [x, y + 0.5]], dtype=float)
        for x in range(1, 12)
        for y in range(1, 12)
    )
    obs = ObstacleSet(np.zeros((0, 3)), polys)
    res = shortest_path((0.0, 0.0), (12.8, 12.8), obs, 0.1, max_disks=400)
    assert not res.exact and math.isnan(res.length) and "max_disks" in (res.reason or "")


# ----------------------------------------------------------------------------- grid A* cross-check


def _grid_path(start, goal, obs: ObstacleSet, margin: float, world, h: float) -> np.ndarray:
    """A collision-free path: 8-connected grid Dijkstra, then greedy any-angle shortcutting.

    Grid nodes need clearance > margin + 0.75 h so that every grid move (length <= h sqrt 2)
    stays clear by more than margin; start and goal connect to nearby nodes by checked segments.
    """
    x0, y0, x1, y1 = world
    xs, ys = np.arange(x0, x1 + 1e-9, h), np.arange(y0, y1 + 1e-9, h)
    nx, ny = len(xs), len(ys)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    P = np.stack([X, Y], axis=-1).reshape(-1, 2)
    free = obs.point_clearance(P) > margin + 0.75 * h
    ids = np.arange(nx * ny).reshape(nx, ny)
    us, vs, ws = [], [], []
    for dx, dy in ((1, 0), (0, 1), (1, 1), (1, -1)):
        a = ids[max(0, -dx) : nx - max(0, dx), max(0, -dy) : ny - max(0, dy)].ravel()
        b = ids[max(0, dx) :, max(0, dy) : ny + min(0, dy)].ravel() if dy >= 0 else None
        if b is None:
            b = ids[dx:, : ny + dy].ravel()
            a = ids[: nx - dx, -dy:].ravel()
        ok = free[a] & free[b]
        us.append(a[ok])
        vs.append(b[ok])
        ws.append(np.full(int(ok.sum()), h * math.hypot(dx, dy)))
    n = nx * ny
    S, G = n, n + 1
    pts = np.vstack([P, start, goal])
    for node, q in ((S, start), (G, goal)):
        near = np.flatnonzero(free & (np.hypot(*(P - q).T) < 3 * h))
        near = near[obs.segment_clearance(np.asarray(q)[None], P[near]) > margin]
        us.append(np.full(len(near), node))
        vs.append(near)
        ws.append(np.hypot(*(P[near] - q).T))
    u, v, w = map(np.concatenate, (us, vs, ws))
    graph = coo_matrix((w, (u, v)), shape=(n + 2, n + 2)).tocsr()
    dist, pred = dijkstra(graph, directed=False, indices=S, return_predecessors=True)
    assert math.isfinite(dist[G]), "grid found no path"
    chain = [G]
    while chain[-1] != S:
        chain.append(int(pred[chain[-1]]))
    path = pts[chain[::-1]]
    out, i = [path[0]], 0
    while i < len(path) - 1:
        clear = obs.segment_clearance(path[i][None], path[i + 1 :]) > margin
        j = i + 1 + int(np.flatnonzero(clear)[-1])  # the next vertex is always visible
        out.append(path[j])
        i = j
    return np.asarray(out)


def _random_instance(seed: int) -> tuple[ObstacleSet, float, tuple, tuple]:
    rng = np.random.default_rng(seed)
    circles = np.column_stack([rng.uniform(1.5, 8.5, (8, 2)), rng.uniform(0.3, 0.9, 8)])
    polys = []
    for _ in range(2):
        c = rng.uniform(2.0, 8.0, 2)
        ang = np.sort(rng.uniform(0, 2 * math.pi, 5))
        ang = (
            ang
            if np.max(np.diff(np.r_[ang, ang[0] + 2 * math.pi])) < 2.8
            else np.linspace(0, 2 * math.pi, 5, endpoint=False)
        )
        r = rng.uniform(0.4, 1.0, 5)
        polys.append(c + np.column_stack([r * np.cos(ang), r * np.sin(ang)]))
    obs = ObstacleSet(circles, tuple(polys))
    margin = float(rng.uniform(0.1, 0.35))
    # start on the left, goal on the right, so that the obstacles are in the way
    pts = rng.uniform(0.3, 9.7, (400, 2))
    ok = pts[obs.point_clearance(pts) > margin + 0.2]
    left, right = ok[ok[:, 0] < 2.0], ok[ok[:, 0] > 8.0]
    return obs, margin, tuple(left[0]), tuple(right[0])


@pytest.mark.parametrize("seed", range(8))
def test_optimum_matches_grid_astar(seed: int) -> None:
    obs, margin, start, goal = _random_instance(seed)
    world = (0.0, 0.0, 10.0, 10.0)
    h = 0.05
    res = shortest_path(start, goal, obs, margin, world)
    assert res.exact
    _check_polyline(res, obs, margin, start, goal)
    grid = _grid_path(start, goal, obs, margin, world, h)
    assert float(obs.segment_clearance(grid[:-1], grid[1:]).min()) > margin
    grid_len = _polyline_length(grid)
    # the optimum is a lower bound of every collision-free path ...
    assert res.length <= grid_len + 1e-9
    # ... and the grid gets within a few % of it, except through passages narrower than its
    # conservative free space (clearance > margin + 0.75 h), which it cannot enter: compare
    # with the optimum for that larger margin, which closes the same passages.
    wide = shortest_path(start, goal, obs, margin + 0.75 * h, world)
    assert grid_len <= wide.length * 1.04
    if wide.length <= res.length * 1.01:  # no narrow passage on the way
        assert grid_len <= res.length * 1.03


# ----------------------------------------------------------------------------- MFB static map


def test_mfb_static_map_optimum() -> None:
    obs = _circles([(x, y, 0.5) for x, y in MFB_CENTRES])
    world = (0.0, 0.0, 10.0, 10.0)
    res = shortest_path((0.0, 0.0), (10.0, 10.0), obs, 0.5, world)
    assert res.exact
    assert res.length == pytest.approx(MFB_OPTIMUM, abs=1e-9)
    assert res.length <= MFB_BEST_REPORTED
    _check_polyline(res, obs, 0.5, (0.0, 0.0), (10.0, 10.0))
    grid = _grid_path((0.0, 0.0), (10.0, 10.0), obs, 0.5, world, 0.05)
    grid_len = _polyline_length(grid)
    assert res.length <= grid_len <= res.length * 1.02


def test_sorted_csr_is_the_canonical_matrix_of_its_entries() -> None:
    """The search's graph built straight from its (row, column)-sorted edges equals scipy's own
    COO -> CSR conversion entry for entry, including empty rows and an empty graph."""
    rng = np.random.default_rng(3)
    for n, m in ((1, 0), (7, 12), (60, 400)):
        keys = np.unique(rng.integers(0, n * n, size=m))
        rows, cols = keys // n, keys % n
        w = rng.random(len(keys))
        ours = _sorted_csr(rows, cols, w, n)
        ref = coo_matrix((w, (rows, cols)), shape=(n, n)).tocsr()
        assert ours.shape == ref.shape
        np.testing.assert_array_equal(ours.indptr, ref.indptr)
        np.testing.assert_array_equal(ours.indices, ref.indices)
        np.testing.assert_array_equal(ours.data, ref.data)
        if n > 1:
            a = dijkstra(ours, directed=False, indices=0, return_predecessors=True)
            b = dijkstra(ref, directed=False, indices=0, return_predecessors=True)
            np.testing.assert_array_equal(a[0], b[0])
            np.testing.assert_array_equal(a[1], b[1])
