"""The conformance gate for an optimizer (``swarmpath check optimizer NAME``, ``check_optimizer``).

Every property runs the algorithm on a small study (Rosenbrock F5, 5 dimensions, 12 iterations,
4 runs; F5's minimiser is not at the origin, so a search that collapses there gains nothing) and
asks one question; a failing property says what it saw:

* ``parameters``: its defaults resolve; an unknown parameter, a value of the wrong type and a
  value outside a choice are refused by a ParameterError naming the parameter; fewer agents than
  ``min_agents`` are refused;
* ``reproducible``: the same seed gives bit-identical curves, positions and counts;
* ``seed-sensitive``: another seed gives other curves;
* ``batch-independent``: run r alone, inside a batch, in another order and stacked with another
  function's runs (as a worker stacks leases) gives the same numbers;
* ``no-hidden-random-state``: the results do not change with the global ``numpy.random`` and
  ``random`` states, and the run leaves both states as it found them;
* ``budget``: each run counts between the algorithm's declared fewest and most evaluations
  (:meth:`Optimizer.expected_evaluations`: N (T + 1) unless it declares more), every point handed
  to the objective is counted (unless masked out), the curve has one point per iteration and
  never rises, the reported best is the objective at the reported position and no better than
  anything evaluated, and an evaluation budget (``max_evaluations``) is never exceeded;
* ``bounds``: every evaluated point lies in the box, unless the class declares another
  ``bound_rule`` (shown as information);
* ``process-independent``: the runs computed by ``-j 2`` children equal these;
* ``worker-slot``: the runs computed by a worker's slot process from a lease equal these.

Information (never a verdict): the origin-bias figure of ``swarmpath audit``, the median over
F1, F9, F10 (10 dimensions) of the decades lost when the optimum is shifted off the origin.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from functools import partial
from typing import Any

import numpy as np

from swarmpath.optimizers.base import Optimizer, ParameterError
from swarmpath.testing.globals import moved, seed_globals
from swarmpath.testing.report import Report

FUNCTION = "F5"
DIM = 5
ITERATIONS = 12
RUNS = 4
SEED = 7


@contextlib.contextmanager
def registered(optimizer: str | type[Optimizer]) -> Iterator[type[Optimizer]]:
    """The class to check, registered under its name while the checks run (a class not yet
    registered is registered for the duration)."""
    from swarmpath.optimizers.registry import REGISTRY, get_optimizer

    if isinstance(optimizer, str):
        yield get_optimizer(optimizer)
        return
    if not (isinstance(optimizer, type) and issubclass(optimizer, Optimizer)):
        raise TypeError(f"check_optimizer takes an Optimizer subclass or a name, got {optimizer!r}")
    known = REGISTRY.names()
    if optimizer.name in known:
        if get_optimizer(optimizer.name) is not optimizer:
            raise ValueError(f"another optimizer is registered as {optimizer.name!r}")
        yield optimizer
        return
    REGISTRY.register(optimizer)
    try:
        yield optimizer
    finally:
        REGISTRY.unregister(optimizer.name)


def settings(cls: type[Optimizer]) -> dict[str, Any]:
    """The gate's study; on the numpy backend: it checks the optimizer's own code (a compiled
    kernel, which "auto" would run, is checked against it by tests/test_compiled*.py)."""
    return {"function": FUNCTION, "dim": DIM, "agents": max(10, cls.min_agents),
            "iterations": ITERATIONS, "seed": SEED, "backend": "numpy"}


def _same(a: Any, b: Any) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k))
               for k in ("curve", "best_position", "evaluations"))


def _rows(res: Any, rows: list[int]) -> dict[str, np.ndarray]:
    return {"curve": res.curve[rows], "best_position": res.best_position[rows],
            "evaluations": res.evaluations[rows]}


def _differs(expected: dict[str, np.ndarray], got: dict[str, np.ndarray]) -> str | None:
    for key, value in expected.items():
        if not np.array_equal(value, got[key]):
            return f"{key} differs"
    return None


def check_optimizer(
    optimizer: str | type[Optimizer], *, processes: bool = True, bias: bool = True,
    raise_on_failure: bool = True,
) -> Report:
    """Check every property of the module docstring; with ``raise_on_failure`` a
    :class:`~swarmpath.testing.ConformanceError` naming each failing one (what a plugin's own
    test suite calls), else the :class:`~swarmpath.testing.Report`. ``processes=False`` leaves
    out the two properties that start processes; ``bias=False`` the origin-bias figure."""
    return check_optimizers([optimizer], processes=processes, bias=bias,
                            raise_on_failure=raise_on_failure)[0]


def check_optimizers(
    optimizers: Sequence[str | type[Optimizer]], *, processes: bool = True, bias: bool = True,
    raise_on_failure: bool = True,
) -> list[Report]:
    """:func:`check_optimizer` for several algorithms, their process properties computed in one
    pool of ``-j 2`` children and one worker slot (one process start for all of them)."""
    with contextlib.ExitStack() as stack:
        classes = [stack.enter_context(registered(o)) for o in optimizers]
        reports = []
        bases = []
        for cls in classes:
            report = Report("optimizer", cls.name)
            bases.append(_check(report, cls, bias))
            reports.append(report)
        if processes:
            _processes(reports, classes, bases)
    if raise_on_failure:
        for report in reports:
            report.raise_for_failures()
    return reports


def _processes(reports: list[Report], classes: list[type[Optimizer]], bases: list[Any]) -> None:
    from swarmpath.testing.processes import in_children, in_worker_slot, plugin_spec

    jobs = [(cls.name, settings(cls)) for cls in classes]
    specs = [plugin_spec(cls.__module__) for cls in classes]
    runs = list(range(RUNS))
    children = in_children(jobs, [[0, 1], [2, 3]], specs)
    slots = in_worker_slot(jobs, runs, specs)
    for report, base, child, slot in zip(reports, bases, children, slots, strict=True):
        expected = _rows(base, runs)
        report.check("process-independent", partial(_compare, expected, child))
        report.check("worker-slot", partial(_compare, expected, slot))


def _compare(expected: dict[str, np.ndarray], got: dict[str, np.ndarray] | Exception) -> str | None:
    if isinstance(got, Exception):
        raise got
    return _differs(expected, got)


def _check(report: Report, cls: type[Optimizer], bias: bool) -> Any:
    """The in-process properties; returns the base study's result."""
    from swarmpath.optimizers import minimize, minimize_many

    kw = settings(cls)
    name = cls.name
    report.check("parameters", lambda: _parameters(cls))
    base = minimize(name, runs=RUNS, **kw)
    report.check("reproducible", lambda: None if _same(base, minimize(name, runs=RUNS, **kw))
                 else "the same seed gave other numbers")
    report.check("seed-sensitive", lambda: None if not np.array_equal(
        base.curve, minimize(name, runs=RUNS, **{**kw, "seed": SEED + 1}).curve)
        else "another seed gave the same curves")

    def batch() -> str | None:
        for r in range(RUNS):
            alone = minimize(name, run_ids=[r], **kw)
            if _differs(_rows(base, [r]), _rows(alone, [0])):
                return f"run {r} alone differs from run {r} in a batch of {RUNS}"
        picked = minimize(name, run_ids=[3, 1], **kw)
        if _differs(_rows(base, [3, 1]), _rows(picked, [0, 1])):
            return "runs [3, 1] differ from the same runs in order"
        fkw = {k: v for k, v in kw.items() if k != "function"}
        stacked = minimize_many(name, [FUNCTION, "F1"], runs=RUNS, **fkw)[0]
        if not _same(stacked, base):
            return "stacked with F1's runs (as a worker stacks leases), the runs differ"
        return None

    report.check("batch-independent", batch)
    report.check("no-hidden-random-state", lambda: _global_state(name, kw, base))
    report.check("budget", lambda: _budget(cls, kw))
    if cls.bound_rule == "box":
        report.check("bounds", lambda: _bounds(cls, kw))
    else:
        report.info["bounds"] = f"not checked: {cls.bound_rule}"
    if bias:
        report.info["origin-bias"] = _origin_bias(name, kw["agents"])
    return base


