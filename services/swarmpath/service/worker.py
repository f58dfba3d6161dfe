"""The worker: a Zenoh client that pulls leases from the coordinator, runs them, reports results.

Layers, the lower ones usable without the upper ones:

* :func:`execute_lease` - the work itself, a plain function: a benchmark lease is one vectorized
  ``minimize(..., run_ids=lease.runs)`` (split into memory-bounded batches, as ``swarmpath bench``
  does; runs are independent so the numbers are the same), a map lease one
  ``Episode(scenario, planner, seed, run, params)`` per run. Returns the encoded RunResults; a run
  that raises is a ``failed`` result (not retried); cancellation is checked every iteration/step.
* Slots - where leases execute, ``--slots N`` of them: spawned child processes by default (never
  forked: the parent runs Zenoh), or threads (``executor="thread"``, for tests and debugging).
  A child ignores SIGINT (the parent decides), and exits by itself when its parent disappears.
* :class:`Worker` - the protocol (schemas/README.md): liveliness token, pull loop with backoff,
  heartbeats (RunProgress) for running leases, results put with CongestionControl.BLOCK and
  re-sent until acknowledged, ``drop_leases`` and ``Cancel`` honoured, graceful stop on
  SIGTERM/SIGINT: stop pulling, let running leases finish for ``grace_seconds`` (then abort them),
  wait for the acks, undeclare the token (the coordinator requeues whatever was not reported).
"""

from __future__ import annotations

import json
import logging
import os
import re
import signal
import socket
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from swarmpath.service.protocol import (
    DEFAULT_PREFIX,
    MAX_BODY_BYTES,
    MAX_BUNDLE_LEASES,
    PROTOCOL_VERSION,
    Ack,
    BenchmarkCell,
    Cancel,
    Keys,
    Lease,
    LeaseBundle,
    LeaseRequest,
    MapCell,
    NoWork,
    RunProgress,
    RunResult,
    decode,
    decode_work_reply,
    encode,
)
from swarmpath.service.zenoh_config import DEFAULT_ZENOH, client_config

log = logging.getLogger("swarmpath.worker")

#: Runs of a benchmark lease are computed in batches of at most this many array elements per
#: population (runs x agents x dim), like ``swarmpath bench``.
BATCH_ELEMENTS = 1 << 22
#: Result batches are cut to stay below this many bytes of JSON (the coordinator drops > 1 MB).
BATCH_BYTES = 512_000
#: A single result larger than this has its curve (and path) thinned to fit.
RESULT_BYTES = MAX_BODY_BYTES - 4096


class Cancelled(Exception):
    """The lease was dropped or cancelled while it ran."""


def _never() -> bool:
    return False


# ----------------------------------------------------------------------------------- executing
def execute_lease(
    lease: Lease,
    cancelled: Callable[[], bool] = _never,
    progress: Callable[[int], None] | None = None,
) -> list[tuple[int, bytes]]:
    """Run every run of ``lease``; returns ``(run, encoded RunResult)`` in run order.

    Raises :class:`Cancelled` when ``cancelled()`` turns true. ``progress(n)`` is called with the
    number of iterations (benchmark) or planner steps (map) done so far in the lease."""
    if isinstance(lease.spec, BenchmarkCell):
        results = _benchmark(lease, lease.spec, cancelled, progress)
    else:
        results = _map(lease, lease.spec, cancelled, progress)
    return [(r.run, fit_result(r)) for r in results]


def _result(lease: Lease, run: int, seconds: float, **fields: Any) -> RunResult:
    return RunResult(
        lease_id=lease.lease_id, job_id=lease.job_id, cell=lease.cell, run=run,
        worker=lease.worker, seconds=max(0.0, seconds), **fields,
    )


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
    done = 0

    def hook(_optimizer: object) -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done)
        if cancelled():
            raise Cancelled(lease.lease_id)

    for batch in benchmark_batches(lease.runs, spec.agents, spec.dim):
        if cancelled():
            raise Cancelled(lease.lease_id)
        started = time.perf_counter()
        try:
            res = minimize(
                spec.algorithm, spec.function, dim=spec.dim, agents=spec.agents,
                iterations=spec.iterations, seed=lease.seed, params=spec.params,
                shifted=spec.shifted, run_ids=batch, on_iteration=hook,
            )
        except Cancelled:
            raise
        except Exception as exc:
            seconds = (time.perf_counter() - started) / len(batch)
            failure = _failure_text(exc)
            log.warning("lease %s: runs %s of %s failed: %s", lease.lease_id, batch, lease.cell,
                        failure.splitlines()[-1] if failure else "")
            out += [_result(lease, r, seconds, status="failed", failure=failure) for r in batch]
            continue
        share = res.seconds / len(batch)
        for i, r in enumerate(batch):
            out.append(_result(
                lease, r, share,
                metrics={"best_fitness": float(res.best_fitness[i]),
                         "evaluations": int(res.evaluations[i])},
                curve=res.curve[i].tolist(),  # float64 -> float, exact (and 20x faster
                best_position=res.best_position[i].tolist(),  # than a Python loop)
            ))
    return out


