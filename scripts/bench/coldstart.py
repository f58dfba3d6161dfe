#!/usr/bin/env python3
"""What a fresh environment's first study costs: CPU and wall time of a command's first run in
an empty numba cache, of the background compile it started (backend auto on a cold cache), and
of its second run in the same cache once that compile finished.

    PYTHONPATH=services .venv/bin/python scripts/bench/coldstart.py [--pairs 3]
        [--modes install,none[,base]] [--baseline DIR] [--command "plan --runs 1"] ...

A pair: a new empty cache directory (``NUMBA_CACHE_DIR``), then in mode ``install`` the
install's warm-up (``swarmpath warmup --if-cold --no-suites``, what scripts/_venv.sh runs; its
CPU is shown apart), in mode ``none`` nothing (a pip user who skipped it), in mode ``base``
nothing either but the commands run the tree at ``--baseline`` (its ``services``: the code
before a change);
then every command twice, in the order given, waiting between the two for every process the
first left behind (a background compile: this script is their subreaper, so they are reaped
here and counted). first - second is what the first run compiled (and loaded the first time):
the runs do the same work otherwise. The modes alternate pair by pair, so that all see the same
load. CPU is user + sys of the command's process and of every process it or this script waited
for (worker processes, background compiles), from ``getrusage(RUSAGE_CHILDREN)``; wall time is
the command's own (not the background compile's), on a shared machine a ratio only within a
pair. The load average at the start and the end and the tree (``git describe``) close the
output. Each command is ``python -m swarmpath.cli`` with these arguments, stdout discarded.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import resource
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

DEFAULT_COMMANDS = ["plan --runs 1", "bench --runs 1 -d 10 --iterations 20"]
INSTALL = ["warmup", "--if-cold", "--no-suites"]  # the last step of scripts/_venv.sh
PR_SET_CHILD_SUBREAPER = 36  # prctl(2)


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def measure(args: list[str], env: dict[str, str]) -> tuple[float, float]:
    """CPU seconds (user + sys, with the processes it reaped) and wall seconds of
    ``python -m swarmpath.cli ARGS``."""
    before, started = _children_cpu(), time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "swarmpath.cli", *args], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - started
    if out.returncode != 0:
        sys.exit(f"{shlex.join(args)} failed:\n{out.stderr[-2000:]}")
    return _children_cpu() - before, wall


def reap_left_behind() -> float:
    """Wait for every process a command left running (its background compile, reparented to
    this script, the subreaper) and return the CPU seconds they used."""
    before = _children_cpu()
    while True:
        try:
            os.waitpid(-1, 0)
        except ChildProcessError:
            return _children_cpu() - before


Run = tuple[float, float, float, float, float]  # first CPU, wall; left behind CPU; second CPU, wall


def one_pair(mode: str, commands: list[list[str]], baseline: str | None) -> tuple[float, list[Run]]:
    """CPU of the install's warm-up (0 without) and each command's runs (:data:`Run`)."""
    cache = tempfile.mkdtemp(prefix="coldstart-")
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    if mode == "base":
        env["PYTHONPATH"] = os.path.join(baseline or ".", "services")
    try:
        install = measure(INSTALL, env)[0] + reap_left_behind() if mode == "install" else 0.0
        runs: list[Run] = []
        for c in commands:
            first = measure(c, env)
            behind = reap_left_behind()
            runs.append((*first, behind, *measure(c, env)))
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    return install, runs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", type=int, default=3, help="pairs per mode")
    ap.add_argument("--modes", default="install,none", help="install, none, base")
    ap.add_argument("--baseline", help="a tree (git archive) whose services mode base runs")
    ap.add_argument("--command", action="append", help=f"(repeatable) default: {DEFAULT_COMMANDS}")
    opts = ap.parse_args()
    modes = [m for m in opts.modes.split(",") if m]
    if not set(modes) <= {"install", "none", "base"} or ("base" in modes) != bool(opts.baseline):
        sys.exit("--modes: install, none and/or base (base with --baseline, and only then)")
    texts = opts.command or DEFAULT_COMMANDS
    commands = [shlex.split(c) for c in texts]
    load = os.getloadavg()[0]
    seen: dict[str, list[tuple[float, list[Run]]]] = {m: [] for m in modes}
    # the background compiles the commands leave behind become this process's children
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, 1)
    for p in range(opts.pairs):
        for mode in modes if p % 2 == 0 else modes[::-1]:
            install, runs = one_pair(mode, commands, opts.baseline)
            seen[mode].append((install, runs))
            parts = "  ".join(f"{t}: {r[0]:.1f} cpu {r[1]:.1f} wall + {r[2]:.1f} behind / "
                              f"{r[3]:.1f} cpu {r[4]:.1f} wall"
                              for t, r in zip(texts, runs, strict=True))
            print(f"pair {p + 1} {mode:7} install {install:6.1f}  {parts}", flush=True)
    print()
    print("| mode | command | install CPU s | first: CPU s / wall s | left behind: CPU s | "
          "second: CPU s / wall s | first - second, CPU s: median |")
    print("| --- | --- | ---: | --- | --- | --- | ---: |")
    for mode in modes:
        install_cpu = statistics.median(p[0] for p in seen[mode])
        for i, text in enumerate(texts):
            rows = [p[1][i] for p in seen[mode]]

            def col(k: int, rows: list[Run] = rows) -> str:
                return ", ".join(f"{r[k]:.1f}" for r in rows)

            extra = statistics.median(r[0] - r[3] for r in rows)
            print(f"| {mode} | `{text}` | {install_cpu:.1f} | {col(0)} / {col(1)} | {col(2)} | "
                  f"{col(3)} / {col(4)} | {extra:.1f} |")
    tree = subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True,
                          text=True).stdout.strip()
    print(f"\nload average {load:.1f} -> {os.getloadavg()[0]:.1f}; tree {tree}")


if __name__ == "__main__":
    main()
