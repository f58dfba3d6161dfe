"""The work itself, plain functions: a benchmark lease is one vectorized
``minimize(..., run_ids=lease.runs)`` (split into memory-bounded batches, as ``swarmpath bench``
does; runs are independent so the numbers are the same), a map lease one
``Episode(scenario, planner, seed, run, params)`` per run. Each result carries its wall seconds
and CPU seconds (this thread's, ``time.thread_time``, as ``minimize`` and a map run's outcome
measure it; a slot runs BLAS single-threaded). A run that raises is a ``failed`` result
(not retried); cancellation is checked every iteration/step. Slots run the benchmark leases of a
bundle that differ only in their function as one batch (:mod:`.stacking`), with the same numbers
and the same per-lease results as here."""

from __future__ import annotations

import logging
import time
import traceback
from collections.abc import Callable, Sequence
from typing import Any

from swarmpath.service.cell_notes import note_metrics, scenario_warnings
from swarmpath.service.protocol import (
    BenchmarkCell,
    Lease,
    MapCell,
    RunResult,
)
from swarmpath.service.worker.packing import _scalar, fit_result

log = logging.getLogger("swarmpath.worker")


#: Runs of a benchmark lease are computed in batches of at most this many array elements per
#: population (runs x agents x dim), like ``swarmpath bench``.
BATCH_ELEMENTS = 1 << 22


class Cancelled(Exception):
    """The lease was dropped or cancelled while it ran."""


def _never() -> bool:
    return False


def iteration_hook(
    progress: Callable[[int], None] | None, cancelled: Callable[[], bool], lease_id: str
) -> Callable[[object], None]:
    """An ``on_iteration`` callback: reports the iterations done so far to ``progress`` and
    raises :class:`Cancelled` (naming ``lease_id``) once ``cancelled()`` is true."""
    done = 0

    def hook(_optimizer: object) -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done)
        if cancelled():
            raise Cancelled(lease_id)

    return hook


def execute_lease(
    lease: Lease,
    cancelled: Callable[[], bool] = _never,
    progress: Callable[[int], None] | None = None,
) -> list[tuple[int, bytes]]:
    """Run every run of ``lease``; returns ``(run, encoded RunResult)`` in run order.

    Raises :class:`Cancelled` when ``cancelled()`` turns true. ``progress(n)`` is called with the
    number of iterations (benchmark) or planner steps (map) done so far in the lease."""
    from swarmpath.service.worker.extensions import check_pins

    check_pins(lease.pins, lease.cell)  # ExtensionUnavailable: reported as such, never failed
    if isinstance(lease.spec, BenchmarkCell):
        results = _benchmark(lease, lease.spec, cancelled, progress)
    else:
        results = _map(lease, lease.spec, cancelled, progress)
    return [(r.run, fit_result(r, capability=lease.capability)) for r in results]


def _result(lease: Lease, run: int, seconds: float, cpu_seconds: float | None = None,
            **fields: Any) -> RunResult:
    return RunResult(
        lease_id=lease.lease_id, job_id=lease.job_id, cell=lease.cell, run=run,
        worker=lease.worker, seconds=max(0.0, seconds),
        cpu_seconds=None if cpu_seconds is None else max(0.0, cpu_seconds), **fields,
    )


def failed_lease(lease: Lease, failure: str) -> list[tuple[int, bytes]]:
    """Every run of ``lease`` as a ``failed`` result with ``failure`` as the reason (a lease that
    cannot start, e.g. its scenario could not be fetched)."""
    return [(r, fit_result(_result(lease, r, 0.0, status="failed", failure=failure[:20_000]),
                           capability=lease.capability)) for r in lease.runs]


def _failure_text(exc: BaseException) -> str:
    text = "".join(traceback.format_exception_only(type(exc), exc)).strip()
    return text[:20_000]


