"""Compiled kernels (numba): the ``backend="numba"`` of ``minimize``/``minimize_many``.

The numpy optimizers are the reference; a kernel here is an accelerated copy of one of them that
must give the same numbers, run for run (equal to the last bit, or within the ``tolerance`` it
declares, which every Result it computes records). Nothing in the numpy path imports this
package.

Kernel signature (one run; ``@njit(cache=True)``, or a Python shim calling one)::

    run(rng, objective, shifted, shift, lower, upper, agents, iterations, params)
        -> (best_fitness: float, best_position: (d,), curve: (iterations,), evaluations: int)

* ``rng``: the run's ``numpy.random.Generator`` (``run_generator(seed, r)``, purpose OPTIMIZER).
* ``objective``: the function's compiled objective (:func:`objectives.objective_for`: its
  address and traits); ``shifted`` (bool) and ``shift`` (d,): the run's shift (zeros when not
  shifted); ``lower``, ``upper`` (d,): the box.
* ``agents``, ``iterations``: ints. ``params``: float64 vector made by the kernel's ``pack``
  from the resolved parameters (choices as indices into their tuple).
* Returns what :class:`~swarmpath.optimizers.api.Result` holds for one run: the best value ever
  evaluated and its point (``Optimizer.evaluate``'s record, not an internal leader), the record
  after each iteration, and the number of counted evaluations.

Rules for kernel authors:

1. Draw through one stream (:func:`streams.open_stream` with your largest single draw as
   capacity; ``mixed=False``, a direct stream, when the algorithm draws uniforms only) and
   :func:`streams.take`: one ``take`` per ``rng.random``/``rng.normal`` call of the reference, of
   the same total size (``random_parts(k, ...)``/``random(k, ...)`` is one take of k parts: part
   i is ``[o + i * size, o + (i + 1) * size)``, C order inside a part), in the same order,
   uniforms and normals alike (a direct stream may merge consecutive takes into one).
   ``uniform(lo, hi, ...)`` is ``lo + (hi - lo) * u`` of one take; ``permutations`` is one
   uniform take and a stable argsort of each row; ``integers`` goes to the generator itself,
   unbuffered (call ``rng.integers`` at that point). A take may overwrite earlier numbers.
2. Evaluate through :func:`objectives.evaluate` exactly where the reference calls
   ``Optimizer.evaluate`` and with the same rows (it draws F7's noise); pass ``mask`` where the
   reference masks (False rows are not computed and get +inf) and count evaluations as it does.
   Keep the record with the first minimum and a strict ``<``, like ``Optimizer.evaluate``
   (:mod:`.best`).
3. Repeat the reference's arithmetic operation for operation: same association and order
   (``a * b + c`` stays that, ``np.sum`` over 3 rows is ``(x0 + x1) + x2``, ``x **= 2`` is
   ``x * x``), no ``fastmath``, no reassociation. numpy reductions along a contiguous axis add
   in a blocked order: use :func:`functions.dot` / :func:`functions.total` for ``einsum`` sums,
   and write ``np.sum`` along the last axis (pairwise, 8 accumulators past 8 elements) only with
   care. Python ``min``/``max`` equal ``np.minimum``/``np.maximum`` except on NaN. Where the
   reference's numbers come from one of numpy's own loops (exp, cos, power, cbrt, matmul),
   call that loop (:mod:`.ufuncs`, bound by symbol name: the caller stays cacheable).
4. Refuse what you do not implement: ``pack`` raises ``ParameterError`` naming the parameter
   (value) it does not support; ``Kernel.transforms`` lists the transforms you handle (rotation
   is refused by the dispatcher for every kernel). Never fall back silently.
5. Register with ``register_kernel(Kernel("NAME", run, pack))`` in your module and add the
   module to ``registry._MODULES``; ``tests/test_compiled.py`` then compares your kernel with
   the reference over its functions, dimensions, seeds, run ids and batch splits, and checks
   that every algorithm without a kernel refuses ``backend="numba"``.
6. ``cache=True`` on every @njit (workers compile once); loops over runs stay in Python. Keep
   compilation cheap: scalar loops over arrays rather than slice assignments or array methods
   (each numpy feature numba compiles costs seconds in a fresh process, numba's shape-error
   messages most), one signature per function (the same argument types at every call).
7. Speed: ``scripts/bench/kernels.py`` times the kernel against an independent fused loop of
   the algorithm (``scripts/bench/fused_*.py``), which must reach the same bests; add yours.
   A helper called in a loop that creates no array and returns none (it writes into arrays
   its caller made) is ``@njit(cache=True, **NO_REFCOUNT)`` (:mod:`.norefcount`: numba's
   ``_nrt=False``), not ``inline="always"``: numba
   counts references to every array a function holds, and an inlined helper binds each array
   argument to a new variable whose count it raises and lowers (an NRT_incref/NRT_decref call
   each, an atomic add, which numba's pruning pass leaves in place across the helper's
   branches); without reference counting its caller's arrays are simply borrowed for the call
   (numba refuses to compile such a helper if it allocates or returns an array). HPO, which
   evaluates and moves one agent at a time, spent a fifth of its run in those calls (perf).
8. Budgets: a kernel whose evaluations per run vary (masked evaluations) counts a study's
   evaluation budget itself, as ``Optimizer.max_evaluations`` does: ``Kernel(capped=True)``,
   ``pack`` ends with a -1.0 slot the dispatcher fills, and every evaluation narrows its mask
   with :func:`best.within_budget` (rows in order) before ``evaluate``. A kernel with a fixed
   count needs nothing: it runs a budget only where the count fits it (``run.check_budget``).
"""

