"""Compile (or load from numba's cache) the kernels a study needs, before it runs.

A kernel is compiled on its first use in a fresh environment (seconds of CPU each: LLVM work),
then loaded from numba's cache (:func:`~swarmpath.optimizers.compiled.versioned_cache_dir`) by
every later process of the same tree. :func:`warm` pays that first use up front, for the
algorithms and functions given, and says what each cost: ``swarmpath warmup`` after an install,
or a worker before it leases.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

from swarmpath.functions import get_function
from swarmpath.optimizers.compiled.objectives import compiled_names, has_objective, objective_for
from swarmpath.optimizers.compiled.registry import find_kernel, kernel_names


@dataclass(frozen=True)
class Warmed:
    """One piece made ready: ``kind`` ("function" or "algorithm"), its name, the CPU seconds
    its compilation (or its load from the cache) took in this process."""

    kind: str
    name: str
    seconds: float


def algorithms_with_kernels(algorithms: Sequence[str] | None) -> list[str]:
    """The registered names of ``algorithms`` (None: every algorithm with a kernel); KeyError
    naming one that is unknown or has no kernel."""
    from swarmpath.optimizers.registry import get_optimizer

    if algorithms is None:
        return kernel_names()
    out = []
    for a in algorithms:
        name = get_optimizer(a).name
        if find_kernel(name) is None:
            raise KeyError(f"algorithm {name!r} has no compiled kernel (these do: "
                           f"{', '.join(kernel_names())})")
        out.append(name)
    return out


def functions_with_objectives(functions: Sequence[str] | None) -> list[str]:
    """``functions`` (None: every function with a compiled objective); KeyError naming one
    that is unknown or has none."""
    if functions is None:
        return compiled_names()
    for name in functions:
        if not has_objective(get_function(name)):
            raise KeyError(f"function {name!r} has no compiled objective (these do: "
                           f"{', '.join(compiled_names())})")
    return list(functions)


def warm(algorithms: Sequence[str] | None = None,
         functions: Sequence[str] | None = None) -> list[Warmed]:
    """Make the compiled objectives of ``functions`` and the kernels of ``algorithms`` ready
    (None: every one there is; KeyError as :func:`algorithms_with_kernels` and
    :func:`functions_with_objectives`). Functions first: an algorithm's first run then times
    its kernel alone."""
    from swarmpath.optimizers.api import minimize
    from swarmpath.optimizers.registry import get_optimizer

    algos = algorithms_with_kernels(algorithms)
    names = functions_with_objectives(functions)
    out = []
    for name in names:
        started = time.process_time()
        objective_for(get_function(name))
        out.append(Warmed("function", name, time.process_time() - started))
    for a in algos:
        started = time.process_time()
        # one tiny run: a kernel has one signature whatever the sizes, so this is its build
        minimize(a, names[0] if names else "F1", dim=2,
                 agents=max(10, get_optimizer(a).min_agents), iterations=2, runs=1,
                 backend="numba")
        out.append(Warmed("algorithm", a, time.process_time() - started))
    return out
