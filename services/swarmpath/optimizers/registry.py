"""Registry of optimizers: the single source of their names.

Each algorithm lives in its own module and registers its class with :func:`register`. The modules
are imported on first use, in the order below (the order catalogues and tables show).
"""

from __future__ import annotations

import importlib

from swarmpath.optimizers.base import Optimizer

_MODULES = (
    "pso", "ssa", "fdo", "gwo", "ba", "mfb", "hpso_mfb", "coot", "mcoot", "icoot", "hpo", "ihpo",
    "rfo",
)
_REGISTRY: dict[str, type[Optimizer]] = {}
_loaded = False


def register(cls: type[Optimizer]) -> type[Optimizer]:
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise ValueError(f"optimizer {cls.name!r} registered twice")
    _REGISTRY[cls.name] = cls
    return cls


def _load() -> None:
    global _loaded
    if not _loaded:
        for module in _MODULES:
            try:
                importlib.import_module(f"swarmpath.optimizers.{module}")
            except ModuleNotFoundError as exc:  # TEMP while the team writes the modules
                if exc.name != f"swarmpath.optimizers.{module}":
                    raise
        _loaded = True


def list_optimizers() -> list[str]:
    _load()
    return list(_REGISTRY)


def get_optimizer(name: str) -> type[Optimizer]:
    _load()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown optimizer {name!r}; valid: {', '.join(_REGISTRY)}") from None