def _parameters(cls: type[Optimizer]) -> str | None:
    resolved = cls.resolve_params(None)
    if dict(resolved) != dict(cls.defaults):
        return "the defaults do not resolve to themselves"
    probes: list[tuple[str, Any]] = [("__bogus__", 1)]
    for key, default in cls.defaults.items():
        if isinstance(default, bool):
            probes.append((key, "not-a-bool"))
        elif isinstance(default, str):
            if cls.choices.get(key):
                probes.append((key, "__not_a_choice__"))
        else:
            probes.append((key, "not-a-number"))
    for key, value in probes:
        try:
            cls.resolve_params({key: value})
        except ParameterError as exc:
            if key not in str(exc):
                return f"{key}={value!r} is refused without naming {key!r}: {exc}"
            continue
        except Exception as exc:
            return f"{key}={value!r} raises {type(exc).__name__}, not ParameterError"
        return f"{key}={value!r} is accepted"
    from swarmpath.optimizers import Problem, RunStreams

    problem = Problem(lambda X, s: np.zeros(X.shape[:2]), np.zeros((1, 2)), np.ones((1, 2)))
    try:
        cls(problem, cls.min_agents - 1, 2, RunStreams.for_runs(0, 1))
    except ParameterError:
        return None
    return f"{cls.min_agents - 1} agents (below min_agents {cls.min_agents}) are accepted"


