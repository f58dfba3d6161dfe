"""The conformance properties that need other processes: the same runs computed in spawned
``-j 2`` children (:mod:`swarmpath.parallel`, as ``swarmpath bench -j 2`` computes) and in a
worker's slot process (:class:`~swarmpath.service.worker.slots.ProcessSlot`, as a farm worker
computes), compared with this process's numbers bit for bit.

The processes find a plugin the way swarmpath's own do: through ``SWARMPATH_PLUGINS`` (set here
for the duration to the plugin's file or module) or its entry points.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from swarmpath.plugins.loading import ENV, loaded, module_name_for, split

SLOT_SECONDS = 300.0  # a slot that did not answer by then fails the property


def plugin_spec(module: str) -> str | None:
    """What a child process loads to get code defined in ``module``: its file when it was
    loaded as a plugin file, else the module's name (None: swarmpath's own)."""
    if module == "swarmpath" or module.startswith("swarmpath."):
        return None
    for spec in loaded():
        if module == module_name_for(Path(spec)):
            return spec
    return module


@contextlib.contextmanager
def plugin_environment(specs: Sequence[str | None]) -> Iterator[None]:
    """``SWARMPATH_PLUGINS`` including ``specs`` while the block runs (the processes it starts
    inherit it)."""
    saved = os.environ.get(ENV)
    current = split(saved or "")
    extra = [s for s in dict.fromkeys(specs) if s is not None and s not in current]
    if extra:
        os.environ[ENV] = os.pathsep.join([*current, *extra])
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop(ENV, None)
        else:
            os.environ[ENV] = saved


Job = tuple[str, dict[str, Any]]  # (algorithm, minimize's settings without the runs)


def _piece(task: Job, report: Any) -> dict[str, Any]:
    """One ``minimize`` in a child (module level: the child imports it)."""
    from swarmpath.optimizers import minimize

    algorithm, kwargs = task
    res = minimize(algorithm, **kwargs)
    return {"curve": res.curve, "best_position": res.best_position,
            "evaluations": res.evaluations}


def in_children(jobs: Sequence[Job], pieces: Sequence[list[int]],
                specs: Sequence[str | None]) -> list[dict[str, np.ndarray] | Exception]:
    """Per job, its runs of ``pieces`` (one list of run ids per task) computed by ``-j 2``
    children, stacked in the order of the pieces (or the exception its tasks raised)."""
    from swarmpath.parallel import run_tasks

    tasks = [(a, {**kw, "run_ids": list(ids)}) for a, kw in jobs for ids in pieces]
    out: list[dict[str, np.ndarray] | Exception] = []
    with plugin_environment(specs):
        try:
            parts = run_tasks(_piece, tasks, jobs=2)
        except Exception as exc:  # one failing job: compute each alone to tell which
            if len(jobs) == 1:
                return [exc]
            return [in_children([job], pieces, specs)[0] for job in jobs]
    for j in range(len(jobs)):
        mine = parts[j * len(pieces):(j + 1) * len(pieces)]
        out.append({key: np.concatenate([p[key] for p in mine]) for key in mine[0]})
    return out


def in_worker_slot(jobs: Sequence[Job], runs: list[int],
                   specs: Sequence[str | None]) -> list[dict[str, np.ndarray] | Exception]:
    """Per job, its runs computed by one worker slot process from a lease of its own, as a
    farm worker computes them (or why that failed)."""
    from swarmpath.service.capability import new_capability
    from swarmpath.service.protocol import BenchmarkCell, Lease
    from swarmpath.service.worker.slots import ProcessSlot

    leases = []
    for i, (algorithm, kw) in enumerate(jobs):
        cell = BenchmarkCell(algorithm=algorithm, function=kw["function"], dim=kw["dim"],
                             agents=kw["agents"], iterations=kw["iterations"],
                             params=kw.get("params") or {}, transform=kw.get("transform", "none"))
        leases.append(Lease(
            lease_id=f"conformance-{i}", worker="conformance", job_id="conformance",
            cell=cell.key, cell_index=i, runs_per_cell=max(runs) + 1, seed=kw["seed"],
            runs=runs, spec=cell, deadline=time.time() + 3600, lease_seconds=3600.0,
            heartbeat_seconds=60.0, capability=new_capability()))
    finished = threading.Event()
    outcomes: list[Any] = []

    def on_done(_slot: Any, got: list[Any]) -> None:
        outcomes[:] = got
        finished.set()

    with plugin_environment(specs):
        slot = ProcessSlot(0, on_done, stacking=False)
        slot.start()
    out: list[dict[str, np.ndarray] | Exception] = []
    try:
        for lease in leases:
            finished.clear()
            slot.submit([lease])
            if not finished.wait(SLOT_SECONDS):
                raise TimeoutError(f"the slot gave no result in {SLOT_SECONDS:.0f} s")
            out.append(_slot_runs(outcomes[0][1], runs))
    finally:
        slot.close()
    return out


def _slot_runs(outcome: Any, runs: list[int]) -> dict[str, np.ndarray] | Exception:
    from swarmpath.service.result_frame import decode_record

    if isinstance(outcome, BaseException):
        return RuntimeError(f"the slot failed: {outcome}")
    records = [decode_record(payload) for _, payload in outcome]
    failed = [r.head for r in records if r.head.status != "ok"]
    if failed:
        last = (failed[0].failure or "").strip().splitlines()
        return RuntimeError(f"run {failed[0].run} failed in the slot: {last[-1] if last else ''}")
    by_run = {r.head.run: r for r in records}
    return {
        "curve": np.array([by_run[r].arrays["curve"] for r in runs]),
        "best_position": np.array([by_run[r].arrays["best_position"] for r in runs]),
        "evaluations": np.array([int(by_run[r].head.metrics["evaluations"]) for r in runs]),
    }
