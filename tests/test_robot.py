"""Kinematics invariants and virtual sensors."""

import itertools
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmpath.robot import DiffDrive, Omni, Pose, get_sensor_model, read_sensors
from swarmpath.robot.kinematics import aligned_drive_command, diff_drive_command
from swarmpath.robot.sensors import ray_circle_distance, ray_segment_distance

BURGER = DiffDrive(wheel_radius=0.033, wheel_separation=0.160, max_linear=0.22, max_angular=2.84)
ICOOT = DiffDrive(
    wheel_radius=0.034, wheel_separation=0.160, max_linear=0.5, max_angular=0.5 / 0.034
)


def test_wheel_and_body_speeds_are_inverse():
    for v, w in [(0.1, 0.0), (0.2, 1.0), (-0.1, -2.0), (0.0, 1.5)]:
        assert BURGER.body_speed(*BURGER.wheel_speeds(v, w)) == pytest.approx((v, w))


@given(st.floats(-1, 1), st.floats(-10, 10))
def test_saturation_keeps_curvature_and_limits(v, w):
    sv, sw = BURGER.saturate(v, w)
    assert abs(sv) <= BURGER.max_linear + 1e-12 and abs(sw) <= BURGER.max_angular + 1e-12
    right, left = BURGER.wheel_speeds(sv, sw)
    assert max(abs(right), abs(left)) * BURGER.wheel_radius <= BURGER.max_linear + 1e-12
    if abs(v) > 1e-9 and abs(w) > 1e-9:
        assert sw / sv == pytest.approx(w / v)  # same curvature


def test_burger_limits_are_not_reachable_together():
    v, w = BURGER.saturate(0.22, 2.84)
    assert v < 0.22 and w < 2.84 and w / v == pytest.approx(2.84 / 0.22)


@settings(max_examples=50)
@given(st.floats(0.01, 0.2), st.floats(-2.0, 2.0), st.floats(-math.pi, math.pi))
def test_arc_step_is_exact(v, w, theta):
    """One long step equals many short ones for a constant command (exact arc integration)."""
    start = Pose(1.0, 2.0, theta)
    one = BURGER.advance(start, v, w, 2.0)
    many = start
    for _ in range(400):
        many = BURGER.advance(many, v, w, 2.0 / 400)
    assert (one.x, one.y) == pytest.approx((many.x, many.y), abs=1e-9)
    assert math.cos(one.theta - many.theta) == pytest.approx(1.0)


def test_full_circle_returns_home_and_radius_is_v_over_w():
    v, w = 0.1, 0.5
    p = BURGER.advance(Pose(0, 0, 0), v, w, 2 * math.pi / w)
    assert (p.x, p.y) == pytest.approx((0, 0), abs=1e-12)
    half = BURGER.advance(Pose(0, 0, 0), v, w, math.pi / w)
    assert half.y == pytest.approx(2 * v / w)


def test_omni_moves_sideways_and_matches_fine_integration():
    omni = Omni(max_linear=1.0, max_angular=2.0)
    p = omni.advance(Pose(0, 0, math.pi / 2), 0.0, 0.5, 0.0, 2.0)  # body-left while facing +y
    assert (p.x, p.y) == pytest.approx((-1.0, 0.0))
    one = omni.advance(Pose(0, 0, 0.3), 0.4, -0.2, 0.7, 3.0)
    q = Pose(0, 0, 0.3)
    for _ in range(3000):
        q = omni.advance(q, 0.4, -0.2, 0.7, 0.001)
    assert (one.x, one.y) == pytest.approx((q.x, q.y), abs=1e-6)


def test_waypoint_controller_reaches_target():
    pose = Pose(0, 0, 0)
    for _ in range(400):
        v, w = diff_drive_command(ICOOT, pose, (1.0, 1.0), 0.05)
        pose = ICOOT.advance(pose, v, w, 0.05)
    assert math.hypot(pose.x - 1, pose.y - 1) < 1e-3


