"""Registry of compiled kernels: the single source of which algorithms the numba backend runs.

A kernel module registers one :class:`Kernel` per algorithm with :func:`register_kernel`; the
modules listed in ``_MODULES`` are imported on first use (add yours there).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmpath.registry import ParamValue

_MODULES: tuple[str, ...] = ("pso", "gwo", "ssa", "fdo", "coot", "hpo", "ba", "bats", "rfo")
_KERNELS: dict[str, Kernel] = {}
_loaded = False


@dataclass(frozen=True)
class Kernel:
    """The compiled form of one registered optimizer.

    ``run``: the @njit kernel of one run (signature in the package docstring). ``pack``: the
    algorithm's resolved parameters -> the float64 vector ``run`` reads; it raises
    ``ParameterError`` naming a parameter or value the kernel does not implement.
    ``transforms``: the transforms the kernel supports. ``tolerance``: the largest relative
    difference from the numpy reference the kernel allows (0.0: equal to the last bit); it is
    recorded in every result the kernel computes. ``check``: optional checks of the resolved
    parameters against the number of agents that the reference makes when it is built (e.g. COOT's
    leaders must leave a coot); it raises ``ParameterError`` naming the parameter.
    """

    algorithm: str
    run: Callable[..., Any]
    pack: Callable[[Mapping[str, ParamValue]], NDArray[np.float64]]
    transforms: tuple[str, ...] = ("none", "shift")
    tolerance: float = 0.0
    check: Callable[[Mapping[str, ParamValue], int], None] | None = None
    capped: bool = False


def register_kernel(kernel: Kernel) -> Kernel:
    """Register ``kernel`` under its algorithm's registered name (KeyError if there is none)."""
    from swarmpath.optimizers.registry import get_optimizer

    name = get_optimizer(kernel.algorithm).name
    if name in _KERNELS and _KERNELS[name] is not kernel:
        raise ValueError(f"kernel {name!r} registered twice")
    _KERNELS[name] = kernel
    return kernel


def _load() -> None:
    global _loaded
    if not _loaded:
        for module in _MODULES:
            importlib.import_module(f"swarmpath.optimizers.compiled.{module}")
        _loaded = True


def kernel_names() -> list[str]:
    """Algorithms with a compiled kernel, in the optimizer registry's order."""
    from swarmpath.optimizers.registry import list_optimizers

    _load()
    return [name for name in list_optimizers() if name in _KERNELS]


def find_kernel(algorithm: str) -> Kernel | None:
    _load()
    return _KERNELS.get(algorithm)
