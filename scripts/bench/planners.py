#!/usr/bin/env python3
"""Path planning speed and quality on one map (mfb-static by default), every registered planner.

    .venv/bin/python scripts/bench/planners.py [--map mfb-static] [--seeds 10] [--planners all]
        [--budget 120] [--no-same-budget] [--params JSON]

Each planner runs once per seed 1..N (run 0 of each seed) through :class:`Episode`, exactly as
``swarmpath plan`` does. Reported per planner: runs done, success, collisions, median planning
wall time per run (the ``seconds`` metric: wall time spent in the planner's decisions) and its
CPU time (process time of the same calls: less distorted by other jobs on a shared machine),
median and best executed length, and the gap to the exact optimum: ``gap`` = length / optimum - 1
as the episode reports it, and ``gap+err`` = (length + final error) / optimum - 1, which also
counts the last <= 0.2 m the robot does not drive (the episode ends within 0.2 m of the goal).

The OMPL baselines run at their default budget (an iteration count: the same paths on any
machine and load) and, unless ``--no-same-budget``, again with a CPU-time budget equal to the
median planning CPU time of the other planners' medians ("the same budget": CPU seconds, which
other processes' load does not shrink as it shrinks wall-clock seconds).

``--params`` takes the JSON of ``swarmpath plan --params`` (parameters per planner name, checked by
the planner), e.g. ``'{"MFB": {"knowledge": "map"}}'``; a row with parameters says so in its label.

Bounded: a planner stops taking new seeds once its runs have used ``--budget`` wall seconds (the
table says how many ran). A planner that raises is reported with the exception, not hidden.
Markdown on stdout (ready for docs/benchmarks.md), progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from decide_time import timed_episode  # scripts/bench/decide_time.py

from swarmpath.planners import get_planner, list_planners
from swarmpath.world import get_map

OMPL = ("OMPL-RRTstar", "OMPL-BITstar")


def note(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f} / {five:.2f} / {fifteen:.2f}"


def tree() -> str:
    """The commit measured (short hash), for the table's context line; a dirty tree says so."""
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=here, check=True,
                              capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=here, check=True, capture_output=True, text=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"
    return f"`{head}`" + (" with uncommitted changes" if dirty else "")


@dataclass
class Row:
    label: str
    planner: str
    params: dict[str, Any]
    outcomes: list[Any] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    wall_total: float = 0.0
    load: str = ""


def run_row(row: Row, scenario: Any, seeds: Sequence[int], budget: float) -> Row:
    for seed in seeds:
        if row.wall_total >= budget:
            note(f"  {row.label}: budget of {budget:g} s used, {len(row.outcomes)} runs done")
            break
        started = time.perf_counter()
        try:
            cpu, out = timed_episode(scenario, row.planner, seed, row.params)
            row.outcomes.append(out)
            row.cpu.append(cpu)
            note(f"  {row.label} seed {seed}: {'ok' if out.success else out.reason}, "
                 f"length {out.length:.4f}, planning {out.seconds:.3f} s")
        except Exception as exc:  # reported in the table, never hidden
            row.errors.append(f"seed {seed}: {type(exc).__name__}: {exc}")
            note(f"  {row.label} seed {seed}: EXCEPTION {exc!r}")
        row.wall_total += time.perf_counter() - started
    row.load = load()
    return row


def _median(values: Sequence[float]) -> float | None:
    return statistics.median(values) if values else None


def _fmt(v: float | None, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def markdown(rows: Sequence[Row], optimum: float | None) -> str:
    head = ("| planner | runs | success | collisions | median planning s wall (CPU) | "
            "median length m | best length m | median gap | median gap+err | notes |")
    lines = [head, "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    for row in rows:
        outs = row.outcomes
        n = len(outs) + len(row.errors)
        ok = [o for o in outs if o.success]
        wall = _median([o.seconds for o in outs])
        cpu = _median(row.cpu)
        lengths = [o.length for o in ok]
        gaps = [o.gap for o in ok if o.gap is not None]
        gap_err = ([(o.length + o.error) / optimum - 1.0 for o in ok] if optimum else [])
        reasons: dict[str, int] = {}
        for o in outs:
            if not o.success:
                reasons[o.reason] = reasons.get(o.reason, 0) + 1
        notes = [f"{k}x {r}" for r, k in reasons.items()] + row.errors
        lines.append(
            f"| {row.label} | {n} | {len(ok)}/{n} | {sum(o.collisions for o in outs)} | "
            f"{_fmt(wall, '.3f')} ({_fmt(cpu, '.3f')}) | {_fmt(_median(lengths), '.4f')} | "
            f"{_fmt(min(lengths) if lengths else None, '.4f')} | "
            f"{_fmt(None if not gaps else 100 * _median(gaps), '.2f')}% | "
            f"{_fmt(None if not gap_err else 100 * _median(gap_err), '.2f')}% | "
            f"{'; '.join(notes)[:300]} |"
        )
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--map", default="mfb-static")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--planners", default="all", help="comma-separated names, or 'all'")
    ap.add_argument("--budget", type=float, default=120.0,
                    help="wall seconds per planner row before it stops taking seeds")
    ap.add_argument("--no-same-budget", action="store_true")
    ap.add_argument("--params", default="{}", help="JSON: parameters per planner name")
    args = ap.parse_args(argv)
    try:
        params = json.loads(args.params)
        if not isinstance(params, dict):
            raise ValueError("expected an object of planner names")
        for name, values in params.items():
            get_planner(name).resolve_params(values)  # bad names and values fail here
    except (ValueError, KeyError) as exc:
        ap.error(f"--params: {exc}")

    scenario = get_map(args.map)
    names = list_planners() if args.planners == "all" else args.planners.split(",")
    for n in names:
        get_planner(n)  # unknown names fail here
    seeds = list(range(1, args.seeds + 1))
    load_start = load()
    note(f"{args.map}: {len(names)} planners x {len(seeds)} seeds, load {load_start}")

    rows: list[Row] = []
    for name in [n for n in names if n not in OMPL]:
        note(name)
        mine = params.get(name, {})
        label = name + (f" {json.dumps(mine, sort_keys=True)}" if mine else "")
        rows.append(run_row(Row(label, name, mine), scenario, seeds, args.budget))
    for name in [n for n in names if n in OMPL]:
        note(name)
        iterations = get_planner(name).defaults["iterations"]
        rows.append(run_row(Row(f"{name} ({iterations} iterations)", name, {}), scenario,
                            seeds, args.budget))
    swarm_medians = [statistics.median(r.cpu)
                     for r in rows if r.planner not in OMPL and r.outcomes]
    if not args.no_same_budget and swarm_medians:
        same = round(statistics.median(swarm_medians), 3)
        for name in [n for n in names if n in OMPL]:
            note(f"{name} at {same} s of CPU time")
            rows.append(run_row(Row(f"{name} ({same:g} s CPU)", name,
                                    {"budget": "cpu", "time": same}), scenario, seeds,
                                args.budget))

    optimum = rows[0].outcomes[0].optimum if rows and rows[0].outcomes else None
    print(f"Map `{args.map}`, exact optimum "
          f"{_fmt(optimum, '.4f')} m; seeds 1-{args.seeds} (run 0 of each); tree {tree()}; "
          f"machine {platform.machine()}, {os.cpu_count()} CPUs, Python "
          f"{platform.python_version()}, numpy {np.__version__}; load average (1/5/15 min) "
          f"at start {load_start}, at the end {load()}.\n")
    print(markdown(rows, optimum))


if __name__ == "__main__":
    main()