def benchmark_batches(runs: Sequence[int], agents: int, dim: int) -> list[list[int]]:
    """The lease's runs in memory-bounded batches (at most BATCH_ELEMENTS per population)."""
    size = max(1, BATCH_ELEMENTS // max(1, agents * dim))
    runs = list(runs)
    return [runs[i:i + size] for i in range(0, len(runs), size)]


def _benchmark(
    lease: Lease,
    spec: BenchmarkCell,
    cancelled: Callable[[], bool],
    progress: Callable[[int], None] | None,
) -> list[RunResult]:
    from swarmpath.optimizers import minimize

    out: list[RunResult] = []
    hook = iteration_hook(progress, cancelled, lease.lease_id)

    for batch in benchmark_batches(lease.runs, spec.agents, spec.dim):
        if cancelled():
            raise Cancelled(lease.lease_id)
        started, cpu_started = time.perf_counter(), time.thread_time()
        try:
            res = minimize(
                spec.algorithm, spec.function, run_ids=batch, on_iteration=hook,
                **minimize_options(lease, spec),
            )
        except Cancelled:
            raise
        except Exception as exc:
            seconds = (time.perf_counter() - started) / len(batch)
            cpu = (time.thread_time() - cpu_started) / len(batch)
            failure = _failure_text(exc)
            log.warning("lease %s: runs %s of %s failed: %s", lease.lease_id, batch, lease.cell,
                        failure.splitlines()[-1] if failure else "")
            out += [_result(lease, r, seconds, cpu, status="failed", failure=failure)
                    for r in batch]
            continue
        out += ok_results(lease, res)
    return out


#: What backend "auto" runs in this process: "auto" (the compiled kernels where the study has
#: them) once the process compiled them all before taking work (slots.warm_compiled), the numpy
#: reference until then. The numbers are the same either way; this way no lease waits for
#: numba's compiler (a kernel's first compilation costs 3-20 s of CPU).
AUTO = ["numpy"]


def minimize_options(lease: Lease, spec: BenchmarkCell) -> dict[str, Any]:
    """The arguments of ``minimize`` a benchmark lease fixes besides the function and runs (the
    same for a lease run alone and for a stack of leases, see :mod:`.stacking`)."""
    backend = AUTO[0] if spec.backend == "auto" else spec.backend
    return {"dim": spec.dim, "agents": spec.agents, "iterations": spec.iterations,
            "seed": lease.seed, "params": spec.params, "transform": spec.transform,
            "backend": backend, "max_evaluations": spec.max_evaluations}


def ok_results(lease: Lease, res: Any) -> list[RunResult]:
    """The results of ``res`` (a ``minimize`` Result of the lease's cell; its runs, in its
    order), each charged an equal share of its wall and CPU seconds."""
    share = res.seconds / len(res.run_ids)
    cpu = None if res.cpu_seconds is None else res.cpu_seconds / len(res.run_ids)
    return [
        _result(
            lease, r, share, cpu,
            metrics={"best_fitness": float(res.best_fitness[i]),
                     "evaluations": int(res.evaluations[i])},
            curve=res.curve[i].tolist(),  # float64 -> float, exact (and 20x faster
            best_position=res.best_position[i].tolist(),  # than a Python loop)
        )
        for i, r in enumerate(res.run_ids)
    ]


def load_scenario(spec: MapCell) -> Any:
    """The cell's scenario: the inline object, or the preset named ``spec.map``."""
    if spec.scenario_ref is not None:  # the worker puts it in place first (scenarios.resolve)
        raise ValueError(f"map {spec.map}: scenario {spec.scenario_ref.sha256[:16]}... was not "
                         "fetched")
    if spec.scenario is not None:
        from swarmpath.world.scenario_io import scenario_from_dict

        return scenario_from_dict(dict(spec.scenario))
    from swarmpath.world.presets import get_map

    return get_map(spec.map)


def _map(
    lease: Lease,
    spec: MapCell,
    cancelled: Callable[[], bool],
    progress: Callable[[int], None] | None,
) -> list[RunResult]:
    out: list[RunResult] = []
    steps = 0
    try:
        from swarmpath.planners import Episode
        from swarmpath.planners.episode import optimum_of
        from swarmpath.world.optimum import DEFAULT_BUDGET

        scenario = load_scenario(spec)
    except Exception as exc:
        failure = _failure_text(exc)
        return [_result(lease, r, 0.0, status="failed", failure=failure) for r in lease.runs]
    budget = DEFAULT_BUDGET if spec.optimum_budget is None else spec.optimum_budget
    warnings = scenario_warnings(scenario)  # once per scenario and process (cell_notes)
    for r in lease.runs:
        if cancelled():
            raise Cancelled(lease.lease_id)
        started, cpu_started = time.perf_counter(), time.thread_time()
        try:
            episode = Episode(scenario, spec.planner, lease.seed, r, spec.params,
                              optimum_budget=budget)
            while not episode.done:
                episode.step()
                steps += 1
                if progress is not None:
                    progress(steps)
                if cancelled():
                    raise Cancelled(lease.lease_id)
            outcome = episode.outcome()
        except Cancelled:
            raise
        except Exception as exc:
            out.append(_result(lease, r, time.perf_counter() - started,
                               time.thread_time() - cpu_started, status="failed",
                               failure=_failure_text(exc)))
            continue
        data = outcome.to_dict()
        path = data.pop("path", None) or []
        metrics = {k: v for k, v in data.items() if _scalar(v)}
        # why there is no optimum (remembered per scenario and budget: no second search)
        reason = optimum_of(scenario, budget)[1] if data.get("optimum") is None else None
        metrics.update(note_metrics(reason, warnings))
        out.append(_result(
            lease, r, time.perf_counter() - started, time.thread_time() - cpu_started,
            metrics=metrics,
            path=[(float(p[0]), float(p[1]), float(p[2])) for p in path],
        ))
    return out
