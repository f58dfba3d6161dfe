"""Budgets in the field's units: a number of function evaluations per run (COCO, CEC: 10000 D).

A study given ``budget_evals`` N runs each algorithm for the iterations that spend N (or just
under it), and counts no evaluation past N: the reported best and curve are those of the first N
evaluations of every run (:attr:`Optimizer.max_evaluations`).

The iterations come from the algorithm itself: its evaluations after 1 and 2 iterations, on the
study's agents, dimension and parameters, give e(T) = e0 + T e1 (every registered algorithm
spends a fixed number per iteration, except FDO, whose extra evaluations vary by run, and PSO
with bounds "fly", whose particles outside the box are not evaluated: they get the iterations
of their probe run, and the cap ends them at N; a PSO whose particles leave the box for good,
``vmax_mode="none"`` at d >= 10, probes few evaluations per iteration and so gets many
iterations). T = max(1, floor((N - e0) / e1)).

The compiled kernels (``backend="numba"``) honour a budget with the reference's numbers where
the cap cannot bind: :func:`most_evaluations` in the study's iterations fits it (every
algorithm with a fixed count per iteration, at the iterations above), or the kernel counts the
budget itself (PSO's, FDO's); elsewhere ``auto`` runs numpy (``compiled.run.check_budget``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import Any

from swarmpath.optimizers.base import ParameterError

#: CEC's budget: 10000 evaluations per dimension.
CEC_EVALUATIONS_PER_DIM = 10_000
#: the largest N of a budget N or NxD
MAX_BUDGET = 10**9


def parse_budget(text: str | None) -> str | None:
    """A budget as a study states it: 'N' (evaluations per run) or 'NxD' (N times the
    dimension: CEC's '10000xD'), normalised; ParameterError naming budget_evals otherwise."""
    if text is None:
        return None
    number, sep, per_dim = str(text).strip().replace("*", "x").partition("x")
    if (sep and per_dim.strip().upper() != "D") or not number.strip().isdigit() or not (
            1 <= int(number) <= MAX_BUDGET):
        raise ParameterError(f"budget_evals {text!r} is not a positive integer N or NxD "
                             "(N times the dimension, e.g. 10000xD)")
    return f"{int(number)}xD" if sep else str(int(number))


def budget_at(budget: str | None, dim: int) -> int | None:
    """The evaluations of one run at ``dim`` of a parsed budget (None: no budget)."""
    if budget is None:
        return None
    number, _, per_dim = budget.partition("x")
    return int(number) * (dim if per_dim else 1)


def study_iterations(algorithm: str, budget: str | None, iterations: int, agents: int, dim: int,
                     params: Mapping[str, Any] | None = None) -> int:
    """A study's iterations for ``algorithm`` at ``dim``: ``iterations`` without a budget, else
    those that spend it (:func:`iterations_for_budget`)."""
    evaluations = budget_at(budget, dim)
    if evaluations is None:
        return iterations
    return iterations_for_budget(algorithm, evaluations, agents, dim, params)


def iterations_for_budget(algorithm: str, budget: int, agents: int, dim: int,
                          params: Mapping[str, Any] | None = None) -> int:
    """The iterations of ``algorithm`` that spend at most ``budget`` evaluations per run
    (ParameterError if even its initialization and one iteration do not fit)."""
    if isinstance(budget, bool) or not isinstance(budget, int) or budget < 1:
        raise ParameterError(f"budget_evals must be a positive integer, got {budget!r}")
    key = tuple(sorted((params or {}).items()))
    first, per_iteration = _probe(algorithm, agents, dim, key)
    if first + per_iteration > budget:
        raise ParameterError(
            f"budget_evals {budget} is less than {algorithm}'s {first + per_iteration} "
            f"evaluations for its initialization and one iteration with {agents} agents")
    return max(1, (budget - first) // max(per_iteration, 1))


def check_compiled_budget(backend: str, algorithms: Sequence[str], budget: str | None,
                          iterations: int, agents: int, dims: Sequence[int],
                          params: Mapping[str, Mapping[str, Any]] | None = None) -> None:
    """Before a study: ParameterError naming budget_evals where ``backend`` 'numba' could not
    give the reference's numbers under ``budget`` (``compiled.run.check_budget`` at each
    algorithm's study iterations and each dim); nothing for the other backends."""
    if backend != "numba" or budget is None:
        return
    from swarmpath.optimizers.compiled.run import check_budget

    for a in algorithms:
        for d in dims:
            p = (params or {}).get(a)
            check_budget(a, p, agents, study_iterations(a, budget, iterations, agents, d, p), d,
                         budget_at(budget, d))


def most_evaluations(algorithm: str, agents: int, iterations: int, dim: int,
                     params: tuple[tuple[str, Any], ...] = ()) -> int:
    """The most evaluations a run of ``algorithm`` counts in ``iterations``
    (:func:`declared_evaluations`)."""
    return declared_evaluations(algorithm, agents, iterations, dim, params)[1]


@lru_cache(maxsize=256)
def declared_evaluations(algorithm: str, agents: int, iterations: int, dim: int,
                         params: tuple[tuple[str, Any], ...] = ()) -> tuple[int, int]:
    """(fewest, most) evaluations a run of ``algorithm`` counts in ``iterations``: what it
    declares (:meth:`Optimizer.expected_evaluations`, held to it by the conformance gate), read
    from an instance on a one-run problem that is never evaluated. ``params``: sorted (name,
    value) pairs (hashable, for the cache)."""
    import numpy as np

    from swarmpath.optimizers.problem import Problem
    from swarmpath.optimizers.registry import get_optimizer
    from swarmpath.optimizers.streams import RunStreams

    def never(x: Any, streams: Any) -> Any:
        raise AssertionError("declared_evaluations evaluates nothing")

    problem = Problem(never, np.zeros((1, dim)), np.ones((1, dim)))
    opt = get_optimizer(algorithm)(problem, agents, iterations, RunStreams.for_runs(0, [0]),
                                   dict(params))
    few, most = opt.expected_evaluations()
    return int(few), int(most)


@lru_cache(maxsize=256)
def _probe(algorithm: str, agents: int, dim: int, params: tuple[tuple[str, Any], ...]) -> tuple[
    int, int
]:
    """(e0, e1): evaluations of one run before the first iteration and per iteration."""
    from swarmpath.optimizers.api import minimize

    counts = [int(minimize(algorithm, "F1", dim=dim, agents=agents, iterations=t, runs=1,
                           seed=0, params=dict(params)).evaluations[0]) for t in (1, 2)]
    per_iteration = counts[1] - counts[0]
    return counts[0] - per_iteration, per_iteration
