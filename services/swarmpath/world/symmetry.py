"""Copies of a static scenario moved by a symmetry of the plane (pure; no I/O).

A planner that does not favour a place or a direction solves a map and its rotated, mirrored or
translated copy alike (the exact optimum is the same), and a start/goal swap too (the shortest
path is the same, reversed). :func:`symmetric_copy` makes each copy; ``swarmpath audit --maps``
(:mod:`swarmpath.evidence.map_audit`) runs planners on them and tests whether success and path
length move, as ``swarmpath audit`` does for optimizers whose search is pulled toward the
origin.

The world stays ``[0, w] x [0, h]`` with its origin at the lower left, so every copy is a valid
scenario: a rotation by 90 or 270 degrees swaps w and h; the translation moves the whole
scenario by (w/2, h/2) inside a world of (1.5 w, 1.5 h): the world's centre and corner move with
respect to the obstacles (what a planner seeded towards the centre or the origin of its
coordinates notices), and the robot may drive in the added strips (the exact optimum is
recomputed per copy, so a gap stays against each copy's own optimum). Only static scenarios:
a random walk's draws are not rotated with its world. The robot starts facing +x in every copy
(the simulator's convention), so a differential drive's first turn is part of what a copy
changes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

from swarmpath.world.scenario import Obstacle, Scenario

#: The copies, in the order the audit reports them.
TRANSFORMS = ("rot90", "rot180", "rot270", "mirror", "translate", "swap")

Point = tuple[float, float]

__all__ = ["TRANSFORMS", "symmetric_copy"]


def _mapping(kind: str, w: float, h: float) -> tuple[Callable[[Point], Point], Point]:
    """The point map of a transform and the copy's world size."""
    if kind == "rot90":  # counter-clockwise
        return (lambda p: (h - p[1], p[0])), (h, w)
    if kind == "rot180":
        return (lambda p: (w - p[0], h - p[1])), (w, h)
    if kind == "rot270":
        return (lambda p: (p[1], w - p[0])), (h, w)
    if kind == "mirror":  # about the vertical line x = w / 2
        return (lambda p: (w - p[0], p[1])), (w, h)
    if kind == "translate":
        return (lambda p: (p[0] + 0.5 * w, p[1] + 0.5 * h)), (1.5 * w, 1.5 * h)
    if kind == "swap":
        return (lambda p: p), (w, h)
    raise ValueError(f"transform must be one of {', '.join(TRANSFORMS)}, got {kind!r}")


def symmetric_copy(scenario: Scenario, kind: str) -> Scenario:
    """``scenario`` moved by ``kind`` (one of :data:`TRANSFORMS`), named ``<name>@<kind>``.
    Raises ValueError for a scenario where anything moves."""
    if scenario.is_dynamic:
        raise ValueError(f"{scenario.name}: only static maps have symmetric copies (a random "
                         "walk or a moving obstacle is not moved with its world)")
    w, h = scenario.size
    f, size = _mapping(kind, float(w), float(h))
    obstacles = []
    for o in scenario.obstacles:
        if o.shape == "circle":
            assert o.center is not None and o.radius is not None
            obstacles.append(Obstacle.circle(f(o.center), o.radius))
        else:
            obstacles.append(Obstacle.polygon([f(p) for p in o.points or ()]))
    start, goal = f(scenario.start), f(scenario.goal)
    if kind == "swap":
        start, goal = goal, start
    return dataclasses.replace(scenario, name=f"{scenario.name}@{kind}", size=size,
                               start=start, goal=goal, obstacles=tuple(obstacles), grid=None)
