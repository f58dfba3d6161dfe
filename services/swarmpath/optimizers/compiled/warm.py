"""Compile (or load from numba's cache) the kernels a study needs, before it runs.

A kernel is compiled on its first use in a fresh environment (seconds of CPU each: LLVM work),
then loaded from numba's cache (:func:`~swarmpath.optimizers.compiled.versioned_cache_dir`) by
every later process of the same tree. :func:`warm` pays that first use up front, for the
algorithms and functions given, and says what each cost: ``swarmpath warmup`` after an install,
or a worker before it leases.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass

from swarmpath.functions import get_function
from swarmpath.optimizers.compiled.objectives import compiled_names, has_objective, objective_for
from swarmpath.optimizers.compiled.registry import find_kernel, kernel_names


@dataclass(frozen=True)
class Warmed:
    """One piece made ready: ``kind`` ("function", "algorithm" or "map": the world's clearance
    and sensing kernels every map run calls), its name, the CPU seconds
    its compilation (or its load from the cache) took in this process."""

    kind: str
    name: str
    seconds: float


def algorithms_with_kernels(algorithms: Sequence[str] | None) -> list[str]:
    """The registered names of ``algorithms`` (None: every algorithm with a kernel); KeyError
    naming one that is unknown or has no kernel."""
    from swarmpath.optimizers.registry import get_optimizer

    if algorithms is None:
        return kernel_names()
    out = []
    for a in algorithms:
        name = get_optimizer(a).name
        if find_kernel(name) is None:
            raise KeyError(f"algorithm {name!r} has no compiled kernel (these do: "
                           f"{', '.join(kernel_names())})")
        out.append(name)
    return out


def functions_with_objectives(functions: Sequence[str] | None) -> list[str]:
    """``functions`` (None: every function with a compiled objective); KeyError naming one
    that is unknown or has none."""
    if functions is None:
        return compiled_names()
    for name in functions:
        if not has_objective(get_function(name)):
            raise KeyError(f"function {name!r} has no compiled objective (these do: "
                           f"{', '.join(compiled_names())})")
    return list(functions)


def objective_pieces(functions: Iterable[object]) -> list[tuple[str, str]]:
    """The objective pieces of these registered functions, each once, by the name its compiled
    objective is cached under (an instance of a suite function shares its base's)."""
    from swarmpath.optimizers.compiled.objectives import _population_name

    names = dict.fromkeys(_population_name(fn) for fn in functions)  # type: ignore[arg-type]
    return [("function", n) for n in names]


def pieces(algorithms: Sequence[str] | None = None, functions: Sequence[str] | None = None,
           maps: bool | None = None) -> list[tuple[str, str]]:
    """The pieces :func:`warm` makes ready for these arguments, as ``(kind, name)``, functions
    first (KeyError as :func:`algorithms_with_kernels` and :func:`functions_with_objectives`);
    an instance of a suite function is its base's objective (``bbob:f3@i7`` -> ``bbob:f3``)."""
    out = objective_pieces(get_function(n) for n in functions_with_objectives(functions))
    out += [("algorithm", a) for a in algorithms_with_kernels(algorithms)]
    if maps or (maps is None and algorithms is None and functions is None):
        out.append(("map", "clearance"))
    return out


def warm(algorithms: Sequence[str] | None = None,
         functions: Sequence[str] | None = None, *, shared: bool = False,
         start: int = 0, maps: bool | None = None, cold_only: bool = False) -> list[Warmed]:
    """Make the compiled objectives of ``functions`` and the kernels of ``algorithms`` ready
    (None: every one there is; KeyError as :func:`algorithms_with_kernels` and
    :func:`functions_with_objectives`), and with ``maps`` (None: when both are None, i.e. a
    warm-up of everything) the world's clearance and sensing kernels as the piece
    ``("map", "clearance")``. Functions first: an algorithm's first run then times its kernel
    alone. Each piece made ready is marked so in the cache directory (:func:`cold`).

    ``cold_only``: skip the pieces already marked (they are not in the list returned): what
    the install's warm-up and a study's first run compile, nothing when the tree's cache is
    filled.

    ``shared``: other processes of this tree may be warming at the same time (a worker's slots,
    the workers of ``swarmpath up``): each piece is made ready under a lock of its own in the
    cache directory, so one process compiles it while the others make other pieces and load
    it from the cache at the end (the first piece they wait for: every kernel's warm-up run
    evaluates it), and the pieces after the first function are taken in turn from position
    ``start`` (processes starting at different positions compile different pieces at once)."""
    from swarmpath.optimizers.api import minimize
    from swarmpath.optimizers.compiled.ready import made_ready
    from swarmpath.optimizers.registry import get_optimizer

    wanted = pieces(algorithms, functions, maps)
    names = [name for kind, name in wanted if kind == "function"]
    first = names[0] if names else "F1"
    first_dim = _smallest_dim(first)

    def function(name: str) -> None:
        objective_for(get_function(name))

    def algorithm(a: str) -> None:
        # one tiny run: a kernel has one signature whatever the sizes, so this is its build
        minimize(a, first, dim=first_dim, agents=max(10, get_optimizer(a).min_agents),
                 iterations=2, runs=1, backend="numba")

    makers: dict[str, Callable[[str], None]] = {
        "function": function, "algorithm": algorithm, "map": _warm_maps}
    order = {piece: i for i, piece in enumerate(wanted)}
    todo = list(wanted)
    if shared and len(todo) > 1:
        # the first function first (every kernel's warm-up run evaluates it), then in turn
        head, rest = todo[:1] if names else [], todo[1:] if names else todo
        k = start % len(rest)
        todo = head + rest[k:] + rest[:k]
    stamp = _source_stamp()
    out = []

    def make(kind: str, name: str, wait: bool) -> bool:
        """Make one piece ready; False (nothing done) when another process holds its lock and
        ``wait`` is false."""
        started = time.process_time()
        with (_piece_lock(kind, _compiled_as(kind, name), wait) if shared
              else contextlib.nullcontext(True)) as held:
            if not held:
                return False
            if cold_only and _is_marked(kind, name, stamp):
                made_ready([(kind, name)])
                return True
            makers[kind](name)
            _mark(kind, name, stamp)
            made_ready([(kind, name)])
        out.append(Warmed(kind, name, time.process_time() - started))
        return True

    # shared: a piece another process is making is passed over (it makes the next one
    # meanwhile: two processes walking the same list in one direction would otherwise wait
    # for each other at every piece), then waited for at the end; the first one always
    later = [p for i, p in enumerate(todo) if not make(*p, wait=i == 0)]
    for kind, name in later:
        make(kind, name, wait=True)
    out.sort(key=lambda w: order[(w.kind, w.name)])  # as asked, whatever order they were made in
    return out


def warm_in_processes(algorithms: Sequence[str] | None, functions: Sequence[str] | None, *,
                      jobs: int, maps: bool | None = None,
                      cold_only: bool = False) -> list[Warmed]:
    """:func:`warm` in ``jobs`` processes at once (this one and ``jobs - 1`` started here), each
    starting at its own share of the pieces, under the pieces' locks (``shared``): a piece is
    compiled by one of them and the others find it marked (``cold_only``) or load it from the
    cache. On two cores the install's warm-up (74 s of CPU in a fresh tree) takes about half
    the wall time. Each piece once in the list returned, with the CPU seconds of the process
    that made it (the largest: a load from the cache costs less than the compile)."""
    if jobs <= 1:
        return warm(algorithms, functions, maps=maps, cold_only=cold_only)
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    rest = max(1, len(pieces(algorithms, functions, maps)) - 1)  # after the first function
    starts = [i * rest // jobs for i in range(jobs)]
    args = (None if algorithms is None else list(algorithms),
            None if functions is None else list(functions))
    # spawned, not forked: a process that compiles needs no state of this one's numba
    with ProcessPoolExecutor(jobs - 1, mp_context=multiprocessing.get_context("spawn")) as pool:
        others = [pool.submit(warm, *args, shared=True, start=k, maps=maps, cold_only=cold_only)
                  for k in starts[1:]]
        done = warm(*args, shared=True, start=starts[0], maps=maps, cold_only=cold_only)
        for future in others:
            done += future.result()
    best: dict[tuple[str, str], Warmed] = {}
    for w in done:
        if (w.kind, w.name) not in best or w.seconds > best[(w.kind, w.name)].seconds:
            best[(w.kind, w.name)] = w
    order = {piece: i for i, piece in enumerate(pieces(algorithms, functions, maps))}
    return sorted(best.values(), key=lambda w: order[(w.kind, w.name)])


def _compiled_as(kind: str, name: str) -> str:
    """The piece whose compilation also makes ``name`` ready: algorithms that share one kernel
    (COOT, mCOOT and ICOOT; HPO and IHPO; MFB and HPSO-MFB: one ``run``, other parameters)
    compile it once, so a shared warm-up locks them as one piece (two processes compiled COOT's
    kernel at once before: 20 of the install's 95 s of CPU)."""
    if kind != "algorithm":
        return name
    run = find_kernel(name).run  # type: ignore[union-attr]
    return next(n for n in kernel_names() if find_kernel(n).run is run)  # type: ignore[union-attr]


def _smallest_dim(name: str) -> int:
    """The smallest dimension function ``name`` is defined in (a CEC function's smallest
    official D; 2 for the others): an algorithm's warm-up run evaluates it there."""
    fn = get_function(name)
    dims = getattr(fn, "dimensions", None)
    return int(min(dims)) if dims else max(2, int(getattr(fn, "min_dim", 2)))


def compile_cold(algorithms: Sequence[str], functions: Sequence[str], maps: bool,
                 note: Callable[[str], None]) -> list[Warmed]:
    """A study's first run in a tree whose cache lacks some of its pieces: tell ``note`` once
    (one line: what compiles, and that ``swarmpath warmup`` does it ahead), then compile them
    here, before the study's runs (its worker processes then load them from the cache instead
    of each compiling the same kernels). Nothing, and no note, when every piece is ready."""
    missing = cold(pieces(algorithms, functions, maps))
    if not missing:
        return []
    names = ", ".join(name for _kind, name in missing[:6]) + (", ..." if len(missing) > 6 else "")
    note(f"compiling the numba kernels this study needs ({names}): once per installed tree, "
         "seconds of CPU each; `swarmpath warmup` compiles every kernel ahead")
    return warm(algorithms, functions, maps=maps, cold_only=True)


def request_cold(algorithms: Sequence[str], functions: Sequence[str], maps: bool,
                 note: Callable[[str], None]) -> list[tuple[str, str]]:
    """A study with backend "auto" in a tree whose cache lacks some of its pieces: ask for them
    in the background (:mod:`.ready`: the study runs the numpy reference for them, the same
    numbers, while a low-priority process compiles them for later runs) and tell ``note`` once.
    Returns the pieces asked for. Where the cache cannot be written, :func:`compile_cold` (each
    process would compile them: once here, before the study's worker processes)."""
    from swarmpath.optimizers.compiled import ready

    missing = ready.missing(pieces(algorithms, functions, maps))
    if not missing:
        return []
    if not ready.cache_writable():
        compile_cold(algorithms, functions, maps, note)
        return []
    started = ready.request(missing) is not None
    names = ", ".join(name for _kind, name in missing[:6]) + (", ..." if len(missing) > 6 else "")
    how = ("a low-priority background process compiles them for later runs" if started else
           "a background compile is under way" if os.environ.get(ready.BACKGROUND_ENV) != "0" else
           f"{ready.BACKGROUND_ENV}=0: nothing compiles them")
    note(f"the numba kernels of {names} are not compiled yet: the numpy reference runs them "
         f"(the same numbers); {how}; `swarmpath warmup` compiles every kernel ahead")
    return missing


def cold(wanted: Sequence[tuple[str, str]]) -> list[tuple[str, str]]:
    """The pieces of ``wanted`` (as :func:`pieces` lists them) that no process of this tree has
    made ready since its compiled sources last changed: a marker file per piece in numba's
    cache directory holds the sources' modification times and sizes (numba's own test of a
    cached kernel: a source touched since is compiled again at its next use)."""
    stamp = _source_stamp()
    return [(kind, name) for kind, name in wanted if not _is_marked(kind, name, stamp)]


def _source_stamp() -> str:
    """The compiled sources' paths, modification times and sizes and numba's and Python's
    versions, hashed: what numba compares (per kernel, its own file's) before it loads a kernel
    from the cache."""
    import sys

    import numba

    from swarmpath.optimizers.compiled import compiled_sources

    digest = hashlib.sha256(f"{numba.__version__}\0{sys.version}\0".encode())
    for path in compiled_sources():
        st = path.stat()
        digest.update(f"{path.as_posix()}\0{st.st_mtime!r}\0{st.st_size}\0".encode())
    return digest.hexdigest()


def _marker(kind: str, name: str, suffix: str) -> str:
    from numba.core import config

    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
    return os.path.join(str(config.CACHE_DIR),  # type: ignore[attr-defined]
                        f".warm-{kind}-{safe}.{suffix}")


def _is_marked(kind: str, name: str, stamp: str) -> bool:
    try:
        with open(_marker(kind, name, "done")) as f:
            return f.read() == stamp
    except OSError:
        return False


def _mark(kind: str, name: str, stamp: str) -> None:
    """Mark a piece ready (no marker where the directory cannot be written: numba cannot cache
    there either, so the piece is not ready for the next process)."""
    path = _marker(kind, name, "done")
    try:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        part = f"{path}.{os.getpid()}.tmp"  # processes marking the same piece at once
        with open(part, "w") as f:
            f.write(stamp)
        os.replace(part, path)
    except OSError:
        pass


def _warm_maps(_name: str) -> None:
    from swarmpath.world.clearance import warm as warm_clearance

    warm_clearance()


@contextlib.contextmanager
def _piece_lock(kind: str, name: str, wait: bool = True) -> Iterator[bool]:
    """An exclusive lock on one piece, shared by the processes of this tree (a file lock in
    numba's cache directory, released by the kernel if its holder dies): yields whether it is
    held (False only without ``wait``, when another holds it); no lock where the directory
    cannot be written (then numba cannot cache there either)."""
    import fcntl

    try:
        path = _marker(kind, name, "lock")
        os.makedirs(os.path.dirname(path), exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield True
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if wait else fcntl.LOCK_NB))
        except BlockingIOError:
            yield False
            return
        yield True
    finally:
        os.close(fd)  # releases the lock
