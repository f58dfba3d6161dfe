"""``swarmpath warmup`` and ``compiled.warm``: the kernels a study needs, made ready before it."""

import contextlib
import fcntl
import json
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.optimizers import minimize
from swarmpath.optimizers.compiled import kernel_names
from swarmpath.optimizers.compiled.objectives import compiled_names
from swarmpath.optimizers.compiled.warm import warm

runner = CliRunner()


def test_warm_makes_the_named_pieces_ready_and_times_each():
    done = warm(["PSO"], ["F9", "F1"])
    assert [(w.kind, w.name) for w in done] == [
        ("function", "F9"), ("function", "F1"), ("algorithm", "PSO")]
    ref = minimize("PSO", "F9", dim=3, agents=6, iterations=4, runs=2, backend="numpy")
    fast = minimize("PSO", "F9", dim=3, agents=6, iterations=4, runs=2)
    assert fast.backend == "numba" and np.array_equal(ref.curve, fast.curve)


def test_warmup_command_lists_what_it_compiled():
    out = runner.invoke(app, ["warmup", "-a", "PSO,GWO", "-f", "F1-F2", "--json"])
    assert out.exit_code == 0, out.output
    names = [(w["kind"], w["name"]) for w in json.loads(out.stdout)]
    assert names == [("function", "F1"), ("function", "F2"), ("algorithm", "PSO"),
                     ("algorithm", "GWO")]
    assert set(kernel_names()) >= {"PSO", "GWO"} and "F1" in compiled_names()


def test_warmup_compiles_the_cec_objectives_like_bbobs():
    out = runner.invoke(app, ["warmup", "-a", "PSO", "-f", "cec2022,bbob:f1", "--json"])
    assert out.exit_code == 0, out.output
    names = [(w["kind"], w["name"]) for w in json.loads(out.stdout)]
    assert names == [*(("function", f"cec2022:F{k}") for k in range(1, 13)),
                     ("function", "bbob:f1"), ("algorithm", "PSO")]
    ref = minimize("PSO", "cec2022:F7", dim=10, agents=6, iterations=4, runs=2, backend="numpy")
    fast = minimize("PSO", "cec2022:F7", dim=10, agents=6, iterations=4, runs=2)
    assert fast.backend == "numba" and np.array_equal(ref.curve, fast.curve)


