#!/usr/bin/env python3
"""What a fresh environment's first study compiles: CPU of a command's first run in an empty
numba cache against its second run in the same cache.

    PYTHONPATH=services .venv/bin/python scripts/bench/coldstart.py [--pairs 3]
        [--modes install,none[,base]] [--baseline DIR] [--command "plan --runs 1"] ...

A pair: a new empty cache directory (``NUMBA_CACHE_DIR``), then in mode ``install`` the
install's warm-up (``swarmpath warmup --if-cold --no-suites``, what scripts/_venv.sh runs; its
CPU is shown apart), in mode ``none`` nothing (a pip user who skipped it), in mode ``base``
nothing either but the commands run the tree at ``--baseline`` (its ``services``: the code
before a change);
then every command twice, in the order given. first - second is what the first run compiled
(and loaded the first time): the runs do the same work otherwise. The modes alternate pair by
pair, so that all see the same load. CPU is user + sys of the command's process and of every
process it waited for (its worker processes), from ``getrusage(RUSAGE_CHILDREN)``; wall time
is not shown (the machine is shared). The load average at the start and the end and the tree
(``git describe``) close the output. Each command is ``python -m swarmpath.cli`` with these
arguments, stdout discarded.
"""

from __future__ import annotations

import argparse
import os
import resource
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile

DEFAULT_COMMANDS = ["plan --runs 1", "bench --runs 1 -d 10 --iterations 20"]
INSTALL = ["warmup", "--if-cold", "--no-suites"]  # the last step of scripts/_venv.sh


def cpu_of(args: list[str], env: dict[str, str]) -> float:
    """User + sys CPU seconds of ``python -m swarmpath.cli ARGS`` and the processes it reaped."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([sys.executable, "-m", "swarmpath.cli", *args], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        sys.exit(f"{shlex.join(args)} failed:\n{out.stderr[-2000:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def one_pair(mode: str, commands: list[list[str]],
             baseline: str | None) -> tuple[float, list[tuple[float, float]]]:
    """CPU of the install's warm-up (0 without) and of each command's (first, second) run."""
    cache = tempfile.mkdtemp(prefix="coldstart-")
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    if mode == "base":
        env["PYTHONPATH"] = os.path.join(baseline or ".", "services")
    try:
        install = cpu_of(INSTALL, env) if mode == "install" else 0.0
        runs = [(cpu_of(c, env), cpu_of(c, env)) for c in commands]
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
    seen: dict[str, list[tuple[float, list[tuple[float, float]]]]] = {m: [] for m in modes}
    for p in range(opts.pairs):
        for mode in modes if p % 2 == 0 else modes[::-1]:
            install, runs = one_pair(mode, commands, opts.baseline)
            seen[mode].append((install, runs))
            parts = "  ".join(f"{t}: {a:.1f} / {b:.1f}"
                              for t, (a, b) in zip(texts, runs, strict=True))
            print(f"pair {p + 1} {mode:7} install {install:6.1f}  {parts}", flush=True)
    print()
    print("| mode | command | install CPU s | first - second, CPU s (pairs) | median |")
    print("| --- | --- | ---: | --- | ---: |")
    for mode in modes:
        install_cpu = statistics.median(p[0] for p in seen[mode])
        for i, text in enumerate(texts):
            extra = [p[1][i][0] - p[1][i][1] for p in seen[mode]]
            print(f"| {mode} | `{text}` | {install_cpu:.1f} | "
                  f"{', '.join(f'{x:.1f}' for x in extra)} | {statistics.median(extra):.1f} |")
    tree = subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True,
                          text=True).stdout.strip()
    print(f"\nload average {load:.1f} -> {os.getloadavg()[0]:.1f}; tree {tree}")


if __name__ == "__main__":
    main()