def load_scenario(spec: MapCell) -> Any:
    """The cell's scenario: the inline object, or the preset named ``spec.map``."""
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

        scenario = load_scenario(spec)
    except Exception as exc:
        failure = _failure_text(exc)
        return [_result(lease, r, 0.0, status="failed", failure=failure) for r in lease.runs]
    for r in lease.runs:
        if cancelled():
            raise Cancelled(lease.lease_id)
        started = time.perf_counter()
        try:
            episode = Episode(scenario, spec.planner, lease.seed, r, spec.params)
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
            out.append(_result(lease, r, time.perf_counter() - started, status="failed",
                               failure=_failure_text(exc)))
            continue
        data = outcome.to_dict()
        path = data.pop("path", None) or []
        metrics = {k: v for k, v in data.items() if _scalar(v)}
        out.append(_result(
            lease, r, time.perf_counter() - started, metrics=metrics,
            path=[(float(p[0]), float(p[1]), float(p[2])) for p in path],
        ))
    return out


def _scalar(v: Any) -> bool:
    return v is None or isinstance(v, bool | int | float | str)


def fit_result(result: RunResult, limit: int = RESULT_BYTES) -> bytes:
    """The encoded result, its curve (and path) thinned to evenly spaced samples, first and last
    kept, when it would not fit in one message (``metrics.curve_stride`` records the stride)."""
    data = encode(result)
    stride = 1
    while len(data) > limit and stride < 1 << 20:
        stride *= 2
        changes: dict[str, Any] = {}
        if result.curve:
            changes["curve"] = _thin(result.curve, stride)
            changes["metrics"] = {**result.metrics, "curve_stride": stride}
        if result.path and len(result.path) > 2:
            changes["path"] = _thin(result.path, stride)
        if not changes:
            break
        data = encode(result.model_copy(update=changes))
    return data


def _thin(values: Sequence[Any], stride: int) -> list[Any]:
    out = list(values[::stride])
    if (len(values) - 1) % stride:
        out.append(values[-1])
    return out


def pack_batches(worker: str, results: Sequence[bytes], limit: int = BATCH_BYTES) -> list[bytes]:
    """ResultBatch payloads from encoded results, each at most ``limit`` bytes when possible."""
    head = b'{"worker":' + json.dumps(worker).encode() + b',"results":['
    out: list[bytes] = []
    chunk: list[bytes] = []
    size = len(head) + 2
    for r in results:
        if chunk and size + len(r) + 1 > limit:
            out.append(head + b",".join(chunk) + b"]}")
            chunk, size = [], len(head) + 2
        chunk.append(r)
        size += len(r) + 1
    if chunk:
        out.append(head + b",".join(chunk) + b"]}")
    return out


# -------------------------------------------------------------------------------------- slots
class NotRun(Exception):
    """A lease of a group that never started (its slot process died before): run it again."""


#: What a slot reports for each lease of a group: ``(lease, outcome)`` with outcome the list of
#: ``(run, encoded RunResult)``, or a :class:`Cancelled`, :class:`NotRun` or other exception.
Outcomes = list[tuple[Lease, Any]]


class Slot:
    """Executes one group of leases at a time, one lease after the other (a group is the leases
    of one LeaseBundle, or a single lease); ``on_done(slot, outcomes)`` is called once per group
    from a thread of the slot. Each lease of a group can be cancelled on its own."""

    def __init__(self, index: int, on_done: Callable[[Slot, Outcomes], None]):
        self.index = index
        self.on_done = on_done
        self.leases: list[Lease] = []

    @property
    def busy(self) -> bool:
        return bool(self.leases)

    @property
    def ready(self) -> bool:
        """Started and able to take a group (a process slot: after its warm-up)."""
        return True

    def start(self) -> None: ...
    def submit(self, leases: Sequence[Lease]) -> None: ...
    def cancel(self, lease_id: str | None = None) -> None: ...
    def iteration(self, lease_id: str | None = None) -> int:
        return 0

    def close(self, timeout: float = 5.0) -> None: ...

    def _position(self, lease_id: str | None) -> list[int]:
        return [i for i, lease in enumerate(self.leases)
                if lease_id is None or lease.lease_id == lease_id]


