"""Slots - where leases execute, ``--slots N`` of them: spawned child processes by default (never
forked: the parent runs Zenoh), or threads (``executor="thread"``, for tests and debugging).
A child ignores SIGINT (the parent decides), and exits by itself when its parent disappears."""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

from swarmpath.service.capability import new_capability
from swarmpath.service.protocol import (
    MAX_BUNDLE_LEASES,
    BenchmarkCell,
    Lease,
    LeaseBundle,
    decode_work_reply,
    encode,
)
from swarmpath.service.worker.execution import Cancelled, _failure_text, execute_lease
from swarmpath.service.worker.stacking import stacked_outcomes

log = logging.getLogger("swarmpath.worker")


class NotRun(Exception):
    """A lease of a group that never started (its slot process died before): run it again."""


#: What a slot reports for each lease of a group: ``(lease, outcome)`` with outcome the list of
#: ``(run, encoded RunResult)``, or a :class:`Cancelled`, :class:`NotRun` or other exception.
Outcomes = list[tuple[Lease, Any]]


class Slot:
    """Executes one group of leases at a time (a group is the leases of one LeaseBundle, or a
    single lease), stack after stack (:mod:`.stacking`: benchmark leases differing only in their
    function run as one batch, any other lease alone); ``on_done(slot, outcomes)`` is called
    once per group from a thread of the slot. Each lease of a group can be cancelled on its
    own."""

    def __init__(self, index: int, on_done: Callable[[Slot, Outcomes], None],
                 stacking: bool = True):
        self.index = index
        self.on_done = on_done
        self.stacking = stacking
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

    def __init__(self, index: int, on_done: Callable[[Slot, Outcomes], None],
                 stacking: bool = True):
        super().__init__(index, on_done, stacking)
        self._cancel: list[threading.Event] = []
        self._running: set[int] = set()  # positions of the leases of the stack running
        self._done = 0
        self._thread: threading.Thread | None = None

    def submit(self, leases: Sequence[Lease]) -> None:
        group = list(leases)
        self._cancel = [threading.Event() for _ in group]
        self._running, self._done = set(), 0
        self.leases = group
        self._thread = threading.Thread(
            target=self._run, args=(group, self._cancel), name=f"slot-{self.index}", daemon=True)
        self._thread.start()

    def _run(self, group: list[Lease], flags: list[threading.Event]) -> None:
        def progress(n: int) -> None:
            self._done = n

        def on_stack(stack: list[int]) -> None:
            self._done = 0
            self._running = set(stack)

        got = dict(stacked_outcomes(group, [flag.is_set for flag in flags], on_stack, progress,
                                    self.stacking))
        self._running = set()
        self.leases = []
        self.on_done(self, [(lease, got[i]) for i, lease in enumerate(group)])

    def cancel(self, lease_id: str | None = None) -> None:
        for i in self._position(lease_id):
            self._cancel[i].set()

    def iteration(self, lease_id: str | None = None) -> int:
        running = self._running
        return self._done if any(i in running for i in self._position(lease_id)) else 0

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
                  lease_seconds=1.0, heartbeat_seconds=1.0, capability=new_capability())
    try:
        execute_lease(lease)
    except Exception:  # pragma: no cover - a broken core shows up in the first real lease
        log.debug("warm-up run failed", exc_info=True)


def warm_compiled() -> None:
    """Compile (or load from numba's on-disk cache) every kernel and compiled objective that
    backend "auto" may run, before the slot takes work: no lease waits for numba's compiler (a
    kernel not in the cache costs 3-20 s of CPU at its first use). The cache is per installed
    tree and shared by every process of it; the slots and workers starting together compile
    each piece once between them (:func:`swarmpath.optimizers.compiled.warm.warm`, shared).
    Only then does backend "auto" run the kernels in this process (``execution.AUTO``; the
    numpy reference before, or without numba: the same numbers)."""
    try:
        from swarmpath.optimizers.compiled.warm import warm
    except ImportError:  # numba is not installed: nothing compiles
        return
    try:
        done = warm(shared=True, start=os.getpid())
    except Exception:  # auto stays on the numpy reference in this slot
        log.warning("compiling the kernels failed; backend auto runs numpy here", exc_info=True)
        return
    from swarmpath.service.worker import execution

    execution.AUTO[0] = "auto"  # every kernel is ready: auto may run them
    seconds = sum(w.seconds for w in done)
    if seconds > 10.0:
        log.warning("compiled the numba kernels in %.0f s of CPU (once per installed tree; "
                    "`swarmpath warmup` does it ahead)", seconds)


