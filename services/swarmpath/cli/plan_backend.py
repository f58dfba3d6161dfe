"""``swarmpath plan --backend numpy|numba``: the ``backend`` parameter of every selected planner
that has one (the swarm planners; RFO and OMPL have none and are left as they are); and the
compiled kernels every map run calls, made ready before the runs (:func:`compile_first`).

A planner's ``backend`` given in ``--params`` too must be the same value: two different values
are refused (exit 2, naming both) rather than one silently overriding the other.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from swarmpath.cli.core import InputError
from swarmpath.optimizers.api import COMPUTING_BACKENDS as BACKENDS  # a planner's (re-exported)


def _numba_missing() -> str | None:
    try:
        import numba  # noqa: F401
    except ImportError as exc:
        return str(exc)
    return None


def apply_backend(backend: str | None, planners: Sequence[str],
                  params: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """``params`` (per planner, as ``--params`` gave them) with ``backend`` set for every planner
    of ``planners`` that has the parameter; unchanged when ``backend`` is None. Raises
    :class:`InputError` naming ``--backend``: a value not in :data:`BACKENDS`, numba not
    installed, no selected planner with a backend, or a different ``backend`` in ``--params``."""
    from swarmpath.planners import get_planner

    if backend is None:
        return params
    if backend not in BACKENDS:
        raise InputError("--backend", f"{backend!r} is not one of {', '.join(BACKENDS)}")
    with_backend = [name for name in planners if "backend" in get_planner(name).defaults]
    if not with_backend:
        raise InputError("--backend", f"none of --planners ({', '.join(planners)}) has a "
                         "backend parameter")
    if backend == "numba":
        missing = _numba_missing()
        if missing is not None:
            raise InputError("--backend", "numba needs numba installed (pip install "
                             f"'swarmpath[fast]'): {missing}")
    out = {name: dict(values) for name, values in params.items()}
    for name in with_backend:
        given = out.get(name, {}).get("backend")
        if given is not None and given != backend:
            raise InputError("--backend", f"{backend} conflicts with --params {name}.backend = "
                             f"{given!r} (give one of them)")
        out.setdefault(name, {})["backend"] = backend
    return out


def compile_first(note: Callable[[str], None]) -> None:
    """The world's clearance and sensing kernels, which every map run calls (backend auto:
    where numba is installed), when this tree's numba cache lacks them: asked for in the
    background once, here, before the runs go to worker processes, which run the numpy
    reference (the same numbers) until the kernels are ready
    (:func:`swarmpath.optimizers.compiled.warm.request_cold`). ``note`` gets one line when
    they are missing. A planner's own ``backend: numba`` compiles its decision in its runs."""
    from swarmpath.world.clearance import compiled_available

    if compiled_available():
        from swarmpath.optimizers.compiled.warm import request_cold

        request_cold([], [], True, note)
