"""Robot motion models: differential drive (ICOOT/IHPO, TurtleBot3) and omnidirectional (MFB).

Differential drive, eqs 33-39 of the ICOOT paper (Abdulsaheb & Kadhim 2022, after Siegwart et al.):
with wheel radius r, half wheel separation l and wheel speeds phi_1 (right), phi_2 (left),

    xi_dot_I = R(theta)^-1 [r (phi_1 + phi_2) / 2, 0, r (phi_1 - phi_2) / (2 l)]^T,

i.e. body speed v = r (phi_1 + phi_2) / 2 and turn rate w = r (phi_1 - phi_2) / (2 l). A command
(v, w) is turned into wheel speeds, each wheel is capped at its limit *keeping the curvature*
(scaling both wheels together, as a real drive saturates), and the pose is advanced with the exact
arc for constant (v, w) over the step, so the trajectory is exact for piecewise-constant commands.

Omnidirectional (Ajeil et al. 2020): body-frame velocities (vx, vy, w) rotated into the world frame;
the speed limit applies to the norm of (vx, vy).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Distance (m) at which a waypoint counts as reached, for the controllers and the simulator alike.
ARRIVE = 1e-4


def wrap_angle(a: float) -> float:
    """Angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


@dataclass(frozen=True)
class Pose:
    x: float
    y: float
    theta: float

    def as_array(self) -> np.ndarray:
        return np.array([self.x, self.y, self.theta])


@dataclass(frozen=True)
class DiffDrive:
    """Two-wheeled differential drive; speeds in m/s and rad/s."""

    wheel_radius: float
    wheel_separation: float
    max_linear: float
    max_angular: float

    @property
    def max_wheel_speed(self) -> float:
        """Wheel rim speed limit (m/s) implied by the linear limit."""
        return self.max_linear

    def wheel_speeds(self, v: float, w: float) -> tuple[float, float]:
        """Right and left wheel angular speeds (rad/s) for body command (v, w)."""
        half = self.wheel_separation / 2.0
        return (v + w * half) / self.wheel_radius, (v - w * half) / self.wheel_radius

    def body_speed(self, phi_right: float, phi_left: float) -> tuple[float, float]:
        """Eq 38: (v, w) from wheel angular speeds."""
        r, half = self.wheel_radius, self.wheel_separation / 2.0
        return r * (phi_right + phi_left) / 2.0, r * (phi_right - phi_left) / (2.0 * half)

    def saturate(self, v: float, w: float) -> tuple[float, float]:
        """Cap |v|, |w| and each wheel's rim speed, scaling (v, w) together (same curvature)."""
        scale = 1.0
        if abs(v) > self.max_linear:
            scale = min(scale, self.max_linear / abs(v))
        if abs(w) > self.max_angular:
            scale = min(scale, self.max_angular / abs(w))
        half = self.wheel_separation / 2.0
        rim = max(abs(v + w * half), abs(v - w * half))
        if rim > self.max_wheel_speed:
            scale = min(scale, self.max_wheel_speed / rim)
        return v * scale, w * scale

    def advance(self, pose: Pose, v: float, w: float, dt: float) -> Pose:
        """Exact pose after dt under constant (saturated) command (v, w)."""
        v, w = self.saturate(v, w)
        dx, dy = _arc_displacement(v, 0.0, pose.theta, w, dt)
        return Pose(pose.x + dx, pose.y + dy, wrap_angle(pose.theta + w * dt))


@dataclass(frozen=True)
class Omni:
    """Omnidirectional base: body-frame (vx, vy, w)."""

    max_linear: float
    max_angular: float

    def saturate(self, vx: float, vy: float, w: float) -> tuple[float, float, float]:
        speed = math.hypot(vx, vy)
        if speed > self.max_linear:
            vx, vy = vx * self.max_linear / speed, vy * self.max_linear / speed
        return vx, vy, max(-self.max_angular, min(self.max_angular, w))

    def advance(self, pose: Pose, vx: float, vy: float, w: float, dt: float) -> Pose:
        """Pose after dt with body velocity (vx, vy) and turn rate w held constant.

        The world-frame velocity rotates with the body; integrated exactly for constant w.
        """
        vx, vy, w = self.saturate(vx, vy, w)
        dx, dy = _arc_displacement(vx, vy, pose.theta, w, dt)
        return Pose(pose.x + dx, pose.y + dy, wrap_angle(pose.theta + w * dt))