class ThreadSlot(Slot):
    """Leases run in a thread of the worker process (shares the GIL: for tests and debugging)."""

    def __init__(self, index: int, on_done: Callable[[Slot, Outcomes], None]):
        super().__init__(index, on_done)
        self._cancel: list[threading.Event] = []
        self._current = -1
        self._done = 0
        self._thread: threading.Thread | None = None

    def submit(self, leases: Sequence[Lease]) -> None:
        group = list(leases)
        self._cancel = [threading.Event() for _ in group]
        self._current, self._done = -1, 0
        self.leases = group
        self._thread = threading.Thread(
            target=self._run, args=(group, self._cancel), name=f"slot-{self.index}", daemon=True)
        self._thread.start()

    def _run(self, group: list[Lease], flags: list[threading.Event]) -> None:
        def progress(n: int) -> None:
            self._done = n

        outcomes: Outcomes = []
        for i, lease in enumerate(group):
            self._current, self._done = i, 0
            try:
                outcome: Any = execute_lease(lease, flags[i].is_set, progress)
            except Cancelled as exc:
                outcome = exc
            except Exception as exc:  # pragma: no cover - execute_lease reports run failures
                outcome = exc
            outcomes.append((lease, outcome))
        self.leases = []
        self.on_done(self, outcomes)

    def cancel(self, lease_id: str | None = None) -> None:
        for i in self._position(lease_id):
            self._cancel[i].set()

    def iteration(self, lease_id: str | None = None) -> int:
        current = self._current
        if 0 <= current < len(self.leases) and (
                lease_id is None or self.leases[current].lease_id == lease_id):
            return self._done
        return 0

    def close(self, timeout: float = 5.0) -> None:
        for flag in self._cancel:
            flag.set()
        if self._thread is not None:
            self._thread.join(timeout)


def warm_up() -> None:
    """One tiny run, so that the first lease does not pay for lazy imports and first-use setup
    (tens of milliseconds; a whole lease of tiny runs costs less)."""
    spec = BenchmarkCell(algorithm="PSO", function="F1", dim=2, agents=5, iterations=1)
    lease = Lease(lease_id="warm-up", worker="warm-up", job_id="warm-up", cell=spec.key,
                  cell_index=0, runs_per_cell=1, seed=0, runs=[0], spec=spec, deadline=0.0,
                  lease_seconds=1.0, heartbeat_seconds=1.0)
    try:
        execute_lease(lease)
    except Exception:  # pragma: no cover - a broken core shows up in the first real lease
        log.debug("warm-up run failed", exc_info=True)


