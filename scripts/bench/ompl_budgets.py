#!/usr/bin/env python3
"""What the OMPL baselines' budgets buy: iterations done in ``--time`` seconds of wall clock, and
CPU time and length at the default iteration budgets, per map (docs/planners.md, "Budgets").

    .venv/bin/python scripts/bench/ompl_budgets.py [--time 1.0] [--seed 5]

Maps: mfb-static, icoot-map1, rfogwo-map3 (presets), tb3_sandbox and arena (tests/data). One
plan per planner and map (``plan_path``, as the episode's first decision calls it). Wall-clock
numbers depend on the load (printed); iteration counts at the default budget do not. Markdown on
stdout.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from planners import load, tree  # scripts/bench/planners.py

from swarmpath.planners import get_planner
from swarmpath.planners.ompl_baselines import plan_path
from swarmpath.world import get_map
from swarmpath.world.importers import load_movingai_map, load_ros_map

DATA = Path(__file__).resolve().parents[2] / "tests" / "data"
PLANNERS = {"RRTstar": "OMPL-RRTstar", "BITstar": "OMPL-BITstar"}


def maps() -> dict[str, object]:
    return {name: get_map(name) for name in ("mfb-static", "icoot-map1", "rfogwo-map3")} | {
        "tb3_sandbox": load_ros_map(DATA / "tb3_sandbox.yaml").scenario,
        "arena": load_movingai_map(DATA / "arena.map").scenario,
    }


def plan(scenario, algorithm: str, params: dict, seed: int) -> tuple[int, float, float | None]:
    """(iterations, CPU s, length or None) of one plan."""
    started = time.thread_time()
    r = plan_path(algorithm, scenario.static_obstacles(), np.array(scenario.start),
                  np.array(scenario.goal), scenario.robot.radius, scenario.size, params, seed)
    cpu = time.thread_time() - started
    length = None if r.path is None else float(np.sum(np.hypot(*np.diff(r.path, axis=0).T)))
    return r.iterations, cpu, length


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--time", type=float, default=1.0, help="wall-clock seconds per plan")
    ap.add_argument("--seed", type=int, default=5)
    args = ap.parse_args()
    start_load = load()
    wall_rows, default_rows = [], []
    for name, scenario in maps().items():
        wall, fixed = [name], [name]
        for algorithm, planner in PLANNERS.items():
            defaults = dict(get_planner(planner).defaults)
            n, cpu, _ = plan(scenario, algorithm,
                             {**defaults, "budget": "wall", "time": args.time}, args.seed)
            wall.append(f"{n:,} ({cpu:.2f})")
            n, cpu, length = plan(scenario, algorithm, defaults, args.seed)
            fixed.append(f"{cpu:.2f}, {'-' if length is None else f'{length:.3f}'}")
        wall_rows.append(wall)
        default_rows.append(fixed)
    print(f"Tree {tree()}; {os.cpu_count()} CPUs; seed {args.seed}; load average (1/5/15 min) "
          f"at start {start_load}, at the end {load()}.\n")
    print(f"| map | RRT* iterations in {args.time:g} s wall (CPU s) | BIT* iterations in "
          f"{args.time:g} s wall (CPU s) |\n| --- | --- | --- |")
    for r in wall_rows:
        print("| " + " | ".join(r) + " |")
    rrt = get_planner("OMPL-RRTstar").defaults["iterations"]
    bit = get_planner("OMPL-BITstar").defaults["iterations"]
    print(f"\n| map | RRT* {rrt:,}: CPU s, length (m) | BIT* {bit:,}: CPU s, length (m) |\n"
          "| --- | --- | --- |")
    for r in default_rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
