"""Name registries and typed parameters, shared by optimizers and planners.

A :class:`Registry` is the single source of a family's names: modules register their classes when
imported, the registry imports its modules on first use and lists names in module order.
:func:`resolve_params` merges user parameters over a class's defaults, checking each against the
type of its default (and the allowed choices of string parameters), with messages that name the
parameter and list what is valid.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import numpy as np

if TYPE_CHECKING:
    from swarmpath.plugins.origin import Origin

ParamValue = float | int | bool | str
T = TypeVar("T")


class Registry(Generic[T]):
    """Named entries of one kind (optimizer classes, planner classes, benchmark functions).

    The built-in entries come from importing ``package.<module>`` for each of ``modules`` (they
    register themselves); plugins then come from :func:`swarmpath.plugins.load_plugins` (entry
    point ``group``, ``SWARMPATH_PLUGINS``), both on first use. Each name remembers its
    :class:`~swarmpath.plugins.origin.Origin`; a name registered again by different code is
    refused with both origins named (:class:`ExtensionClash`).
    """

    def __init__(
        self,
        kind: str,
        package: str,
        modules: tuple[str, ...],
        error: Callable[[str], Exception],
        group: str = "",
    ):
        self.kind = kind  # "optimizer", "planner", "function": used in messages
        self.package = package
        self.modules = modules
        self.error = error
        self.group = group  # entry-point group of its plugins
        self._entries: dict[str, T] = {}
        self._origins: dict[str, Origin] = {}
        self._sequence: dict[int, int] = {}
        self._loaded = False
        self._loading = False
        # name prefix -> (builds the entry for a name with it, origin of that code)
        self._families: dict[str, tuple[Callable[[str], T], Origin]] = {}

    def register(self, entry: T, origin: Origin | None = None) -> T:
        """Add ``entry`` under its ``name`` (usable as a class decorator); returns it."""
        name = getattr(entry, "name", None)
        if not isinstance(name, str) or not name.strip() or name != name.strip():
            raise ValueError(f"a {self.kind} needs a non-empty name without surrounding spaces, "
                             f"got {name!r}")
        if "," in name:
            raise ValueError(f"{self.kind} name {name!r} must not contain a comma")
        found = origin or origin_for(_module_of(entry))
        if not found.builtin:
            self._load_builtins()  # a clash with a built-in is found now, whatever loads first
        known = self._entries.get(name)
        if known is not None and known is not entry:
            before = self._origins[name]
            if before != found:  # the same code registering again (a reload) replaces
                raise ExtensionClash(
                    f"{self.kind} {name!r} from {found.describe()} clashes with {self.kind} "
                    f"{name!r} from {before.describe()}: rename one of them"
                )
        self._entries[name] = entry
        self._origins[name] = found
        self._sequence.setdefault(id(entry), len(self._sequence))
        return entry

    def unregister(self, name: str) -> None:
        entry = self._entries.pop(name)
        self._origins.pop(name, None)
        self._sequence.pop(id(entry), None)

    def _load_builtins(self) -> None:
        if not self._loaded and not self._loading:
            self._loading = True
            try:
                for module in self.modules:
                    importlib.import_module(f"{self.package}.{module}")
            finally:
                self._loading = False
            self._loaded = True

    def _load(self) -> None:
        if not self._loaded:
            self._load_builtins()
        from swarmpath.plugins.loading import load_plugins

        load_plugins(self.group)

    def _position(self, name: str) -> tuple[int, int, int]:
        """Built-ins first, in module order then registration order; plugins after them, in
        registration order."""
        entry = self._entries[name]
        builtin = self._origins[name].builtin
        module = _module_of(entry).rsplit(".", 1)[-1]
        rank = self.modules.index(module) if builtin and module in self.modules else len(
            self.modules)
        return (0 if builtin else 1), rank, self._sequence[id(entry)]

    def names(self, builtin: bool | None = None) -> list[str]:
        """Registered names in catalogue order (``builtin``: only built-ins / only plugins)."""
        self._load()
        ordered = sorted(self._entries, key=self._position)
        if builtin is None:
            return ordered
        return [n for n in ordered if self._origins[n].builtin == builtin]

    def get(self, name: str) -> T:
        self._load()
        entry = self._entries.get(name)
        if entry is not None:
            return entry
        for prefix, (build, _origin) in self._families.items():
            if name.startswith(prefix):
                return build(name)  # raises self.error naming what is wrong
        from swarmpath.names import unknown

        raise self.error(unknown(self.kind, name, self.names() + self.families()))

    def add_family(self, prefix: str, build: Callable[[str], T]) -> None:
        """Names ``<prefix><anything>`` mean ``build(name)`` (e.g. ``swarm:<optimizer>``, a
        planner for every optimizer); they are not listed by :meth:`names`."""
        self._families[prefix] = (build, origin_for(caller_module()))

    def families(self) -> list[str]:
        """The families as users write them: ``swarm:<name>``."""
        self._load()
        return [f"{prefix}<name>" for prefix in self._families]

    def origin(self, name: str) -> Origin:
        self.get(name)
        for prefix, (_build, origin) in self._families.items():
            if name not in self._origins and name.startswith(prefix):
                return origin
        return self._origins[name]

    def __contains__(self, name: object) -> bool:
        self._load()
        return name in self._entries

    def registered(self, name: str) -> bool:
        """Whether ``name`` is registered now, without loading anything (registering code uses
        this: loading plugins from inside an import would run them half-imported)."""
        return name in self._entries


class ExtensionClash(ValueError):
    """Two pieces of code registered the same name; the message names both origins."""


def _module_of(entry: object) -> str:
    """The module that defines an entry: a class's own; an instance's ``origin_module`` (a
    function's kernel's)."""
    if isinstance(entry, type):
        return entry.__module__
    return str(getattr(entry, "origin_module", None) or type(entry).__module__)


def caller_module(depth: int = 2) -> str:
    """The module of the code that called the registering function (``depth`` frames up): the
    origin of what it registers, whatever module defined the pieces (a plugin that builds its
    function from swarmpath's kernels, a class made by ``type()``, is still the plugin)."""
    return str(sys._getframe(depth).f_globals.get("__name__", ""))


def origin_for(module: str) -> Origin:
    """The origin of an entry defined in ``module``: swarmpath's own modules are built-in; code
    loaded by the plugin loader is the distribution or file it is loading; other code is found
    from its module (:func:`swarmpath.plugins.origin.origin_of_module`)."""
    from swarmpath.plugins.origin import builtin_origin, origin_of_module

    if module == "swarmpath" or module.startswith("swarmpath."):
        return builtin_origin(module)
    from swarmpath.plugins.loading import loading_origin

    return loading_origin(module) or origin_of_module(module)


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