def _slot_main(conn: Any, cancel: Any, done: Any, current: Any, parent: int) -> None:
    """A slot's child process: groups of leases in, one reply per lease out, until told to stop
    or orphaned."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's business

    def orphan_watch() -> None:
        while True:
            time.sleep(0.5)
            if os.getppid() != parent:
                os._exit(3)

    threading.Thread(target=orphan_watch, daemon=True).start()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s slot %(message)s")
    # One slot is one core: no BLAS/OpenMP thread pools fighting the other slots and workers
    # (numpy is not imported yet in this fresh process; an explicit setting wins).
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    import swarmpath.optimizers  # noqa: F401  (pay the import before the first lease)

    def progress(n: int) -> None:
        done.value = n

    warm_up()
    try:
        conn.send(("ready", -1))  # the worker pulls work for this slot only from now on
    except (EOFError, OSError):
        return

    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        try:
            bundle = decode_work_reply(message)
            assert isinstance(bundle, LeaseBundle)
        except Exception as exc:  # pragma: no cover - the parent encoded it
            conn.send(("error", -1, _failure_text(exc)))
            continue
        for i, lease in enumerate(bundle.leases):
            current.value, done.value = i, 0
            try:
                reply: tuple[Any, ...] = (
                    "done", i, execute_lease(lease, lambda i=i: bool(cancel[i]), progress))
            except Cancelled:
                reply = ("cancelled", i)
            except Exception as exc:  # reported to the parent
                reply = ("error", i, _failure_text(exc))
            try:
                conn.send(reply)
            except (EOFError, OSError):
                return
        current.value = -1


class ProcessSlot(Slot):
    """Leases run in a spawned child process (true parallelism; killed and respawned if it
    dies). The child is started with the multiprocessing *spawn* method, never forked."""

    def __init__(self, index: int, on_done: Callable[[Slot, Outcomes], None]):
        super().__init__(index, on_done)
        import multiprocessing

        self._ctx = multiprocessing.get_context("spawn")
        self._cancel = self._ctx.Array("b", MAX_BUNDLE_LEASES, lock=False)
        self._done = self._ctx.Value("q", 0, lock=False)
        self._current = self._ctx.Value("i", -1, lock=False)
        self._proc: Any = None
        self._conn: Any = None
        self._waiter: threading.Thread | None = None
        self._closing = False
        self._ready = threading.Event()
        self.on_ready: Callable[[], None] | None = None

    @property
    def busy(self) -> bool:
        """Running a group, or not ready yet (starting): no work is pulled for it then."""
        return bool(self.leases) or not self._ready.is_set()

    @property
    def ready(self) -> bool:
        return self._ready.is_set()

    def _await_ready(self) -> bool:
        try:
            reply = self._conn.recv()
        except (EOFError, OSError):
            return False
        if reply[0] != "ready":  # pragma: no cover - the child says ready first
            return False
        self._ready.set()
        if self.on_ready is not None:
            self.on_ready()
        return True

    def start(self) -> None:
        self._ready.clear()
        parent_conn, child_conn = self._ctx.Pipe()
        self._proc = self._ctx.Process(
            target=_slot_main,
            args=(child_conn, self._cancel, self._done, self._current, os.getpid()),
            name=f"swarmpath-slot-{self.index}", daemon=True,
        )
        self._proc.start()
        child_conn.close()
        self._conn = parent_conn
        threading.Thread(target=self._await_ready, name=f"slot-{self.index}-start",
                         daemon=True).start()

    def submit(self, leases: Sequence[Lease]) -> None:
        if self._proc is None or not self._proc.is_alive():
            self.start()  # the group waits in the pipe until the new child is ready
        group = list(leases)[:MAX_BUNDLE_LEASES]
        for i in range(MAX_BUNDLE_LEASES):
            self._cancel[i] = 0
        self._done.value, self._current.value = 0, -1
        self.leases = group
        self._conn.send(encode(LeaseBundle(leases=group)))
        self._waiter = threading.Thread(
            target=self._wait, args=(group,), name=f"slot-{self.index}", daemon=True)
        self._waiter.start()

    def _wait(self, group: list[Lease]) -> None:
        got: dict[int, Any] = {}
        while len(got) < len(group):
            try:
                if not self._ready.wait(0.05):  # a respawned child: its ready comes first
                    if self._proc is not None and self._proc.is_alive():
                        continue
                    raise EOFError
                reply = self._conn.recv()
            except (EOFError, OSError):
                code = self._proc.exitcode if self._proc is not None else None
                if self._proc is not None:
                    self._proc.join(1.0)
                    code = self._proc.exitcode
                self._proc = None
                # the lease that was running fails (a run that kills its process would kill
                # every worker it is given to); the ones not started yet are run again
                died = RuntimeError(f"the slot process died (exit code {code})")
                running = min((i for i in range(len(group)) if i not in got), default=0)
                for i in range(len(group)):
                    if i not in got:
                        got[i] = died if i == running else NotRun(group[i].lease_id)
                break
            kind, i = reply[0], reply[1]
            if i < 0:  # the group could not be read at all
                for j in range(len(group)):
                    got.setdefault(j, RuntimeError(reply[2]))
                break
            got[i] = (reply[2] if kind == "done" else
                      Cancelled(group[i].lease_id) if kind == "cancelled" else
                      RuntimeError(reply[2]))
        self.leases = []
        if not self._closing:
            self.on_done(self, [(lease, got[i]) for i, lease in enumerate(group)])

    def cancel(self, lease_id: str | None = None) -> None:
        for i in self._position(lease_id):
            self._cancel[i] = 1

    def iteration(self, lease_id: str | None = None) -> int:
        current, leases = int(self._current.value), self.leases
        if 0 <= current < len(leases) and (
                lease_id is None or leases[current].lease_id == lease_id):
            return int(self._done.value)
        return 0

    def close(self, timeout: float = 5.0) -> None:
        self._closing = True
        for i in range(MAX_BUNDLE_LEASES):
            self._cancel[i] = 1
        if self._conn is not None:
            try:
                self._conn.send(None)
            except (OSError, ValueError):
                pass
        if self._proc is not None:
            self._proc.join(timeout)
            if self._proc.is_alive():
                self._proc.terminate()
                self._proc.join(2.0)
        if self._conn is not None:
            self._conn.close()


# ------------------------------------------------------------------------------------- worker
def default_worker_id() -> str:
    host = re.sub(r"[^A-Za-z0-9_.-]", "-", socket.gethostname()).strip("-._") or "host"
    return f"{host[:100]}-{os.getpid()}"


@dataclass
class WorkerSettings:
    connect: list[str] = field(default_factory=lambda: [DEFAULT_ZENOH])
    prefix: str = DEFAULT_PREFIX
    slots: int = 1
    worker_id: str | None = None
    max_runs: int = 1000  # per lease request; the coordinator sizes leases below this
    max_leases: int = 32  # per lease request: small leases come as bundles of up to this many
    prefetch: int = 1  # bundles held beyond the slots: the next one is at hand when a slot frees
    executor: Literal["process", "thread"] = "process"
    user: str | None = None
    password: str | None = None
    shm: bool = False
    zenoh_extra: dict[str, Any] | None = None
    query_timeout: float = 10.0  # waiting for a lease reply
    ack_timeout: float = 5.0  # results not settled within this are put again (with backoff)
    max_backoff: float = 5.0  # coordinator absent: retry pulls at most this far apart
    grace_seconds: float = 10.0  # on stop: running leases get this long to finish
    exit_with_parent: int | None = None  # stop when this process is no longer our parent

    def zenoh_config(self) -> dict[str, Any]:
        return client_config(self.connect, shm=self.shm, user=self.user, password=self.password,
                             extra=self.zenoh_extra)


@dataclass
class _Active:
    lease: Lease
    slot: Slot | None  # None while the lease waits in the queue
    received: float
    last_progress: float


@dataclass
class _Pending:
    job_id: str
    lease_id: str
    data: bytes
    sent: float = 0.0
    seq: int = 0  # of the put that last carried it
    attempts: int = 0


class Worker:
    """See the module docstring. ``run()`` blocks until ``stop()`` (or a signal)."""

    def __init__(self, settings: WorkerSettings):
        self.settings = settings
        self.id = settings.worker_id or default_worker_id()
        Keys(settings.prefix).worker_token(self.id)  # validates the id
        self.keys = Keys(settings.prefix)
        self.host = socket.gethostname()
        self._lock = threading.RLock()
        self._wake = threading.Condition(self._lock)
        self._stop = threading.Event()
        self._abort = threading.Event()
        self._active: dict[str, _Active] = {}  # leases held: running or queued
        self._queue: deque[list[Lease]] = deque()  # groups waiting for a free slot
        self._pending: dict[tuple[str, int], _Pending] = {}
        self._dropped: set[str] = set()
        self._cancelled_jobs: set[str] = set()
        self._slots: list[Slot] = []
        self._session: Any = None
        self._zenoh: Any = None
        self.runs_done = 0
        self.leases_done = 0
        self._closing = False
        self._seq = 0  # puts of results so far
        self._acked_seq = 0  # highest put with an acknowledged result
        self._last_ack = time.monotonic()

    # ------------------------------------------------------------------------------ control
    def stop(self) -> None:
        """Graceful stop (idempotent); a second call aborts running leases at once."""
        if self._stop.is_set():
            self._abort.set()
        self._stop.set()
        with self._wake:
            self._wake.notify_all()

    def install_signal_handlers(self) -> None:
        def handler(signum: int, _frame: Any) -> None:
            name = signal.Signals(signum).name
            if self._stop.is_set():
                log.warning("%s again: aborting running leases", name)
            else:
                log.info("%s: finishing (at most %.0f s), then leaving", name,
                         self.settings.grace_seconds)
            self.stop()

        signal.signal(signal.SIGTERM, handler)
        signal.signal(signal.SIGINT, handler)

    # ---------------------------------------------------------------------------------- run
    def run(self) -> int:
        slot_cls = ProcessSlot if self.settings.executor == "process" else ThreadSlot
        self._slots = [slot_cls(i, self._on_slot_done) for i in range(self.settings.slots)]
        for slot in self._slots:
            if isinstance(slot, ProcessSlot):
                slot.on_ready = self._slot_ready
            slot.start()
        if self.settings.exit_with_parent:
            threading.Thread(target=self._watch_parent, daemon=True).start()
        try:
            if not self._open():
                return 1
            self._declare()
            threads = [
                threading.Thread(target=self._heartbeat_loop, name="heartbeat", daemon=True),
                threading.Thread(target=self._resend_loop, name="resend", daemon=True),
            ]
            for t in threads:
                t.start()
            log.info("worker %s ready: %d %s slot(s), pulling from %s", self.id,
                     len(self._slots), self.settings.executor, ", ".join(self.settings.connect))
            self._pull_loop()
            self._drain()
            return 0
        finally:
            self._shutdown()

    def _slot_ready(self) -> None:
        with self._wake:
            self._wake.notify_all()

    def _watch_parent(self) -> None:
        while not self._stop.wait(0.5):
            if os.getppid() != self.settings.exit_with_parent:
                log.warning("parent process %s is gone: stopping", self.settings.exit_with_parent)
                self.stop()
                return

    def _open(self) -> bool:
        import zenoh

        from swarmpath.service.zenoh_config import describe, to_zenoh

        self._zenoh = zenoh
        conf = self.settings.zenoh_config()
        complained = False
        while not self._stop.is_set():
            try:
                self._session = zenoh.open(to_zenoh(conf))
                log.info("%s", describe(conf))
                return True
            except Exception as exc:
                if not complained:
                    log.warning("cannot open %s (%s); retrying until it answers",
                                describe(conf), " ".join(str(exc).split())[:200])
                    complained = True
                self._stop.wait(1.0)
        return False

    def _declare(self) -> None:
        s = self._session
        self._token = s.liveliness().declare_token(self.keys.worker_token(self.id))
        self._subs = [
            s.declare_subscriber(self.keys.ack(self.id), self._on_ack),
            s.declare_subscriber(self.keys.cancel, self._on_cancel),
        ]
        self._querier = s.declare_querier(
            self.keys.work, timeout=self.settings.query_timeout,
            target=self._zenoh.QueryTarget.BEST_MATCHING,
        )

    # ----------------------------------------------------------------------------- pulling
    def _free_slot(self) -> Slot | None:
        for slot in self._slots:
            if not slot.busy and not any(a.slot is slot for a in self._active.values()):
                return slot
        return None

    def _wants_work(self) -> bool:
        """Pull while fewer groups are held (running or queued) than ready slots + prefetch
        (nothing before a slot is ready: work is not taken before it can start)."""
        ready = [slot for slot in self._slots if slot.ready]
        if not ready:
            return False
        running = sum(1 for slot in ready if slot.busy)
        return running + len(self._queue) < len(ready) + max(0, self.settings.prefetch)

    def request(self) -> bytes:
        return encode(LeaseRequest(
            worker=self.id, max_runs=self.settings.max_runs,
            max_leases=max(1, min(self.settings.max_leases, MAX_BUNDLE_LEASES)),
            host=self.host, pid=os.getpid(), slots=len(self._slots), version=_version(),
            protocol=PROTOCOL_VERSION,
        ))

    def _ask(self) -> Lease | LeaseBundle | NoWork | None:
        """One lease request; None when nobody answered."""
        replies = list(self._querier.get(payload=self.request()))
        for reply in replies:
            ok = reply.ok
            if ok is None:
                err = reply.err
                log.warning("lease request failed: %s",
                            err.payload.to_bytes()[:200] if err is not None else "?")
                continue
            try:
                return decode_work_reply(ok.payload.to_bytes())
            except Exception as exc:
                log.warning("ignored a malformed lease reply: %s", " ".join(str(exc).split())[:200])
        return None

    def _pull_loop(self) -> None:
        """Ask for work whenever fewer groups are held than slots + prefetch: with prefetch the
        next group is already here when a slot finishes, so no slot waits for a round trip."""
        backoff = 0.0
        while not self._stop.is_set():
            with self._wake:
                while not self._stop.is_set() and not self._wants_work():
                    self._wake.wait(0.5)
            if self._stop.is_set():
                return
            try:
                reply = self._ask()
            except Exception as exc:
                log.warning("lease request failed: %s", exc)
                reply = None
            if reply is None:
                backoff = min(self.settings.max_backoff, max(1.0, backoff * 2))
                if backoff <= 1.0:
                    log.warning("no coordinator answers on %s; retrying", self.keys.work)
                self._stop.wait(backoff)
                continue
            if backoff:
                log.info("coordinator reachable again")
                backoff = 0.0
                self._resend_all()
            if isinstance(reply, NoWork):
                self._stop.wait(reply.retry_after)
                continue
            self._take(reply.leases if isinstance(reply, LeaseBundle) else [reply])

    def _take(self, leases: Sequence[Lease]) -> None:
        """Hold a group of granted leases and start it as soon as a slot is free."""
        mine = [lease for lease in leases if lease.worker == self.id]
        if len(mine) < len(leases):  # pragma: no cover - we asked for ourselves
            log.warning("ignored %d leases granted to another worker", len(leases) - len(mine))
        if not mine:
            return
        with self._lock:
            now = time.monotonic()
            for lease in mine:
                self._active[lease.lease_id] = _Active(lease, None, now, now)
                log.debug("lease %s: %s runs %s", lease.lease_id, lease.cell, lease.runs)
            self._queue.append(mine)
        self._dispatch()

    def _start(self, lease: Lease) -> None:
        """Run one lease (as a group of one)."""
        self._take([lease])

    def _dispatch(self) -> None:
        """Start queued groups on free slots."""
        while True:
            with self._lock:
                if not self._queue or self._stop.is_set():  # stopping: _drain forgets them
                    return
                slot = self._free_slot()
                if slot is None:
                    return
                group = [lease for lease in self._queue.popleft()
                         if lease.lease_id in self._active]
                if not group:
                    continue
                for lease in group:
                    self._active[lease.lease_id].slot = slot
                slot.leases = group  # busy from now on (submit sets it again)
            slot.submit(group)

    # ----------------------------------------------------------------------------- results
    def _on_slot_done(self, slot: Slot, outcomes: Outcomes) -> None:
        done: list[tuple[Lease, list[tuple[int, bytes]]]] = []
        again: list[Lease] = []
        with self._lock:
            for lease, outcome in outcomes:
                dropped = lease.lease_id in self._dropped or lease.job_id in self._cancelled_jobs
                held = self._active.get(lease.lease_id)
                if isinstance(outcome, NotRun) and held is not None and not dropped \
                        and not self._stop.is_set():
                    held.slot = None
                    again.append(lease)
                    continue
                self._active.pop(lease.lease_id, None)
                if isinstance(outcome, Cancelled | NotRun) or dropped:
                    log.info("lease %s (%s) dropped", lease.lease_id, lease.cell)
                elif isinstance(outcome, BaseException):
                    text = f"{type(outcome).__name__}: {outcome}"
                    log.error("lease %s failed as a whole: %s", lease.lease_id, text)
                    done.append((lease, [
                        (r, fit_result(_result(lease, r, 0.0, status="failed",
                                               failure=text[:20_000])))
                        for r in lease.runs
                    ]))
                else:
                    done.append((lease, outcome))
                    self.leases_done += 1
                    self.runs_done += len(outcome)
            if again:
                self._queue.appendleft(again)
        try:
            self._dispatch()  # the next group first: the slot is free again
            self._publish_many(done)
        except Exception:  # never lose the slot thread silently; the lease expires and requeues
            log.exception("handling the outcome of a group of %d leases failed", len(outcomes))
        finally:
            with self._wake:
                self._wake.notify_all()

    def _publish_results(self, lease: Lease, results: list[tuple[int, bytes]]) -> None:
        self._publish_many([(lease, results)])

    def _publish_many(self, items: Sequence[tuple[Lease, list[tuple[int, bytes]]]]) -> None:
        """Results of finished leases: remembered until acknowledged, put once per job (in
        batches of at most BATCH_BYTES)."""
        by_job: dict[str, list[_Pending]] = {}
        with self._lock:
            for lease, results in items:
                for run, data in results:
                    entry = _Pending(lease.job_id, lease.lease_id, data)
                    self._pending[(lease.lease_id, run)] = entry
                    by_job.setdefault(lease.job_id, []).append(entry)
        for job_id, entries in by_job.items():
            self._send(job_id, entries)

    def _send(self, job_id: str, entries: list[_Pending]) -> None:
        """Put results (in batches) and note when and in which put they went."""
        with self._lock:
            self._seq += 1
            now = time.monotonic()
            for e in entries:
                e.sent, e.seq = now, self._seq
                e.attempts += 1
        key = self.keys.results(job_id)
        for payload in pack_batches(self.id, [e.data for e in entries]):
            self._put(key, payload)

    def _put(self, key: str, payload: bytes) -> None:
        try:
            self._session.put(
                key, payload, encoding=self._zenoh.Encoding.APPLICATION_JSON,
                congestion_control=self._zenoh.CongestionControl.BLOCK,
            )
        except Exception as exc:
            log.warning("put on %s failed (will retry): %s", key, exc)

    def _on_ack(self, sample: Any) -> None:
        """Zenoh callback: quick bookkeeping only."""
        try:
            ack = decode(Ack, sample.payload.to_bytes())
        except Exception as exc:
            log.warning("ignored a malformed ack: %s", " ".join(str(exc).split())[:200])
            return
        with self._wake:
            if ack.results:
                self._last_ack = time.monotonic()
            for r in ack.results:
                entry = self._pending.pop((r.lease_id, r.run), None)
                if entry is not None:
                    self._acked_seq = max(self._acked_seq, entry.seq)
                if r.status == "stale":
                    log.info("result %s run %d was stale (%s)", r.cell, r.run, r.lease_id)
            for lease_id in ack.drop_leases:
                self._drop(lease_id)
            self._wake.notify_all()

    def _on_cancel(self, sample: Any) -> None:
        try:
            msg = decode(Cancel, sample.payload.to_bytes())
        except Exception as exc:
            log.warning("ignored a malformed cancel: %s", " ".join(str(exc).split())[:200])
            return
        with self._wake:
            self._cancelled_jobs.add(msg.job_id)
            for a in list(self._active.values()):
                if a.lease.job_id == msg.job_id:
                    log.info("job %s cancelled: dropping lease %s", msg.job_id, a.lease.lease_id)
                    self._abandon(a)
            for key in [k for k, p in self._pending.items() if p.job_id == msg.job_id]:
                del self._pending[key]
            self._wake.notify_all()

    def _drop(self, lease_id: str) -> None:
        self._dropped.add(lease_id)
        if len(self._dropped) > 10_000:
            self._dropped = {lease_id}
        active = self._active.get(lease_id)
        if active is not None:
            log.info("coordinator dropped lease %s (%s)", lease_id, active.lease.cell)
            self._abandon(active)
        for key in [k for k, p in self._pending.items() if p.lease_id == lease_id]:
            del self._pending[key]

    def _abandon(self, active: _Active) -> None:
        """Stop a held lease: cancel it in its slot, or forget it if it has not started."""
        if active.slot is not None:
            active.slot.cancel(active.lease.lease_id)
        else:
            self._active.pop(active.lease.lease_id, None)  # _dispatch skips it

    def _resend_all(self) -> None:
        with self._lock:
            for p in self._pending.values():
                p.sent = 0.0

    def _resend_loop(self) -> None:
        while self._session is not None and not self._abort.is_set():
            time.sleep(0.25)
            self.resend_due()
            if self._closing:
                return

    def resend_due(self, now: float | None = None) -> int:
        """Put again what was not acknowledged within ack_timeout (doubling, at most 30 s) -
        unless acks keep coming for earlier puts: the coordinator handles each worker's messages
        in order, so it is busy, not deaf, and re-sending would only add duplicates to its queue.
        A result is re-sent at once when a later put was acknowledged before it (it was lost)
        or after an outage (``_resend_all``). Returns how many results were put again."""
        now = time.monotonic() if now is None else now
        due: dict[str, list[_Pending]] = {}
        with self._lock:
            silent = now - self._last_ack >= self.settings.ack_timeout
            for p in self._pending.values():
                wait = min(30.0, self.settings.ack_timeout * 2 ** max(0, p.attempts - 1))
                overtaken = p.seq < self._acked_seq
                if p.sent == 0.0 or (now - p.sent >= wait and (silent or overtaken)):
                    due.setdefault(p.job_id, []).append(p)
        for job_id, entries in due.items():
            log.info("re-sending %d unacknowledged results of job %s", len(entries), job_id)
            self._send(job_id, entries)
        return sum(len(v) for v in due.values())

    # --------------------------------------------------------------------------- heartbeat
    def _heartbeat_loop(self) -> None:
        while not self._closing:
            time.sleep(0.25)
            self.heartbeat_due()

    def heartbeat_due(self, now: float | None = None) -> int:
        """RunProgress for each running lease not reported for half its heartbeat_seconds."""
        now = time.monotonic() if now is None else now
        with self._lock:
            due = [a for a in self._active.values()
                   if now - a.last_progress >= 0.5 * a.lease.heartbeat_seconds]
            for a in due:
                a.last_progress = now
        for a in due:
            lease = a.lease
            spec = lease.spec
            total = spec.iterations * len(
                benchmark_batches(lease.runs, spec.agents, spec.dim)
            ) if isinstance(spec, BenchmarkCell) else 0
            msg = RunProgress(
                lease_id=lease.lease_id, job_id=lease.job_id, worker=self.id,
                cell=lease.cell, runs=list(lease.runs),
                iteration=a.slot.iteration(lease.lease_id) if a.slot is not None else 0,
                iterations=total,
            )
            self._put(self.keys.progress(lease.job_id), encode(msg))
        return len(due)

    # ---------------------------------------------------------------------------- stopping
    def _drain(self) -> None:
        """Stop: let running leases finish (grace), abort the rest, wait for the acks."""
        deadline = time.monotonic() + self.settings.grace_seconds
        with self._wake:
            # leases not started yet are left to the coordinator (requeued when we leave)
            for group in self._queue:
                for lease in group:
                    a = self._active.get(lease.lease_id)
                    if a is not None and a.slot is None:
                        self._dropped.add(lease.lease_id)
                        del self._active[lease.lease_id]
            self._queue.clear()
            while self._active and not self._abort.is_set() and time.monotonic() < deadline:
                self._wake.wait(0.25)
            if self._active:
                log.info("aborting %d running leases; the coordinator requeues them",
                         len(self._active))
                for a in list(self._active.values()):
                    self._dropped.add(a.lease.lease_id)
                    self._abandon(a)
            stop_at = time.monotonic() + 3.0
            while self._active and time.monotonic() < stop_at:
                self._wake.wait(0.25)
            ack_deadline = time.monotonic() + self.settings.ack_timeout
            if self._pending:
                self._resend_all()
            while self._pending and not self._abort.is_set() and time.monotonic() < ack_deadline:
                self._wake.wait(0.25)
            if self._pending:
                log.warning("%d results not acknowledged at exit: the coordinator requeues "
                            "their runs", len(self._pending))

    def _shutdown(self) -> None:
        self._closing = True
        for entity in (getattr(self, "_querier", None), *getattr(self, "_subs", []),
                       getattr(self, "_token", None)):
            if entity is None:
                continue
            try:
                entity.undeclare()
            except Exception:  # pragma: no cover
                log.debug("undeclare failed", exc_info=True)
        self._subs = []
        self._token = None
        self._querier = None
        if self._session is not None:
            try:
                self._session.close()
            except Exception:  # pragma: no cover
                log.debug("closing the session failed", exc_info=True)
            self._session = None
        for slot in self._slots:
            slot.close(timeout=3.0)
        log.info("worker %s stopped: %d leases, %d runs", self.id, self.leases_done,
                 self.runs_done)


def _version() -> str:
    try:
        from swarmpath import __version__
    except ImportError:  # pragma: no cover
        return ""
    return __version__


def run_worker(settings: WorkerSettings, *, signals: bool = True) -> int:
    """Run a worker until SIGTERM/SIGINT (the ``swarmpath worker`` command)."""
    worker = Worker(settings)
    if signals:
        worker.install_signal_handlers()
    return worker.run()


__all__ = [
    "Cancelled",
    "ProcessSlot",
    "ThreadSlot",
    "Worker",
    "WorkerSettings",
    "benchmark_batches",
    "execute_lease",
    "fit_result",
    "pack_batches",
    "run_worker",
]
