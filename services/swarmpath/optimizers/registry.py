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
_SEQUENCE: dict[str, int] = {}
_loaded = False


def register(cls: type[Optimizer]) -> type[Optimizer]:
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise ValueError(f"optimizer {cls.name!r} registered twice")
    _REGISTRY[cls.name] = cls
    _SEQUENCE.setdefault(cls.__name__ + "/" + cls.__module__, len(_SEQUENCE))
    return cls


def _load() -> None:
    global _loaded
    if not _loaded:
        for module in _MODULES:
            importlib.import_module(f"swarmpath.optimizers.{module}")
        _loaded = True


def _position(cls: type) -> tuple[int, int]:
    """Listing order: the module order above, then registration order (whatever was imported
    first, e.g. by a test importing one module directly)."""
    module = cls.__module__.rsplit(".", 1)[-1]
    rank = _MODULES.index(module) if module in _MODULES else len(_MODULES)
    return rank, _SEQUENCE[cls.__name__ + "/" + cls.__module__]


def list_optimizers() -> list[str]:
    _load()
    return [cls.name for cls in sorted(_REGISTRY.values(), key=_position)]


def get_optimizer(name: str) -> type[Optimizer]:
    _load()
    try:
        return _REGISTRY[name]
    except KeyError:
        valid = ", ".join(list_optimizers())
        raise KeyError(f"unknown optimizer {name!r}; valid: {valid}") from None
