"""Stacking: the benchmark leases of a group that differ only in their function run as one
``minimize_many`` batch, so that leases of a few runs each share one of ``minimize``'s chunks
instead of each being a small batch of its own (docs/benchmarks.md, Stacking).

A group (the leases of one LeaseBundle) is cut into *stacks*: leases of one job whose cell specs
are equal but for ``function`` (same algorithm, dim, agents, iterations, params, transform,
backend and, whatever fields a spec gains, those too) go into one stack, in the group's order, as
long as the stack's population stays within ``STACK_ELEMENTS`` coordinates, one chunk of
``minimize``: the stacks run one after the other, each a single optimizer whose arrays stay in
the CPU caches for all its iterations (measured faster than one large stack whose chunks are
stepped in turn). Any other lease, and a lease larger than a chunk, is a stack of its own and
runs as before (:func:`~.execution.execute_lease`).

Each lease keeps everything it has alone: its runs give the numbers of
``minimize(algorithm, function, ..., run_ids=lease.runs)`` (``minimize_many`` guarantees it),
its results carry its own proof, its cancellation flag is its own. A stack stops as soon as
every lease in it is cancelled (checked every iteration); a lease cancelled while the others go
on is reported as cancelled when the stack ends, and its results are never sent. A stack whose
batch raises is run again lease by lease, so a failure is charged to the lease that causes it.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from swarmpath.service.protocol import BenchmarkCell, Lease
from swarmpath.service.worker.execution import (
    Cancelled,
    execute_lease,
    iteration_hook,
    minimize_options,
    ok_results,
)
from swarmpath.service.worker.packing import fit_result

log = logging.getLogger("swarmpath.worker")

#: Coordinates per population of one stack: ``swarmpath.optimizers.api.CHUNK_ELEMENTS`` (not
#: imported: the worker process itself never loads the optimizers).
STACK_ELEMENTS = 100_000

#: What a stack gives for each of its leases: the encoded results ``(run, bytes)`` in run
#: order, or the :class:`Cancelled` of a lease that was cancelled.
Outcome = list[tuple[int, bytes]] | Cancelled


def stack_key(lease: Lease) -> str | None:
    """Leases with equal keys may run in one batch; None for a lease that runs alone (a map
    lease)."""
    spec = lease.spec
    if not isinstance(spec, BenchmarkCell):
        return None
    fixed = spec.model_dump(mode="json", exclude={"function"})
    return json.dumps([lease.job_id, lease.seed, fixed], sort_keys=True)


def _elements(lease: Lease) -> int:
    spec = lease.spec
    assert isinstance(spec, BenchmarkCell)
    return len(lease.runs) * spec.agents * spec.dim


def plan_stacks(leases: Sequence[Lease], limit: int | None = None) -> list[list[int]]:
    """Indices into ``leases``, cut into stacks (see the module docstring), each in the group's
    order; the stacks are ordered by their first lease. ``limit``: coordinates per stack
    (default ``STACK_ELEMENTS``, read at each call)."""
    limit = STACK_ELEMENTS if limit is None else limit
    stacks: list[list[int]] = []
    open_stack: dict[str, tuple[list[int], int]] = {}  # key -> (stack, coordinates so far)
    for i, lease in enumerate(leases):
        key = stack_key(lease)
        if key is None or _elements(lease) > limit:
            stacks.append([i])
            continue
        current = open_stack.get(key)
        if current is not None and current[1] + _elements(lease) <= limit:
            current[0].append(i)
            open_stack[key] = (current[0], current[1] + _elements(lease))
            continue
        stack = [i]
        stacks.append(stack)
        open_stack[key] = (stack, _elements(lease))
    return stacks


def execute_stack(
    leases: Sequence[Lease],
    cancelled: Sequence[Callable[[], bool]],
    progress: Callable[[int], None] | None = None,
) -> list[Outcome]:
    """Run a stack (see :func:`plan_stacks`): one outcome per lease, in order. ``cancelled[i]``
    tells whether lease i was cancelled; ``progress(n)``: iterations done by the stack."""
    if len(leases) == 1:
        return [_alone(leases[0], cancelled[0], progress)]
    from swarmpath.optimizers import minimize_many

    first = leases[0]
    spec = first.spec
    assert isinstance(spec, BenchmarkCell)
    hook = iteration_hook(progress, lambda: all(flag() for flag in cancelled), first.lease_id)

    if all(flag() for flag in cancelled):
        return [Cancelled(lease.lease_id) for lease in leases]
    try:
        results = minimize_many(
            spec.algorithm, [_function(lease) for lease in leases], on_iteration=hook,
            function_runs=[lease.runs for lease in leases], **minimize_options(first, spec),
        )
    except Cancelled:
        return [Cancelled(lease.lease_id) for lease in leases]
    except Exception as exc:
        log.warning("a stack of %d leases (%s ...) failed (%s): running them one by one",
                    len(leases), first.cell, " ".join(str(exc).split())[:200])
        return [_alone(lease, flag, progress) for lease, flag in zip(leases, cancelled,
                                                                     strict=True)]
    out: list[Outcome] = []
    for lease, flag, res in zip(leases, cancelled, results, strict=True):
        if flag():
            out.append(Cancelled(lease.lease_id))
            continue
        out.append([(r.run, fit_result(r, capability=lease.capability))
                    for r in ok_results(lease, res)])
    return out


def _function(lease: Lease) -> str:
    assert isinstance(lease.spec, BenchmarkCell)
    return lease.spec.function


def _alone(
    lease: Lease, cancelled: Callable[[], bool], progress: Callable[[int], None] | None
) -> Outcome:
    try:
        return execute_lease(lease, cancelled, progress)
    except Cancelled as exc:
        return exc


def stacked_outcomes(
    leases: Sequence[Lease],
    cancelled: Sequence[Callable[[], bool]],
    on_stack: Callable[[list[int]], None] | None = None,
    progress: Callable[[int], None] | None = None,
    stacking: bool = True,
) -> Iterator[tuple[int, Any]]:
    """Run a whole group stack by stack, yielding ``(index, outcome)`` for the leases of each
    stack as it ends (an exception other than Cancelled is that lease's outcome).
    ``on_stack(indices)`` is called before each stack starts. ``stacking=False``: every lease
    alone (``swarmpath worker --no-stacking``, to measure what stacking saves)."""
    stacks = plan_stacks(leases) if stacking else [[i] for i in range(len(leases))]
    for stack in stacks:
        if on_stack is not None:
            on_stack(stack)
        try:
            outcomes: list[Any] = execute_stack(
                [leases[i] for i in stack], [cancelled[i] for i in stack], progress)
        except Exception as exc:  # pragma: no cover - execute_lease reports run failures
            outcomes = [exc] * len(stack)
        yield from zip(stack, outcomes, strict=True)
