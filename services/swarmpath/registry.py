"""Name registries and typed parameters, shared by optimizers and planners.

A :class:`Registry` is the single source of a family's names: modules register their classes when
imported, the registry imports its modules on first use and lists names in module order.
:func:`resolve_params` merges user parameters over a class's defaults, checking each against the
type of its default (and the allowed choices of string parameters), with messages that name the
parameter and list what is valid.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any, Generic, TypeVar

import numpy as np

ParamValue = float | int | bool | str
T = TypeVar("T")


class Registry(Generic[T]):
    def __init__(
        self,
        kind: str,
        package: str,
        modules: tuple[str, ...],
        error: Callable[[str], Exception],
    ):
        self.kind = kind  # "optimizer", "planner": used in messages
        self.package = package
        self.modules = modules
        self.error = error
        self._classes: dict[str, type[T]] = {}
        self._sequence: dict[type[T], int] = {}
        self._loaded = False

    def register(self, cls: type[T]) -> type[T]:
        name: str = cls.name  # type: ignore[attr-defined]
        if name in self._classes and self._classes[name] is not cls:
            raise ValueError(f"{self.kind} {name!r} registered twice")
        self._classes[name] = cls
        self._sequence.setdefault(cls, len(self._sequence))
        return cls

    def unregister(self, name: str) -> None:
        self._sequence.pop(self._classes.pop(name), None)

    def _load(self) -> None:
        if not self._loaded:
            for module in self.modules:
                importlib.import_module(f"{self.package}.{module}")
            self._loaded = True

    def _position(self, cls: type[T]) -> tuple[int, int]:
        """Module order, then registration order (whatever was imported first)."""
        module = cls.__module__.rsplit(".", 1)[-1]
        rank = self.modules.index(module) if module in self.modules else len(self.modules)
        return rank, self._sequence[cls]

    def names(self) -> list[str]:
        self._load()
        ordered = sorted(self._classes.values(), key=self._position)
        return [cls.name for cls in ordered]  # type: ignore[attr-defined]

    def get(self, name: str) -> type[T]:
        self._load()
        try:
            return self._classes[name]
        except KeyError:
            from swarmpath.names import unknown

            raise self.error(unknown(self.kind, name, self.names())) from None


def resolve_params(
    owner: str,
    defaults: Mapping[str, ParamValue],
    choices: Mapping[str, tuple[str, ...]],
    params: Mapping[str, Any] | None,
    error: Callable[[str], Exception],
) -> dict[str, ParamValue]:
    """``defaults`` updated with ``params``; each value must match its default's type."""
    merged: dict[str, ParamValue] = dict(defaults)
    for key, value in (params or {}).items():
        if key not in defaults:
            from swarmpath.names import did_you_mean

            valid = ", ".join(sorted(defaults)) or "none"
            hint = did_you_mean(str(key), list(defaults))
            raise error(f"{owner} has no parameter {key!r}{hint}; valid: {valid}")
        default = defaults[key]
        if isinstance(default, bool):
            if not isinstance(value, bool):
                raise error(f"{owner}.{key} must be true or false, got {value!r}")
        elif isinstance(default, str):
            allowed = choices.get(key, ())
            if not isinstance(value, str) or (allowed and value not in allowed):
                raise error(f"{owner}.{key} must be one of {', '.join(allowed)}; got {value!r}")
        elif isinstance(default, int):
            if isinstance(value, bool) or not isinstance(value, int | float) or (
                float(value) != int(value)
            ):
                raise error(f"{owner}.{key} must be an integer, got {value!r}")
            value = int(value)
        else:
            if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(
                value
            ):
                raise error(f"{owner}.{key} must be a finite number, got {value!r}")
            value = float(value)
        merged[key] = value
    return merged