import hashlib
import os
from pathlib import Path

from numba.core import config as _numba_config

_PACKAGE = Path(__file__).resolve().parent


def compiled_sources(package: Path = _PACKAGE) -> list[Path]:
    """The files numba's kernels are compiled from (or take constants from): the whole of
    ``swarmpath.optimizers`` and ``swarmpath.functions``, the planners' ``compiled*.py`` and
    ``world/*_compiled*.py`` (the planners' aim calls the shortest path's kernels; the clearance
    grid's kernels check every path), sorted
    within each group. Every module with an ``@njit(cache=True)`` kernel must be one of them
    (``tests/test_compiled_cache.py`` checks it)."""
    root = package.parent.parent  # services/swarmpath (or a copy of it)
    groups = (
        sorted((root / "optimizers").rglob("*.py")),
        sorted((root / "functions").rglob("*.py")),
        sorted((root / "planners").glob("compiled*.py")),
        sorted((root / "world").glob("*_compiled*.py")),
    )
    return [path for group in groups for path in group]


def versioned_cache_dir(package: Path = _PACKAGE) -> str:
    """Where numba caches the kernels: a directory named by a hash of
    :func:`compiled_sources` (names and contents), under ``NUMBA_CACHE_DIR`` if set, else this
    package's ``__pycache__``.

    numba keys a cached function on its own file only: a kernel that inlines ``evaluate`` (or a
    constant such as ``trig.COS``) from another module kept running the old code after that
    module changed (a cached ``run`` of a.py calling b.helper returned the old helper's value
    after b.py was edited). With the directory keyed by every source, any change compiles
    afresh; a worker never runs stale kernels after an update.

    numba picks a kernel's cache directory when the ``@njit`` decorator runs, from the
    ``CACHE_DIR`` set at that moment: every module defining cached kernels outside this package
    therefore imports ``swarmpath.optimizers.compiled`` before its first ``@njit`` (else, when
    imported first, its kernels are cached next to it, keyed on its own file only).
    """
    digest = hashlib.sha256()
    root = package.parent.parent
    for path in compiled_sources(package):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    base = os.environ.get("NUMBA_CACHE_DIR") or str(package / "__pycache__")
    return os.path.join(base, f"swarmpath-{digest.hexdigest()[:16]}")


_numba_config.CACHE_DIR = versioned_cache_dir()  # type: ignore[attr-defined]

from swarmpath.optimizers.compiled.registry import (  # noqa: E402 - after the cache dir is set
    Kernel,
    find_kernel,
    kernel_names,
    register_kernel,
)

__all__ = ["Kernel", "find_kernel", "kernel_names", "register_kernel"]
