"""Loading plugins: installed entry points, ``--plugin`` and ``SWARMPATH_PLUGINS``.

Installed plugins declare entry points in the groups of :data:`GROUPS`; each entry point loads
one optimizer class, one planner class, or (functions group) one
:class:`~swarmpath.functions.BenchmarkFunction` or :class:`~swarmpath.functions.Suite`, which
the loader registers under the entry point's name (a module that registers its own classes at
import as well is fine: registering the same object twice is a no-op). Quick plugins are a
Python file or an importable module named by ``--plugin`` or in ``SWARMPATH_PLUGINS`` (paths
and module names separated by the platform's path separator); they register their extensions at
import (``@register``, ``register_function``, ``register_suite``).

Every registry loads its group's entry points and the ``SWARMPATH_PLUGINS`` plugins on first
use, in every process: so a ``-j N`` child, a worker and its slots (spawned processes inherit
the environment, where ``--plugin`` adds what it loaded: :func:`export`) all see the plugins of
the command that started them. A name that clashes is refused there and then
(:class:`~swarmpath.registry.ExtensionClash`, naming both origins); an entry point that fails to
import is left out and reported (:func:`problems`, ``swarmpath plugins``), never fatal, while
a plugin named explicitly that fails raises :class:`PluginError`.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import importlib.metadata
import importlib.util
import logging
import os
import sys
from collections.abc import Iterable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmpath.plugins.origin import DISTRIBUTION, Origin, file_origin, package_files

ENV = "SWARMPATH_PLUGINS"
#: Entry-point group of each kind of extension.
GROUPS = {
    "optimizer": "swarmpath.optimizers",
    "function": "swarmpath.functions",
    "planner": "swarmpath.planners",
}
log = logging.getLogger("swarmpath.plugins")


class PluginError(ValueError):
    """A plugin named on the command line or in SWARMPATH_PLUGINS could not be loaded."""


@dataclass(frozen=True)
class Problem:
    """An installed entry point that could not be loaded (it is left out)."""

    group: str
    name: str
    origin: str
    message: str


@dataclass
class _State:
    env_done: bool = False
    groups_done: set[str] | None = None
    loaded: dict[str, Origin] | None = None  # spec (absolute path or module) -> origin
    problems: list[Problem] | None = None


_state = _State(groups_done=set(), loaded={}, problems=[])
# While a plugin loads: (its module name, or the top-level package of an entry point's module;
# the origin of what that code registers, or the distribution's (name, version)).
_context: ContextVar[tuple[str, Origin | tuple[str, str]] | None] = ContextVar(
    "swarmpath_plugin_context", default=None
)


def loading_origin(module: str) -> Origin | None:
    """The origin of an entry registered from ``module`` while a plugin loads, if it is that
    plugin's code."""
    ctx = _context.get()
    if ctx is None:
        return None
    prefix, what = ctx
    if module != prefix and not module.startswith(prefix + "."):
        return None
    if isinstance(what, Origin):
        return what
    files, root = package_files(module)
    return Origin(DISTRIBUTION, what[0], what[1], files, root)


@contextlib.contextmanager
def _loading(prefix: str, what: Origin | tuple[str, str]) -> Iterator[None]:
    token = _context.set((prefix, what))
    try:
        yield
    finally:
        _context.reset(token)


def load_plugins(group: str = "") -> None:
    """The ``SWARMPATH_PLUGINS`` plugins (once per process), then ``group``'s entry points (once
    per group). Registries call this on first use."""
    if not _state.env_done:
        _state.env_done = True
        for spec in split(os.environ.get(ENV, "")):
            load_plugin(spec, via=ENV)
    assert _state.groups_done is not None
    if group and group not in _state.groups_done:
        _state.groups_done.add(group)
        for ep in _entry_points(group):
            _load_entry_point(group, ep)


def load_all() -> None:
    """Every group's entry points and the environment's plugins (``swarmpath plugins``)."""
    for group in GROUPS.values():
        load_plugins(group)


def split(text: str) -> list[str]:
    return [part.strip() for part in text.split(os.pathsep) if part.strip()]


def _entry_points(group: str) -> list[importlib.metadata.EntryPoint]:
    found = importlib.metadata.entry_points(group=group)
    unique: dict[tuple[str, str], importlib.metadata.EntryPoint] = {}
    for ep in found:  # the same distribution found twice on sys.path: once
        unique.setdefault((ep.name, ep.value), ep)
    return sorted(unique.values(), key=lambda ep: ep.name)


def _load_entry_point(group: str, ep: importlib.metadata.EntryPoint) -> None:
    dist = getattr(ep, "dist", None)
    name = getattr(dist, "name", None) or ep.module.split(".", 1)[0]
    version = getattr(dist, "version", "") or ""
    label = f"distribution {name} {version}".strip()
    top = ep.module.split(".", 1)[0]
    try:
        with _loading(top, (name, version)):
            obj = ep.load()
            files, root = package_files(ep.module)
            register_loaded(group, ep.name, obj, Origin(DISTRIBUTION, name, version, files, root))
    except Exception as exc:
        from swarmpath.registry import ExtensionClash

        if isinstance(exc, ExtensionClash):
            raise
        message = f"{type(exc).__name__}: {exc}"
        assert _state.problems is not None
        _state.problems.append(Problem(group, ep.name, label, message))
        log.warning("plugin %s (entry point %r of %s) left out: %s", group, ep.name, label,
                    message)