def _global_state(name: str, kw: dict[str, Any], base: Any) -> str | None:
    from swarmpath.optimizers import minimize

    for seed in (1, 2):
        before = seed_globals(seed)
        res = minimize(name, runs=RUNS, **kw)
        touched = moved(before)
        if not _same(res, base):
            return "the results change with the global numpy.random / random state"
        if touched:
            return f"a run draws from (or reseeds) the global {touched} state"
    return None


def _budget(cls: type[Optimizer], kw: dict[str, Any]) -> str | None:
    from swarmpath.functions import get_function
    from swarmpath.optimizers import Problem, RunStreams

    fn = get_function(FUNCTION)
    dim, runs = kw["dim"], RUNS
    computed = np.zeros(runs, dtype=np.int64)
    lowest = np.full(runs, np.inf)

    def objective(X: np.ndarray, streams: Any) -> np.ndarray:
        values = fn.kernel(X)
        computed[:] += X.shape[1]
        np.minimum(lowest, values.min(axis=1), out=lowest)
        return values

    lower, upper = fn.bounds(dim)
    problem = Problem(objective, np.tile(lower, (runs, 1)), np.tile(upper, (runs, 1)))
    opt = cls(problem, kw["agents"], kw["iterations"], RunStreams.for_runs(kw["seed"], runs))
    curve = []
    while not opt.done:
        opt.step()
        curve.append(opt.best_fitness.copy())
    if opt.t != kw["iterations"] or len(curve) != kw["iterations"]:
        return f"{len(curve)} iterations stepped for {kw['iterations']}"
    with contextlib.suppress(RuntimeError):
        opt.step()
        return "a step past the last iteration was accepted"
    few, most = opt.expected_evaluations()
    counted = opt.evaluations
    if np.any(counted < few) or np.any(counted > most):
        return (f"counted {counted.tolist()} evaluations per run, declared "
                f"{few if few == most else f'{few}..{most}'} (expected_evaluations)")
    if np.any(computed < counted):
        return f"counted {counted.tolist()} but only {computed.tolist()} points were evaluated"
    if not opt.masked_evaluation and np.any(computed != counted):
        return f"{computed.tolist()} points were evaluated but {counted.tolist()} counted"
    c = np.array(curve).T
    if np.any(np.diff(c, axis=1) > 0):
        return "the best-so-far curve rises"
    if not np.allclose(fn.kernel(opt.best_position), opt.best_fitness, rtol=1e-12, atol=1e-12):
        return "the reported best is not the objective at the reported position"
    if np.any(opt.best_fitness < lowest):
        return "the reported best is better than any point evaluated"
    return _cap(cls, kw)


def _cap(cls: type[Optimizer], kw: dict[str, Any]) -> str | None:
    from swarmpath.optimizers import minimize

    cap = max(kw["agents"], kw["agents"] * (kw["iterations"] + 1) // 2)
    res = minimize(cls.name, runs=RUNS, max_evaluations=cap, **kw)
    if np.any(res.evaluations > cap):
        return f"with max_evaluations {cap}, {res.evaluations.tolist()} were counted"
    return None


def _bounds(cls: type[Optimizer], kw: dict[str, Any]) -> str | None:
    from swarmpath.functions import get_function
    from swarmpath.optimizers import Problem, RunStreams

    fn = get_function(FUNCTION)
    lower, upper = fn.bounds(kw["dim"])
    lower, upper = lower + 3.0, upper - 7.0  # a box not symmetric about the origin
    outside: list[float] = []

    def objective(X: np.ndarray, streams: Any) -> np.ndarray:
        excess = np.maximum(lower - X, X - upper).max(initial=0.0)
        if excess > 0:
            outside.append(float(excess))
        return fn.kernel(X)

    problem = Problem(objective, np.tile(lower, (RUNS, 1)), np.tile(upper, (RUNS, 1)))
    opt = cls(problem, kw["agents"], kw["iterations"], RunStreams.for_runs(kw["seed"], RUNS))
    while not opt.done:
        opt.step()
    if outside:
        return (f"{len(outside)} evaluations had points outside the box (up to {max(outside):.3g}"
                " beyond it); declare bound_rule if that is the algorithm's rule")
    if np.any(opt.best_position < lower) or np.any(opt.best_position > upper):
        return "the reported best position is outside the box"
    return None


def _origin_bias(name: str, agents: int) -> str:
    from swarmpath.evidence.audit import audit
    from swarmpath.optimizers import minimize

    functions, dim = ["F1", "F9", "F10"], 10
    values = {}
    for f in functions:
        for t in ("none", "shift", "shift+rotate"):
            res = minimize(name, f, dim=dim, agents=agents, iterations=100, runs=5, seed=SEED,
                           transform=t)
            values[(name, f, dim, t)] = [float(v) for v in res.best_fitness]
    row = audit(values, [name], functions, [dim])[0]
    return (f"median decades lost when shifted {row.median('shift'):+.2f}, shifted and "
            f"rotated {row.median('shift+rotate'):+.2f} (F1, F9, F10, D={dim}; swarmpath audit)")