def _slot_main(
    conn: Any, cancel: Any, done: Any, running: Any, parent: int, stacking: bool = True,
    warm: bool = False,
) -> None:
    """A slot's child process: groups of leases in, one reply per lease out, until told to stop
    or orphaned."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's business

    def orphan_watch() -> None:
        """Exit at once when the worker dies, busy or not: multiprocessing's parent sentinel
        (a pipe whose other end only the worker holds) reads end-of-file the moment it dies;
        without one (not spawned), the parent's pid is checked every 0.1 s."""
        import multiprocessing
        from multiprocessing.connection import wait

        watched = multiprocessing.parent_process()
        if watched is not None and watched.pid == parent:
            wait([watched.sentinel])
        else:
            while os.getppid() == parent:
                time.sleep(0.1)
        os._exit(3)

    threading.Thread(target=orphan_watch, daemon=True).start()
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s slot %(message)s")
    # One slot is one core: no BLAS/OpenMP thread pools fighting the other slots and workers
    # (numpy is not imported yet in this fresh process; an explicit setting wins).
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    # Pay the imports before the first lease: the optimizers, and the planners with the scipy
    # modules they use (sparse, spatial; ~0.5 s of CPU that a map lease of short runs would
    # otherwise spend at its start, in every slot).
    import swarmpath.optimizers
    import swarmpath.planners  # noqa: F401

    def progress(n: int) -> None:
        done.value = n

    warm_up()
    if warm:
        warm_compiled()
    try:
        conn.send(("ready", -1))  # the worker pulls work for this slot only from now on
    except (EOFError, OSError):
        return

    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):  # the worker died: its end of the pipe closed with it
            os._exit(3)  # at once (an interpreter's teardown with the core loaded took ~1 s)
        if message is None:
            return
        try:
            bundle = decode_work_reply(message)
            assert isinstance(bundle, LeaseBundle)
        except Exception as exc:  # pragma: no cover - the parent encoded it
            conn.send(("error", -1, _failure_text(exc)))
            continue
        def on_stack(stack: list[int]) -> None:
            done.value = 0
            for j in range(MAX_BUNDLE_LEASES):
                running[j] = 1 if j in stack else 0

        flags = [lambda i=i: bool(cancel[i]) for i in range(len(bundle.leases))]
        for i, outcome in stacked_outcomes(bundle.leases, flags, on_stack, progress, stacking):
            reply: tuple[Any, ...] = (
                ("cancelled", i) if isinstance(outcome, Cancelled) else
                ("error", i, _failure_text(outcome)) if isinstance(outcome, BaseException) else
                ("done", i, outcome))
            try:
                conn.send(reply)
            except (EOFError, OSError):
                return
        for j in range(MAX_BUNDLE_LEASES):
            running[j] = 0


class ProcessSlot(Slot):
    """Leases run in a spawned child process (true parallelism; killed and respawned if it
    dies). The child is started with the multiprocessing *spawn* method, never forked; it says
    ready after its warm-up (imports, a tiny run, and with ``warm`` the compiled kernels:
    :func:`warm_compiled`; a worker passes its ``--warm`` setting, other users of a slot, such
    as the conformance check, run the numpy cells they give it and need none)."""

    def __init__(self, index: int, on_done: Callable[[Slot, Outcomes], None],
                 stacking: bool = True, warm: bool = False):
        super().__init__(index, on_done, stacking)
        self.warm = warm
        import multiprocessing

        self._ctx = multiprocessing.get_context("spawn")
        self._cancel = self._ctx.Array("b", MAX_BUNDLE_LEASES, lock=False)
        self._done = self._ctx.Value("q", 0, lock=False)
        self._running = self._ctx.Array("b", MAX_BUNDLE_LEASES, lock=False)
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
            args=(child_conn, self._cancel, self._done, self._running, os.getpid(),
                  self.stacking, self.warm),
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
            self._running[i] = 0
        self._done.value = 0
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
        if any(self._running[i] for i in self._position(lease_id)):
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
