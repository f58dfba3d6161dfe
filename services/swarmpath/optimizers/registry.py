"""Registry of optimizers: the single source of their names.

Each algorithm lives in its own module and registers its class with :func:`register`. The modules
are imported on first use, in the order below (the order catalogues and tables show).
"""

from __future__ import annotations

from swarmpath.optimizers.base import Optimizer
from swarmpath.registry import Registry

_MODULES = (
    "pso", "ssa", "fdo", "gwo", "ba", "mfb", "hpso_mfb", "coot", "mcoot", "icoot", "hpo", "ihpo",
    "rfo",
)
REGISTRY: Registry[Optimizer] = Registry("optimizer", "swarmpath.optimizers", _MODULES, KeyError)
register = REGISTRY.register


def list_optimizers() -> list[str]:
    return REGISTRY.names()


def get_optimizer(name: str) -> type[Optimizer]:
    return REGISTRY.get(name)
