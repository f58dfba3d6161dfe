"""Where an extension comes from, and a digest of its code.

Every name in a registry has an :class:`Origin`: ``built-in`` (swarmpath itself), a
``distribution`` (an installed package, with its version), a ``file`` (``--plugin my_gwo.py``) or a
``module`` (imported by name, not part of any installed distribution). Its ``digest`` is a
sha256 over the source files of that code, so two processes (a coordinator and a worker, a laptop
and a farm) can tell whether they would run the same extension:

* a file plugin: the file;
* a package (distribution or module plugin): every ``.py`` file of its top-level package, in
  sorted relative order, each as its path and its bytes;
* a built-in: the module that defines it (not all of swarmpath: editing one algorithm changes no
  other's digest).

Digests are computed on first request and cached per set of files.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import sys
from dataclasses import dataclass, field
from pathlib import Path

BUILTIN = "built-in"
DISTRIBUTION = "distribution"
FILE = "file"
MODULE = "module"
#: Characters of a digest shown in tables and messages (the full 64 are kept and compared).
SHORT = 12


@dataclass(frozen=True)
class Origin:
    """``source`` (built-in, distribution, file, module), ``label`` (the distribution's name, the
    file's path or the module's name), ``version`` (a distribution's; swarmpath's for built-ins)
    and the files whose bytes make the digest."""

    source: str
    label: str
    version: str = ""
    files: tuple[str, ...] = field(default=(), compare=False)
    root: str = field(default="", compare=False)

    @property
    def builtin(self) -> bool:
        return self.source == BUILTIN

    @property
    def digest(self) -> str:
        return code_digest(self.files, self.root)

    def describe(self) -> str:
        """``built-in``, ``distribution swarmpath-example 0.1.0``, ``file /x/my_gwo.py``."""
        if self.builtin:
            return BUILTIN
        version = f" {self.version}" if self.version else ""
        return f"{self.source} {self.label}{version}"


@functools.lru_cache(maxsize=512)
def code_digest(files: tuple[str, ...], root: str = "") -> str:
    """sha256 over ``files`` (sorted by their path relative to ``root``): each file's relative
    path, a NUL, its length and its bytes. Empty when there is no file to read."""
    if not files:
        return ""
    h = hashlib.sha256()
    base = Path(root) if root else None
    rows = []
    for name in files:
        path = Path(name)
        rel = path.relative_to(base).as_posix() if base is not None else path.name
        rows.append((rel, path))
    for rel, path in sorted(rows):
        try:
            data = path.read_bytes()
        except OSError:
            data = b""
        h.update(rel.encode() + b"\0" + str(len(data)).encode() + b"\0" + data)
    return h.hexdigest()


def module_file(module: str) -> Path | None:
    mod = sys.modules.get(module)
    path = getattr(mod, "__file__", None)
    return Path(path).resolve() if path else None


def package_files(module: str) -> tuple[tuple[str, ...], str]:
    """The ``.py`` files of ``module``'s top-level package (or the module's own file when it is
    a top-level module), and the directory they are relative to."""
    top = module.split(".", 1)[0]
    top_mod = sys.modules.get(top)
    paths = list(getattr(top_mod, "__path__", []) or [])
    if paths:
        root = Path(paths[0]).resolve()
        files = sorted(str(p) for p in root.rglob("*.py") if "__pycache__" not in p.parts)
        return tuple(files), str(root.parent)
    own = module_file(module)
    if own is None:
        return (), ""
    return (str(own),), str(own.parent)


@functools.lru_cache(maxsize=64)
def distribution_of(top_level: str) -> tuple[str, str] | None:
    """(name, version) of the installed distribution that provides the top-level package."""
    names = importlib.metadata.packages_distributions().get(top_level) or []
    for name in names:
        try:
            return name, importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            continue
    return None


def builtin_origin(module: str) -> Origin:
    from swarmpath import __version__

    own = module_file(module)
    files = (str(own),) if own is not None else ()
    return Origin(BUILTIN, "swarmpath", __version__, files, str(own.parent) if own else "")


def file_origin(path: Path) -> Origin:
    resolved = path.resolve()
    return Origin(FILE, str(resolved), "", (str(resolved),), str(resolved.parent))


def origin_of_module(module: str) -> Origin:
    """The origin of code defined in ``module`` (already imported), found from the module alone:
    swarmpath's own modules are built-in; a module of an installed distribution is that
    distribution; any other is its file (or the module's name when it has no file)."""
    if module == "swarmpath" or module.startswith("swarmpath."):
        return builtin_origin(module)
    top = module.split(".", 1)[0]
    dist = distribution_of(top)
    if dist is not None:
        files, root = package_files(module)
        return Origin(DISTRIBUTION, dist[0], dist[1], files, root)
    if getattr(sys.modules.get(top), "__path__", None):
        files, root = package_files(module)
        return Origin(MODULE, top, "", files, root)
    own = module_file(module)
    if own is not None:
        return file_origin(own)
    return Origin(MODULE, module)
