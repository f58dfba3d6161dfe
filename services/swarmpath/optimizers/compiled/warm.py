"""Compile (or load from numba's cache) the kernels a study needs, before it runs.

A kernel is compiled on its first use in a fresh environment (seconds of CPU each: LLVM work),
then loaded from numba's cache (:func:`~swarmpath.optimizers.compiled.versioned_cache_dir`) by
every later process of the same tree. :func:`warm` pays that first use up front, for the
algorithms and functions given, and says what each cost: ``swarmpath warmup`` after an install,
or a worker before it leases.
"""

from __future__ import annotations

import contextlib
import os
import re
import time
from collections.abc import Callable, Iterator, Sequence
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


def warm(algorithms: Sequence[str] | None = None,
         functions: Sequence[str] | None = None, *, shared: bool = False,
         start: int = 0, maps: bool | None = None) -> list[Warmed]:
    """Make the compiled objectives of ``functions`` and the kernels of ``algorithms`` ready
    (None: every one there is; KeyError as :func:`algorithms_with_kernels` and
    :func:`functions_with_objectives`), and with ``maps`` (None: when both are None, i.e. a
    warm-up of everything) the world's clearance and sensing kernels as the piece
    ``("map", "clearance")``. Functions first: an algorithm's first run then times its kernel
    alone.

    ``shared``: other processes of this tree may be warming at the same time (a worker's slots,
    the workers of ``swarmpath up``): each piece is made ready under a lock of its own in the
    cache directory, so one process compiles it while the others wait and then load it from
    the cache, and the pieces after the first function are taken in turn from position
    ``start`` (processes starting at different positions compile different pieces at once)."""
    from swarmpath.optimizers.api import minimize
    from swarmpath.optimizers.registry import get_optimizer

    algos = algorithms_with_kernels(algorithms)
    names = functions_with_objectives(functions)
    first = names[0] if names else "F1"
    first_dim = _smallest_dim(first)

    def function(name: str) -> None:
        objective_for(get_function(name))

    def algorithm(a: str) -> None:
        # one tiny run: a kernel has one signature whatever the sizes, so this is its build
        minimize(a, first, dim=first_dim, agents=max(10, get_optimizer(a).min_agents),
                 iterations=2, runs=1, backend="numba")

    pieces: list[tuple[str, str, Callable[[str], None]]] = [
        ("function", n, function) for n in names]
    pieces += [("algorithm", a, algorithm) for a in algos]
    if maps or (maps is None and algorithms is None and functions is None):
        pieces.append(("map", "clearance", _warm_maps))
    order = {(kind, name): i for i, (kind, name, _make) in enumerate(pieces)}
    if shared and len(pieces) > 1:
        # the first function first (every kernel's warm-up run evaluates it), then in turn
        head, rest = pieces[:1] if names else [], pieces[1:] if names else pieces
        k = start % len(rest)
        pieces = head + rest[k:] + rest[:k]
    out = []
    for kind, name, make in pieces:
        started = time.process_time()
        with _piece_lock(kind, name) if shared else contextlib.nullcontext():
            make(name)
        out.append(Warmed(kind, name, time.process_time() - started))
    out.sort(key=lambda w: order[(w.kind, w.name)])  # as asked, whatever order they were made in
    return out


def _smallest_dim(name: str) -> int:
    """The smallest dimension function ``name`` is defined in (a CEC function's smallest
    official D; 2 for the others): an algorithm's warm-up run evaluates it there."""
    fn = get_function(name)
    dims = getattr(fn, "dimensions", None)
    return int(min(dims)) if dims else max(2, int(getattr(fn, "min_dim", 2)))


def _warm_maps(_name: str) -> None:
    from swarmpath.world.clearance import warm as warm_clearance

    warm_clearance()


@contextlib.contextmanager
def _piece_lock(kind: str, name: str) -> Iterator[None]:
    """An exclusive lock on one piece, shared by the processes of this tree (a file lock in
    numba's cache directory, released by the kernel if its holder dies); no lock where the
    directory cannot be written (then numba cannot cache there either)."""
    import fcntl

    from numba.core import config

    try:
        folder = str(config.CACHE_DIR)  # type: ignore[attr-defined]
        os.makedirs(folder, exist_ok=True)
        safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
        fd = os.open(os.path.join(folder, f".warm-{kind}-{safe}.lock"),
                     os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock
