"""Registry of optimizers: the single source of their names.

Each algorithm lives in its own module and registers its class with :func:`register`. The modules
are imported on first use, in the order below (the order catalogues and tables show); plugins
(entry-point group ``swarmpath.optimizers``, ``--plugin``, ``SWARMPATH_PLUGINS``) register
theirs the same way and are listed after the built-ins.
"""

from __future__ import annotations

from swarmpath.optimizers.base import Optimizer
from swarmpath.registry import Registry, caller_module, origin_for

_MODULES = (
    "pso", "ssa", "fdo", "gwo", "ba", "mfb", "hpso_mfb", "coot", "mcoot", "icoot", "hpo", "ihpo",
    "rfo", "rs", "cmaes", "lshade", "jso",
)
#: The strong baselines a study can add to its algorithms (``swarmpath bench --baselines``):
#: Hansen's CMA-ES (IPOP), the CEC winners L-SHADE (2014) and jSO (2017), uniform random search.
BASELINES: tuple[str, ...] = ("CMA-ES", "L-SHADE", "jSO", "RS")
REGISTRY: Registry[type[Optimizer]] = Registry(
    "optimizer", "swarmpath.optimizers", _MODULES, KeyError, group="swarmpath.optimizers"
)


def register(cls: type[Optimizer]) -> type[Optimizer]:
    """Class decorator: add an :class:`Optimizer` subclass under its ``name`` (a name taken by
    other code is refused, naming both origins)."""
    if not (isinstance(cls, type) and issubclass(cls, Optimizer)):
        raise TypeError(f"register takes an Optimizer subclass, got {cls!r}")
    return REGISTRY.register(cls, origin_for(caller_module()))


def list_optimizers(builtin: bool | None = None) -> list[str]:
    """Registered names, built-ins first (``builtin``: only built-ins, or only plugins)."""
    return REGISTRY.names(builtin)


def get_optimizer(name: str) -> type[Optimizer]:
    return REGISTRY.get(name)
