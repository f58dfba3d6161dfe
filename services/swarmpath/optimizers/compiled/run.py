"""``minimize_many(..., backend="numba")``: every run through its algorithm's compiled kernel."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from swarmpath.functions import BenchmarkFunction
from swarmpath.functions.transforms import rotates
from swarmpath.optimizers.base import ParameterError
from swarmpath.optimizers.budget import most_evaluations
from swarmpath.optimizers.compiled.objectives import (
    Objective,
    data_for,
    has_objective,
    objective_for,
)
from swarmpath.optimizers.compiled.registry import Kernel, find_kernel, kernel_names
from swarmpath.optimizers.problem import BenchmarkProblem
from swarmpath.optimizers.registry import get_optimizer
from swarmpath.optimizers.streams import run_generator


def kernel_for(algorithm: str, params: Mapping[str, Any] | None, transform: str) -> tuple[
    Kernel, dict[str, Any], np.ndarray
]:
    """The kernel, resolved parameters and packed parameter vector for a study, or
    ParameterError naming what has no kernel (``algorithm``, ``transform`` or a parameter)."""
    cls = get_optimizer(algorithm)
    kernel = find_kernel(cls.name)
    if kernel is None:
        raise ParameterError(
            f"algorithm {cls.name!r} has no numba kernel (backend='numba' runs "
            f"{', '.join(kernel_names())}); use backend='numpy'"
        )
    if transform not in kernel.transforms:
        raise ParameterError(
            f"transform {transform!r} has no numba kernel for {cls.name} (it runs "
            f"{', '.join(kernel.transforms)}); use backend='numpy'"
        )
    resolved = cls.resolve_params(params)
    return kernel, resolved, np.ascontiguousarray(kernel.pack(resolved), dtype=np.float64)


def check_study(algorithm: str, params: Mapping[str, Any] | None, transform: str) -> None:
    """ParameterError if ``minimize_compiled`` would refuse this algorithm, transform or
    parameters (rotation, no kernel, an unsupported parameter value)."""
    if rotates(transform):
        raise ParameterError(
            f"transform {transform!r}: the numba backend does not rotate (numpy's matmul sums "
            "in BLAS order); use backend='numpy'"
        )
    kernel_for(algorithm, params, transform)


def check_function(fn: BenchmarkFunction) -> None:
    """ParameterError naming ``function`` if it has no compiled objective (e.g. a hand-made
    kernel); compiles nothing."""
    if not has_objective(fn):
        raise ParameterError(f"function {fn.name!r} has no numba kernel; use backend='numpy'")


def check_budget(algorithm: str, params: Mapping[str, Any] | None, agents: int, iterations: int,
                 dim: int, max_evaluations: int | None) -> None:
    """ParameterError naming budget_evals unless the kernel gives the reference's numbers under
    ``max_evaluations``: it counts the budget itself (``Kernel.capped``), or no run of the
    algorithm can reach it in ``iterations`` (its declared most evaluations fit), so the
    reference's cap never binds and its numbers are those of the uncapped run."""
    if max_evaluations is None:
        return
    cls = get_optimizer(algorithm)
    kernel = find_kernel(cls.name)
    if kernel is None or kernel.capped:
        return  # kernel_for names a missing kernel
    key = tuple(sorted(cls.resolve_params(params).items()))
    most = most_evaluations(cls.name, agents, iterations, dim, key)
    if most > max_evaluations:
        raise ParameterError(
            f"budget_evals {max_evaluations}: {cls.name}'s kernel does not count a budget and "
            f"its runs may spend {most} evaluations in {iterations} iterations; use "
            "backend='numpy' (or the iterations that fit the budget)")


def compiled_objective(fn: BenchmarkFunction, dim: int) -> Objective:
    """The compiled objective of a registered function in ``dim`` dimensions, with its data
    (:func:`check_function`'s error if it has none)."""
    check_function(fn)
    return objective_for(fn, data_for(fn, dim))


def minimize_compiled(
    algorithm: str,
    fns: Sequence[BenchmarkFunction],
    dim: int,
    agents: int,
    iterations: int,
    ids: Sequence[int],
    seed: int,
    params: Mapping[str, Any] | None,
    transform: str,
    on_iteration: Callable[[Any], None] | None = None,
    max_evaluations: int | None = None,
) -> list[dict[str, Any]]:
    """Per function: the fields of its Result (the caller builds the Result).

    Runs are computed one after another, each by its kernel from its own generator, so run r
    gives the same numbers in any batch. ``on_iteration`` (progress, cancellation) is called
    ``iterations`` times in all, spread over the runs as they finish, with ``None``.
    ``max_evaluations``: the reference's evaluation budget (:func:`check_budget`).
    """
    cls = get_optimizer(algorithm)
    check_study(cls.name, params, transform)
    kernel, resolved, packed = kernel_for(cls.name, params, transform)
    if agents < cls.min_agents:
        raise ParameterError(f"{cls.name} needs agents >= {cls.min_agents}, got {agents}")
    if kernel.check is not None:
        kernel.check(resolved, agents)
    check_budget(cls.name, params, agents, iterations, dim, max_evaluations)
    if kernel.capped:
        packed[-1] = -1.0 if max_evaluations is None else float(max_evaluations)
    objectives = [compiled_objective(fn, dim) for fn in fns]
    started, cpu_started = time.perf_counter(), time.thread_time()
    total = len(fns) * len(ids)
    done = 0
    out = []
    for fn, objective in zip(fns, objectives, strict=True):
        problem = BenchmarkProblem.build(fn, dim, list(ids), seed, transform)
        shifted = problem.shifts is not None
        shift = np.zeros((len(ids), dim)) if problem.shifts is None else problem.shifts
        best = np.empty(len(ids))
        position = np.empty((len(ids), dim))
        curve = np.empty((len(ids), iterations))
        evaluations = np.empty(len(ids), dtype=np.int64)
        for k, r in enumerate(ids):
            f, x, c, e = kernel.run(
                run_generator(seed, r), objective, shifted, np.ascontiguousarray(shift[k]),
                np.ascontiguousarray(problem.lower[k]), np.ascontiguousarray(problem.upper[k]),
                agents, iterations, packed,
            )
            best[k], position[k], curve[k], evaluations[k] = f, x, c, e
            done += 1
            if on_iteration is not None:
                for _ in range(iterations * done // total - iterations * (done - 1) // total):
                    on_iteration(None)
        if max_evaluations is not None and np.any(evaluations > max_evaluations):
            raise RuntimeError(  # a declaration (expected_evaluations) or a kernel is wrong
                f"{cls.name}'s kernel counted {int(evaluations.max())} evaluations, past the "
                f"budget of {max_evaluations}")
        out.append({
            "best_fitness": best, "best_position": position, "curve": curve,
            "evaluations": evaluations, "shifts": problem.shifts, "params": dict(resolved),
            "tolerance": kernel.tolerance,
        })
    seconds = time.perf_counter() - started
    cpu_seconds = time.thread_time() - cpu_started
    for fields in out:
        fields["seconds"] = seconds / len(fns)
        fields["cpu_seconds"] = cpu_seconds / len(fns)
    return out
