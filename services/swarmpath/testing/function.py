"""The conformance gate for a benchmark function (``swarmpath check function NAME``,
``check_function``). In each dimension it is defined for (all of ``dimensions``, else its
smallest and 10):

* ``box``: lower < upper on every coordinate;
* ``shape``: the kernel maps (runs, agents, d) to (runs, agents), (m, d) to (m,) and (d,) to (),
  in float64 (an optimizer evaluates whole batches);
* ``finite``: finite values at 256 uniform points of the box and at its corners;
* ``deterministic``: the same points give the same values, a run's population (runs, agents, d)
  gives the same values alone as in a batch of runs and in any order of the runs, and neither
  depends on the global ``numpy.random`` / ``random`` states, which it leaves untouched (an
  optimizer evaluates all its runs at once, a worker stacks runs of several cells). Whether a
  single point alone gives the same last bit as inside its population (a kernel with matrix
  products may not; optimizers always evaluate whole populations) is shown as information;
* ``minimum``: with a known minimiser, it lies in the box and its value is ``f_min_for(d)``; no
  sampled point (the uniform ones, and 64 within 1e-3 of the minimiser) is below ``f_min``.
"""

from __future__ import annotations

import itertools

import numpy as np

from swarmpath.functions.base import BenchmarkFunction
from swarmpath.testing.globals import moved, seed_globals
from swarmpath.testing.report import Report

SAMPLES = 256
NEAR = 64


def _dims(fn: BenchmarkFunction) -> list[int]:
    if fn.dimensions:
        return sorted(fn.dimensions)
    return sorted({max(fn.min_dim, 2), max(fn.min_dim, 10)})


def check_function(function: str | BenchmarkFunction, *, raise_on_failure: bool = True) -> Report:
    """Check every property of the module docstring (see :func:`check_optimizer` for
    ``raise_on_failure``)."""
    from swarmpath.functions import get_function

    fn = get_function(function) if isinstance(function, str) else function
    if not isinstance(fn, BenchmarkFunction):
        raise TypeError(f"check_function takes a BenchmarkFunction or a name, got {function!r}")
    report = Report("function", fn.name)
    dims = _dims(fn)
    report.check("box", lambda: _box(fn, dims))
    report.check("shape", lambda: _shape(fn, dims))
    report.check("finite", lambda: _finite(fn, dims))
    report.check("deterministic", lambda: _deterministic(fn, dims))
    alone = _point_alone(fn, dims)
    if alone:
        report.info["point-alone"] = alone
    if fn.has_optimum:
        report.check("minimum", lambda: _minimum(fn, dims))
    else:
        report.info["minimum"] = (f"no known minimiser; best known value "
                                  f"{fn.f_min_for(dims[0]):.10g}")
    return report.raise_for_failures() if raise_on_failure else report


def _points(fn: BenchmarkFunction, d: int, n: int, seed: int = 20) -> np.ndarray:
    lower, upper = fn.bounds(d)
    return np.random.default_rng([seed, d]).uniform(lower, upper, (n, d))


def _box(fn: BenchmarkFunction, dims: list[int]) -> str | None:
    for d in dims:
        lower, upper = fn.bounds(d)
        if lower.shape != (d,) or upper.shape != (d,):
            return f"bounds({d}) are not two vectors of {d}"
        if not np.all(lower < upper):
            return f"lower >= upper on some coordinate in {d} dimensions"
    return None


def _shape(fn: BenchmarkFunction, dims: list[int]) -> str | None:
    for d in dims:
        X = _points(fn, d, 12).reshape(3, 4, d)
        for x, want in ((X, (3, 4)), (X[0], (4,)), (X[0, 0], ())):
            value = np.asarray(fn.kernel(x))
            if value.shape != want:
                return f"{x.shape} gave shape {value.shape}, not {want}"
            if value.dtype != np.float64:
                return f"{x.shape} gave dtype {value.dtype}, not float64"
    return None


def _finite(fn: BenchmarkFunction, dims: list[int]) -> str | None:
    for d in dims:
        lower, upper = fn.bounds(d)
        corners = np.array(list(itertools.islice(itertools.product(*zip(lower, upper,
                                                                        strict=True)), 64)))
        for X in (_points(fn, d, SAMPLES), corners):
            bad = ~np.isfinite(fn.evaluate(X))
            if bad.any():
                return f"{int(bad.sum())} non-finite values in {d} dimensions, e.g. at {X[bad][0]}"
    return None


def _deterministic(fn: BenchmarkFunction, dims: list[int]) -> str | None:
    for d in dims:
        X = _points(fn, d, 32).reshape(4, 8, d)
        before = seed_globals(1)
        first = np.asarray(fn.kernel(X))
        touched = moved(before)
        if touched:
            return f"the kernel draws from (or reseeds) the global {touched} state"
        seed_globals(2)
        if not np.array_equal(first, fn.kernel(X)):
            return f"the same {d}-dimensional points gave other values"
        for r in range(len(X)):
            if not np.array_equal(first[r:r + 1], np.asarray(fn.kernel(X[r:r + 1]))):
                return f"a run's population gives other values alone than in a batch (d={d})"
        if not np.array_equal(first[::-1], np.asarray(fn.kernel(X[::-1]))):
            return f"a run's population gives other values with the runs reordered (d={d})"
    return None


def _point_alone(fn: BenchmarkFunction, dims: list[int]) -> str | None:
    for d in dims:
        X = _points(fn, d, 32)
        if not np.array_equal(np.asarray(fn.kernel(X))[:1], np.asarray(fn.kernel(X[:1]))):
            return (f"a point alone differs in the last bits from the same point among 32 "
                    f"(d={d}): fine for optimizers, which evaluate whole populations")
    return None


def _minimum(fn: BenchmarkFunction, dims: list[int]) -> str | None:
    for d in dims:
        x_star = fn.optimum(d)
        lower, upper = fn.bounds(d)
        if x_star.shape != (d,) or np.any(x_star < lower) or np.any(x_star > upper):
            return f"the minimiser in {d} dimensions is not a point of the box"
        f_min = fn.f_min_for(d)
        tol = 1e-9 * max(1.0, abs(f_min))
        at = float(fn.evaluate(x_star[None, :])[0])
        if abs(at - f_min) > tol:
            return f"f(minimiser) = {at!r} in {d} dimensions, f_min_for({d}) = {f_min!r}"
        near = np.clip(x_star + np.random.default_rng([21, d]).normal(0, 1e-3, (NEAR, d)),
                       lower, upper)
        for X in (_points(fn, d, SAMPLES), near):
            values = fn.evaluate(X)
            if np.any(values < f_min - tol):
                i = int(np.argmin(values))
                return f"f = {values[i]!r} < f_min {f_min!r} at {X[i]} in {d} dimensions"
    return None