def register_loaded(group: str, name: str, obj: Any, origin: Origin) -> None:
    """Register what the entry point ``name`` of ``group`` loaded, from ``origin`` (a
    TypeError/ValueError when it is not an extension of that kind, or not named ``name``)."""
    if group == GROUPS["optimizer"]:
        from swarmpath.optimizers.base import Optimizer
        from swarmpath.optimizers.registry import REGISTRY as OPTIMIZERS

        _check_class(obj, Optimizer, "an Optimizer subclass", name)
        OPTIMIZERS.register(obj, origin)
    elif group == GROUPS["planner"]:
        from swarmpath.planners.base import REGISTRY as PLANNERS
        from swarmpath.planners.base import Planner

        _check_class(obj, Planner, "a Planner subclass", name)
        PLANNERS.register(obj, origin)
    elif group == GROUPS["function"]:
        from swarmpath.functions.registry import (
            BenchmarkFunction,
            Suite,
            register_function,
            register_suite,
        )

        if callable(obj) and not isinstance(obj, BenchmarkFunction | Suite):
            obj = obj()  # a factory (a suite built on demand)
        if isinstance(obj, Suite):
            _check_name(obj.name, name)
            register_suite(obj, origin)
        elif isinstance(obj, BenchmarkFunction):
            _check_name(obj.name, name)
            register_function(obj, origin)
        else:
            raise TypeError(f"loads {type(obj).__name__}, not a BenchmarkFunction or a Suite")
    else:  # pragma: no cover - GROUPS is the only caller's source
        raise ValueError(f"unknown group {group!r}")


def _check_class(obj: Any, base: type, what: str, name: str) -> None:
    if not (isinstance(obj, type) and issubclass(obj, base)):
        raise TypeError(f"loads {obj!r}, not {what}")
    _check_name(getattr(obj, "name", None), name)


def _check_name(registered: Any, name: str) -> None:
    if registered != name:
        raise ValueError(f"the entry point is named {name!r} but loads {registered!r}: "
                         "name it as the extension is named")


def load_plugin(spec: str, via: str = "--plugin") -> Origin:
    """Import a plugin file (``path/to/x.py``) or module (``package.module``); what it
    registers is attributed to it. Loading the same plugin again does nothing. PluginError
    (naming ``via`` and the plugin) when it cannot be loaded."""
    key, path = _key(spec)
    assert _state.loaded is not None
    if key in _state.loaded:
        return _state.loaded[key]
    if path is not None:
        origin = _load_file(path, via)
    else:
        origin = _load_module(spec, via)
    _state.loaded[key] = origin
    return origin


def _key(spec: str) -> tuple[str, Path | None]:
    text = spec.strip()
    if not text:
        raise PluginError("empty plugin name")
    looks_like_file = text.endswith(".py") or os.sep in text or (os.altsep or os.sep) in text
    if looks_like_file:
        path = Path(text).expanduser().resolve()
        return str(path), path
    return text, None


def module_name_for(path: Path) -> str:
    """The module name a plugin file is imported as: the same in every process (a spawned
    child unpickling one of its classes finds it)."""
    stem = "".join(c if c.isalnum() else "_" for c in path.stem)
    tag = hashlib.sha256(str(path).encode()).hexdigest()[:10]
    return f"swarmpath_plugin_{stem}_{tag}"


def _load_file(path: Path, via: str) -> Origin:
    if not path.is_file():
        raise PluginError(f"{via}: {str(path)!r} is not a file")
    name = module_name_for(path)
    origin = file_origin(path)
    if name in sys.modules:
        return origin
    module_spec = importlib.util.spec_from_file_location(name, path)
    if module_spec is None or module_spec.loader is None:
        raise PluginError(f"{via}: cannot import {str(path)!r} (not a Python file?)")
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[name] = module
    try:
        with _loading(name, origin):
            module_spec.loader.exec_module(module)
    except Exception as exc:
        sys.modules.pop(name, None)
        _reraise(via, str(path), exc)
    return origin


def _load_module(name: str, via: str) -> Origin:
    from swarmpath.plugins.origin import origin_of_module

    try:
        importlib.import_module(name)
    except Exception as exc:
        _reraise(via, name, exc)
    return origin_of_module(name)


def _reraise(via: str, what: str, exc: Exception) -> None:
    """A clash as it is (it names both origins); anything else as a PluginError naming the
    plugin."""
    from swarmpath.registry import ExtensionClash

    if isinstance(exc, ExtensionClash):
        raise exc
    if isinstance(exc, ModuleNotFoundError) and exc.name == what:
        raise PluginError(f"{via}: no module named {what!r} (a file needs its .py suffix)") from exc
    raise PluginError(f"{via}: {what}: {type(exc).__name__}: {exc}") from exc


def export(specs: Iterable[str]) -> None:
    """Add plugins to ``SWARMPATH_PLUGINS`` of this process (files as absolute paths), so that
    every process it starts loads them too."""
    current = split(os.environ.get(ENV, ""))
    for spec in specs:
        key, path = _key(spec)
        value = str(path) if path is not None else key
        if value not in current:
            current.append(value)
    if current:
        os.environ[ENV] = os.pathsep.join(current)


def problems() -> list[Problem]:
    assert _state.problems is not None
    return list(_state.problems)


def loaded() -> dict[str, Origin]:
    """Plugins loaded by name (``--plugin``, ``SWARMPATH_PLUGINS``) in this process."""
    assert _state.loaded is not None
    return dict(_state.loaded)