# ------------------------------------------------------------------------------ sensors
def test_aligned_drive_follows_a_polyline_exactly():
    model = DiffDrive(0.033, 0.16, 0.22, 2.84)
    corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (-0.5, 0.2), (0.3, -0.7)]
    pose, dt = Pose(0.0, 0.0, 2.0), 0.1
    worst = 0.0
    for (ax, ay), (bx, by) in itertools.pairwise(corners):
        for _ in range(500):
            v, w = aligned_drive_command(model, pose, (bx, by), dt)
            if v == 0.0 and w == 0.0:
                break
            pose = model.advance(pose, v, w, dt)
            # distance of the centre from the segment it was sent along
            d = abs((bx - ax) * (pose.y - ay) - (by - ay) * (pose.x - ax)) / math.hypot(
                bx - ax, by - ay)
            worst = max(worst, d)
        assert math.hypot(pose.x - bx, pose.y - by) < 1e-4
    assert worst < 1e-9
    # the ordinary controller turns while driving and leaves the segment at the corners
    pose, off = Pose(1.0, 0.0, 0.0), 0.0
    for _ in range(200):
        v, w = diff_drive_command(model, pose, (1.0, 1.0), dt)
        pose = model.advance(pose, v, w, dt)
        off = max(off, abs(pose.x - 1.0))
    assert off > 1e-3


def test_mfb12_layout_and_gap_vector():
    model = get_sensor_model("mfb-12")
    assert model.n_sensors == 12 and np.all(model.ranges == 0.8)
    # obstacle straight ahead: sensor 0 covers [-15, 15] degrees
    reading = read_sensors(model, 0, 0, 0, 0.5, np.array([[1.5, 0.0, 0.3]]), ())
    assert reading.fired[0] and reading.fired.sum() == 1
    assert reading.nearest[0] == pytest.approx(1.5 - 0.3 - 0.5, abs=0.01)
    gaps = reading.gap_vector()
    assert gaps[0] and gaps[11] and gaps.sum() == 2  # Vg_i = Vs_i OR Vs_{i+1}
    far = read_sensors(model, 0, 0, 0, 0.5, np.array([[2.0, 0.0, 0.3]]), ())
    assert not far.fired.any()  # 1.2 m from the body: beyond 0.8 m


def test_icoot80_layers():
    model = get_sensor_model("icoot-80")
    assert model.n_sensors == 80
    counts = np.bincount(model.sensor_of_ray)
    assert len(counts) == 80 and np.all(counts == counts[0])
    assert sorted(set(np.round(model.ranges, 9))) == [0.5, 1.0, 1.5, 2.0]


def test_heading_rotates_the_sensors():
    model = get_sensor_model("mfb-12")
    circle = np.array([[0.0, 1.5, 0.3]])  # to the left in the world
    facing_x = read_sensors(model, 0, 0, 0.0, 0.5, circle, ())
    facing_y = read_sensors(model, 0, 0, math.pi / 2, 0.5, circle, ())
    assert facing_x.fired[3] and facing_y.fired[0]


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-3, 3), st.floats(-3, 3), st.floats(0.1, 1.0),
    st.floats(-math.pi, math.pi),
)
def test_ray_casting_matches_shapely(cx, cy, r, angle):
    origin = np.array([0.0, 0.0])
    d = np.array([[math.cos(angle), math.sin(angle)]])
    ours = ray_circle_distance(origin, d, np.array([[cx, cy, r]]))[0]
    if math.hypot(cx, cy) < r - 1e-9:
        assert ours == 0.0
        return
    # shapely's disk is a polygon: compare against a slightly shrunken one, robust at grazing rays
    core = shapely.Point(cx, cy).buffer(r - 1e-4, quad_segs=256)
    if math.isinf(ours):
        assert not shapely.LineString([(0, 0), (100 * d[0, 0], 100 * d[0, 1])]).intersects(core)
    else:
        hit = ours * d[0]
        assert math.hypot(hit[0] - cx, hit[1] - cy) == pytest.approx(r, abs=1e-9)
        before = max(ours - 1e-6, 0.0) * d[0]
        assert not shapely.LineString([(0, 0), tuple(before)]).intersects(core)


def test_ray_hits_polygon_edges():
    square = np.array([[1.0, -1.0], [2.0, -1.0], [2.0, 1.0], [1.0, 1.0]])
    A, B = square, np.roll(square, -1, axis=0)
    dirs = np.array([[1.0, 0.0], [-1.0, 0.0], [math.cos(0.3), math.sin(0.3)]])
    t = ray_segment_distance(np.zeros(2), dirs, A, B)
    assert t[0] == pytest.approx(1.0) and math.isinf(t[1])
    assert t[2] == pytest.approx(1 / math.cos(0.3))
    model = get_sensor_model("mfb-12")
    inside = read_sensors(model, 1.5, 0.0, 0.0, 0.1, np.zeros((0, 3)), (square,))
    assert inside.fired.all()
