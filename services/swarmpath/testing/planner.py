"""The conformance gate for a planner (``swarmpath check planner NAME``, ``check_planner``): the
episode contract, on a small static scenario (4 x 4 m, two circles between start and goal, an
omni robot of radius 0.2 m, the MFB paper's 12 sensors):

* ``parameters``: its defaults resolve; an unknown parameter and a value of the wrong type are
  refused by a PlannerError naming the parameter;
* ``episode``: an episode runs to its end (goal, or a limit); every decision is a finite 2-D
  target (or None with a reason), with whole iterations and a positive duration or None; the
  outcome carries every metric (finite length, error, smoothness, clearance), a path from the
  start, and the reason it ended;
* ``collision-free-success``: a run reported as a success never came within the robot's radius
  of an obstacle, checked here on the executed path against the circles themselves (not by the
  episode's own check);
* ``reproducible``: the same seed gives the same path, point for point, whatever the global
  ``numpy.random`` / ``random`` states, and the episode leaves those states as it found them.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from swarmpath.testing.globals import moved, seed_globals
from swarmpath.testing.report import Report

SEED = 3


def scenario() -> Any:
    from swarmpath.world.scenario import Obstacle, RobotSpec, Scenario

    return Scenario(
        name="conformance", size=(4.0, 4.0), start=(0.5, 0.5), goal=(3.5, 3.5),
        robot=RobotSpec.preset("omni", radius=0.2),
        obstacles=(Obstacle.circle((2.0, 2.0), 0.5), Obstacle.circle((1.0, 3.0), 0.3)),
        sensors="mfb-12", description="swarmpath check planner: two circles",
    )


#: (centre, radius) of the scenario's circles, written out for the independent check.
CIRCLES = (((2.0, 2.0), 0.5), ((1.0, 3.0), 0.3))


def check_planner(planner: str | type, *, raise_on_failure: bool = True) -> Report:
    """Check every property of the module docstring (see :func:`check_optimizer` for
    ``raise_on_failure``). A class not registered is registered for the duration."""
    from swarmpath.planners.base import REGISTRY, Planner

    if isinstance(planner, str):
        cls = REGISTRY.get(planner)
        return _run(cls, cls.name, raise_on_failure)
    if not (isinstance(planner, type) and issubclass(planner, Planner)):
        raise TypeError(f"check_planner takes a Planner subclass or a name, got {planner!r}")
    if planner.name in REGISTRY:
        if REGISTRY.get(planner.name) is not planner:
            raise ValueError(f"another planner is registered as {planner.name!r}")
        return _run(planner, planner.name, raise_on_failure)
    REGISTRY.register(planner)
    try:
        return _run(planner, planner.name, raise_on_failure)
    finally:
        REGISTRY.unregister(planner.name)


def _run(cls: Any, name: str, raise_on_failure: bool) -> Report:
    report = Report("planner", name)
    report.check("parameters", lambda: _parameters(cls))
    episodes: list[Any] = []
    report.check("episode", lambda: _episode(name, episodes))
    if episodes:
        outcome = episodes[0]
        report.check("collision-free-success", lambda: _collision_free(outcome))
        report.check("reproducible", lambda: _reproducible(name, outcome))
    return report.raise_for_failures() if raise_on_failure else report


def _parameters(cls: Any) -> str | None:
    from swarmpath.planners.base import PlannerError

    if dict(cls.resolve_params(None)) != dict(cls.defaults):
        return "the defaults do not resolve to themselves"
    probes: list[tuple[str, Any]] = [("__bogus__", 1)]
    for key, default in cls.defaults.items():
        if isinstance(default, bool):
            probes.append((key, "not-a-bool"))
        elif not isinstance(default, str):
            probes.append((key, "not-a-number"))
    for key, value in probes:
        try:
            cls.resolve_params({key: value})
        except PlannerError as exc:
            if key not in str(exc):
                return f"{key}={value!r} is refused without naming {key!r}: {exc}"
            continue
        except Exception as exc:
            return f"{key}={value!r} raises {type(exc).__name__}, not PlannerError"
        return f"{key}={value!r} is accepted"
    return None


def _episode(name: str, out: list[Any]) -> str | None:
    from swarmpath.planners import Episode

    seed_globals(1)
    ep = Episode(scenario(), name, SEED, 0)
    decide = ep.planner.decide

    def checked(obs: Any) -> Any:
        decision = decide(obs)
        problem = _bad_decision(decision)
        if problem is not None:
            raise _BrokenDecision(problem)
        return decision

    ep.planner.decide = checked  # type: ignore[method-assign]
    try:
        outcome = ep.run()
    except _BrokenDecision as exc:
        return str(exc)
    for field in ("length", "error", "smoothness", "min_clearance", "travel_time"):
        if not math.isfinite(float(getattr(outcome, field))):
            return f"the outcome's {field} is not finite"
    path = np.asarray(outcome.path, dtype=float)
    if path.ndim != 2 or path.shape[1] != 3 or len(path) < 1:
        return "the outcome has no path"
    if not np.allclose(path[0, :2], scenario().start):
        return "the path does not start at the start"
    if not outcome.reason:
        return "the outcome does not say why the episode ended"
    out.append(outcome)
    return None


class _BrokenDecision(Exception):
    """A decision that breaks the contract (found before the simulator drives it)."""


def _bad_decision(d: Any) -> str | None:
    if d.target is None:
        return None if d.reason else "a decision gave up (target None) without a reason"
    target = np.asarray(d.target, dtype=float)
    if target.shape != (2,) or not np.all(np.isfinite(target)):
        return f"a decision's target is not a finite 2-D point: {d.target!r}"
    if not isinstance(d.iterations, int | np.integer) or d.iterations < 0:
        return f"a decision's iterations are not a whole number >= 0: {d.iterations!r}"
    if d.duration is not None and not d.duration > 0:
        return f"a decision's duration is not positive: {d.duration!r}"
    return None


def _collision_free(outcome: Any) -> str | None:
    if not outcome.success:
        return None
    path = np.asarray(outcome.path, dtype=float)[:, :2]
    radius = scenario().robot.radius
    for centre, r in CIRCLES:
        gap = np.hypot(*(path - np.asarray(centre)).T) - r - radius
        if np.any(gap <= 0):
            return (f"a success whose path comes {-float(gap.min()):.3g} m into the circle at "
                    f"{centre} (the episode reported {outcome.collisions} collisions)")
    return None


def _reproducible(name: str, first: Any) -> str | None:
    from swarmpath.planners import Episode

    before = seed_globals(2)
    again = Episode(scenario(), name, SEED, 0).run()
    touched = moved(before)
    if touched:
        return f"the episode draws from (or reseeds) the global {touched} state"
    if not np.array_equal(np.asarray(first.path), np.asarray(again.path)):
        return "the same seed gave another path (or the path depends on the global random state)"
    return None