def _arc_displacement(
    vx: float, vy: float, theta: float, w: float, dt: float
) -> tuple[float, float]:
    """World displacement of a body moving at body-frame (vx, vy) while turning at w for dt.

    Exact: integral of R(theta + w s) [vx, vy] ds = dt sinc(w dt / 2) R(theta + w dt / 2) [vx, vy],
    written with sinc so that w -> 0 is stable (no v / w cancellation).
    """
    half = 0.5 * w * dt
    factor = dt * (math.sin(half) / half if abs(half) > 1e-9 else 1.0 - half * half / 6.0)
    mid = theta + half
    c, s = math.cos(mid), math.sin(mid)
    return factor * (c * vx - s * vy), factor * (s * vx + c * vy)


def diff_drive_command(
    model: DiffDrive,
    pose: Pose,
    target: tuple[float, float],
    dt: float,
    gain: float = 4.0,
    arrive: float | None = None,
) -> tuple[float, float]:
    """Waypoint tracking for a differential drive: turn toward the target, then drive.

    w = gain * heading error (capped), v = max_linear * cos(error) when the error is under 90
    degrees, else 0 (turn in place), and never overshooting the target within one step. Within
    ``arrive`` metres of the target the robot stops (no dithering on the spot).
    """
    dx, dy = target[0] - pose.x, target[1] - pose.y
    dist = math.hypot(dx, dy)
    if dist < (ARRIVE if arrive is None else arrive):
        return 0.0, 0.0
    err = wrap_angle(math.atan2(dy, dx) - pose.theta)
    w = max(-model.max_angular, min(model.max_angular, gain * err))
    if abs(w) * dt > abs(err):  # do not overshoot the heading within this step
        w = err / dt
    v = 0.0 if abs(err) >= math.pi / 2 else model.max_linear * math.cos(err)
    v = min(v, dist / dt)
    return v, w


#: Heading error (rad) below which :func:`aligned_drive_command` drives instead of turning.
ALIGN_TOLERANCE = 1e-9


def aligned_drive_command(
    model: DiffDrive,
    pose: Pose,
    target: tuple[float, float],
    dt: float,
    tolerance: float = ALIGN_TOLERANCE,
    arrive: float | None = None,
) -> tuple[float, float]:
    """Turn in place until facing the target, then drive straight at it (a polyline follower).

    While the heading error exceeds ``tolerance`` the robot turns in place at up to
    ``max_angular``, landing exactly on the heading in the last step (w = error / dt); then it
    drives at up to ``max_linear`` without overshooting, correcting the (round-off) error with
    w = error / dt. The centre therefore moves along the straight segment from where it stands to
    the target, which is what a planner whose segments were collision-checked needs: unlike
    :func:`diff_drive_command`, no arc bulges off the checked segment. Within ``arrive`` metres
    (default :data:`ARRIVE`) of the target it stops.
    """
    dx, dy = target[0] - pose.x, target[1] - pose.y
    dist = math.hypot(dx, dy)
    if dist < (ARRIVE if arrive is None else arrive):
        return 0.0, 0.0
    err = wrap_angle(math.atan2(dy, dx) - pose.theta)
    w = max(-model.max_angular, min(model.max_angular, err / dt))
    if abs(err) > tolerance:
        return 0.0, w
    return min(model.max_linear, dist / dt), w


def omni_command(model: Omni, pose: Pose, target: tuple[float, float], dt: float) -> tuple[
    float, float, float
]:
    """Drive straight at the target at full speed (body frame), no rotation needed."""
    dx, dy = target[0] - pose.x, target[1] - pose.y
    dist = math.hypot(dx, dy)
    if dist < 1e-9:
        return 0.0, 0.0, 0.0
    speed = min(model.max_linear, dist / dt)
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    wx, wy = dx / dist * speed, dy / dist * speed
    return c * wx + s * wy, -s * wx + c * wy, 0.0
