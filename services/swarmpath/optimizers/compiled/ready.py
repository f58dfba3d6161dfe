"""Backend "auto" on a cold cache: the numpy reference for what is not compiled yet, compiled in
the background meanwhile.

numba compiles a kernel at its first use in a fresh environment (seconds of CPU each; the
default ``swarmpath bench`` of every algorithm on F1-F13 spent 83 s compiling before its first
run). Backend "auto" runs a *piece* (``(kind, name)`` as :func:`.warm.pieces` lists them: an
algorithm's kernel, a function's objective, the map kernels) compiled only once it is ready:
made ready in this process (:func:`.warm.warm`, a ``backend="numba"`` run), or marked ready in
the tree's cache by any process (the warm-up's markers: the install's ``swarmpath warmup``, a
worker slot, an earlier study, a background compile). A marker is one small file read (about
25 us; the sources' stamp it is compared with is computed once per process, about 20 ms), the
same test :func:`.warm.cold` makes.

Otherwise auto runs the numpy reference, the same numbers to the last bit (auto picks only
kernels and objectives of tolerance 0.0, each compared with the reference bit for bit:
tests/test_compiled.py, test_compiled_suites.py, test_clearance_compiled.py), and asks
:func:`request` for the missing pieces: one detached process at the lowest priority
(:mod:`.background`) compiles them and marks them as the warm-up does, so that the later
calls of this process and every later process run them compiled. ``backend="numba"`` still
compiles on demand, and ``swarmpath up``'s slots still warm every piece before their first
lease (:func:`swarmpath.service.worker.slots.warm_compiled`).

Where the cache directory cannot be written nothing can be marked: auto then compiles in the
process that needs the piece, as numba alone does. ``SWARMPATH_BACKGROUND_COMPILE=0`` keeps the
numpy reference for cold pieces without starting a compile (the test suite sets it).
"""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
from collections.abc import Iterable, Sequence

from swarmpath.optimizers.compiled import warm as _warm

Piece = tuple[str, str]

#: ``0``: never start a background compile (auto still runs numpy for cold pieces).
BACKGROUND_ENV = "SWARMPATH_BACKGROUND_COMPILE"
#: The piece every map run needs compiled (the clearance and sensing kernels).
MAP_PIECE: Piece = ("map", "clearance")

_READY: set[Piece] = set()  # made ready in this process, or found marked
_REQUESTED: set[Piece] = set()  # handed to a background compile by this process
_STAMP: list[str] = []  # the compiled sources' stamp, computed once per process
_WRITABLE: list[bool] = []
_CHILDREN: list[subprocess.Popen[bytes]] = []  # reaped as they finish


def study_pieces(algorithm: str, functions: Iterable[object]) -> list[Piece]:
    """The pieces a ``backend="numba"`` run of ``algorithm`` on ``functions`` (registered
    :class:`~swarmpath.functions.BenchmarkFunction` objects with objectives) runs: each
    function's objective (by the name it is registered under: an instance of a suite function
    shares its base's) and the algorithm's kernel."""
    return [*_warm.objective_pieces(functions), ("algorithm", algorithm)]


def stamp() -> str:
    if not _STAMP:
        _STAMP.append(_warm._source_stamp())
    return _STAMP[0]


def missing(wanted: Sequence[Piece]) -> list[Piece]:
    """The pieces of ``wanted`` neither made ready in this process nor marked ready."""
    out = []
    for piece in wanted:
        if piece in _READY:
            continue
        if _warm._is_marked(*piece, stamp()):
            _READY.add(piece)
            continue
        out.append(piece)
    return out


def made_ready(wanted: Iterable[Piece], mark: bool = False) -> None:
    """``wanted`` are compiled (or loaded) in this process; with ``mark``, also marked for the
    other processes of this tree (a ``backend="numba"`` run that compiled them)."""
    for piece in wanted:
        if piece in _READY:
            continue
        _READY.add(piece)
        if mark:
            _warm._mark(*piece, stamp())


def ready_for_auto(wanted: Sequence[Piece]) -> bool:
    """Whether backend "auto" runs ``wanted`` compiled now: every piece ready, or the cache
    cannot be written (nothing could ever be marked: compile here). Otherwise False, after
    :func:`request` of the missing ones."""
    lack = missing(wanted)
    if not lack:
        return True
    if not cache_writable():
        return True
    request(lack)
    return False


def cache_writable() -> bool:
    """Whether numba can cache in this tree's cache directory (created if need be)."""
    if not _WRITABLE:
        directory = _cache_dir()
        try:
            os.makedirs(directory, exist_ok=True)
            ok = os.access(directory, os.W_OK)
        except OSError:
            ok = False
        _WRITABLE.append(ok)
    return _WRITABLE[0]


def request(wanted: Sequence[Piece]) -> subprocess.Popen[bytes] | None:
    """Start a detached, lowest-priority process compiling the pieces of ``wanted`` that this
    process has not asked for already (:mod:`.background`), unless one is running for this tree
    (the process that asked first; a piece still cold after it is asked for again by the next
    call that needs it) or background compiles are off (:data:`BACKGROUND_ENV`). The process
    holds the tree's background lock from the moment it starts: two processes of a study
    (``bench -j 2``) never start two. Returns it, or None."""
    for child in list(_CHILDREN):
        if child.poll() is not None:
            _CHILDREN.remove(child)
    todo = [p for p in wanted if p not in _REQUESTED]
    if not todo or os.environ.get(BACKGROUND_ENV, "1") == "0" or not cache_writable():
        return None
    try:
        fd = os.open(background_lock(), os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        return None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return None  # one is compiling: asked again by a later call if still cold
        log = open(os.path.join(_cache_dir(), ".warm-background.log"), "wb")
        with log:
            child = subprocess.Popen(
                [sys.executable, "-m", "swarmpath.optimizers.compiled.background",
                 *(f"{kind}:{name}" for kind, name in todo)],
                stdin=subprocess.DEVNULL, stdout=log, stderr=log, pass_fds=(fd,),
                process_group=0,  # not in the terminal's foreground group: Ctrl-C spares it
            )
    except OSError:
        return None
    finally:
        os.close(fd)  # the child's copy keeps the lock until it exits
    _REQUESTED.update(todo)
    _CHILDREN.append(child)
    return child


def background_lock() -> str:
    return os.path.join(_cache_dir(), ".warm-background.lock")


def _cache_dir() -> str:
    from numba.core import config

    return str(config.CACHE_DIR)  # type: ignore[attr-defined]