def test_the_map_piece_compiles_every_clearance_and_sensing_kernel():
    """A worker's warm-up of everything includes the kernels every map run calls: in a fresh
    process none of them has a compiled signature before the piece, each has one after."""
    import subprocess
    import sys

    code = """
import swarmpath.world.clearance_compiled as cc
from numba.core.registry import CPUDispatcher
from swarmpath.optimizers.compiled.warm import warm
kernels = {n: k for n, k in vars(cc).items() if isinstance(k, CPUDispatcher) and n.endswith(
    ("_kernel", "build_index"))}
assert len(kernels) >= 5 and not any(k.signatures for k in kernels.values()), kernels
done = warm([], [], maps=True)
assert [(w.kind, w.name) for w in done] == [("map", "clearance")], done
missing = sorted(n for n, k in kernels.items() if not k.signatures)
assert not missing, missing
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=600, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.returncode == 0, out.stderr[-2000:]
    assert [w.kind for w in warm([], ["F1"])] == ["function"]  # a list of pieces: no map piece


def test_warmup_names_the_option_of_what_has_no_kernel():
    for args, field in ((["-a", "NOPE"], "--algorithms"), (["-a", "RS"], "--algorithms"),
                        (["-f", "cec2017:F1@centre"], "--functions"),
                        (["-f", "F99"], "--functions")):
        out = runner.invoke(app, ["warmup", *args])
        assert out.exit_code == 2, (args, out.output)
        assert f"error: {field}:" in out.output, (args, out.output)


@contextlib.contextmanager
def piece_held(kind: str, name: str):
    """The lock a shared warm-up takes for one piece, held here (as by another process)."""
    from numba.core import config

    path = Path(config.CACHE_DIR) / f".warm-{kind}-{name}.lock"
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield path
    finally:
        os.close(fd)


def waiting_on_a_lock(pid: int) -> bool:
    """Whether process ``pid`` waits for a file lock (a ``->`` line of /proc/locks)."""
    return any(line.split()[1] == "->" and int(line.split()[5]) == pid
               for line in Path("/proc/locks").read_text().splitlines())


def test_a_shared_warm_up_waits_for_the_process_making_a_piece_then_loads_it():
    done: list = []
    with piece_held("function", "F1"):
        thread = threading.Thread(target=lambda: done.append(
            warm([], ["F9", "F1"], shared=True, start=1)), daemon=True)
        thread.start()
        thread.join(3.0)
        assert thread.is_alive() and not done  # F9 comes first: F1 is another's
    thread.join(120)
    assert [(w.kind, w.name) for w in done[0]] == [("function", "F9"), ("function", "F1")]


def test_a_shared_warm_up_makes_the_next_piece_while_another_process_makes_one(monkeypatch,
                                                                            tmp_path):
    """Processes walking the same pieces do not wait at each one (they did, in turn, at every
    piece: two took as long as one): a piece another holds is passed over, the next one made
    meanwhile, the held one waited for at the end."""
    from numba.core import config

    from swarmpath.optimizers.compiled.warm import cold

    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))  # the markers: none made yet
    done: list = []
    with piece_held("function", "F2"):
        thread = threading.Thread(target=lambda: done.append(
            warm([], ["F9", "F2", "F1"], shared=True, cold_only=True)), daemon=True)
        thread.start()
        deadline = time.monotonic() + 120
        while cold([("function", "F1")]) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert cold([("function", "F9"), ("function", "F1")]) == []  # made while F2 was held
        assert thread.is_alive() and cold([("function", "F2")]) == [("function", "F2")]
    thread.join(120)
    assert [(w.kind, w.name) for w in done[0]] == [
        ("function", "F9"), ("function", "F2"), ("function", "F1")]


@pytest.mark.skipif(not Path("/proc/locks").is_file(), reason="needs Linux's /proc/locks")
def test_a_process_slot_says_ready_only_after_its_kernels_and_without_warm_at_once():
    """A slot process compiles (or loads) the kernels before it says ready, so a worker never
    pulls work for a slot that would compile inside its lease; ``warm=False`` skips that."""
    from swarmpath.service.worker.slots import ProcessSlot

    def nothing(*_args: object) -> None:
        pass

    with piece_held("function", "F1"):
        warming, plain = ProcessSlot(0, nothing, warm=True), ProcessSlot(1, nothing, warm=False)
        try:
            warming.start()
            plain.start()
            deadline = time.monotonic() + 180
            while not (plain.ready and waiting_on_a_lock(warming._proc.pid)):
                assert time.monotonic() < deadline, "the slots did not get there in 180 s"
                time.sleep(0.2)
            assert not warming.ready  # it waits for the kernel another process is making
        finally:
            warming.close(timeout=2.0)
            plain.close(timeout=2.0)


def test_a_worker_process_runs_auto_on_the_kernels_only_once_it_compiled_them(monkeypatch):
    """Backend "auto" in a lease is the numpy reference until the process warmed every kernel
    (nothing compiles inside a lease), the kernels after; a failed warm-up keeps numpy."""
    import swarmpath.optimizers.compiled.warm as warm_module
    from swarmpath.service.protocol import BenchmarkCell
    from swarmpath.service.worker import execution, slots
    from test_service_api import make_lease

    monkeypatch.setattr(execution, "AUTO", ["numpy"])
    spec = BenchmarkCell(algorithm="GWO", function="F1", dim=2, agents=6, iterations=3,
                         backend="auto")
    lease = make_lease(spec, [0])
    assert execution.minimize_options(lease, spec)["backend"] == "numpy"
    numba_spec = spec.model_copy(update={"backend": "numba"})
    assert execution.minimize_options(lease, numba_spec)["backend"] == "numba"  # as asked

    def broken(**_kw: object) -> list:
        raise RuntimeError("no compiler")

    monkeypatch.setattr(warm_module, "warm", broken)
    slots.warm_compiled()
    assert execution.minimize_options(lease, spec)["backend"] == "numpy"
    monkeypatch.setattr(warm_module, "warm", lambda **_kw: [])
    slots.warm_compiled()
    assert execution.minimize_options(lease, spec)["backend"] == "auto"


def test_algorithms_sharing_a_kernel_are_locked_as_one_piece():
    """A shared warm-up locks an algorithm under the first one whose kernel it runs, so two
    processes do not compile COOT's kernel at once for COOT and mCOOT."""
    from swarmpath.optimizers.compiled.registry import find_kernel, kernel_names
    from swarmpath.optimizers.compiled.warm import _compiled_as

    assert _compiled_as("algorithm", "mCOOT") == _compiled_as("algorithm", "ICOOT") == "COOT"
    assert _compiled_as("algorithm", "IHPO") == "HPO"
    assert _compiled_as("algorithm", "HPSO-MFB") == "MFB"
    assert _compiled_as("function", "F3") == "F3"
    assert _compiled_as("map", "clearance") == "clearance"
    names = kernel_names()
    for name in names:
        first = _compiled_as("algorithm", name)
        assert find_kernel(first).run is find_kernel(name).run
        assert names.index(first) <= names.index(name)
        assert all(find_kernel(n).run is not find_kernel(name).run
                   for n in names[:names.index(first)])
