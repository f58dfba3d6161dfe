#!/usr/bin/env python3
"""Success, gap and contacts by cause of planners on maps, over seeds (run 0 of each seed).

    .venv/bin/python scripts/bench/maps.py --planners ICOOT,IHPO --maps all --seeds 1-5
        [--params JSON] [--knowledge map] [--jsonl FILE]

``--maps`` takes preset names (``all`` = every registered preset), scenario ``.json`` files,
nav2 map ``.yaml`` files and MovingAI ``.map`` files (their importers' default start and goal;
``X.map#i``: row i of ``X.map.scen``, its start and goal). ``--knowledge map`` sets the
parameter ``knowledge`` of every planner that has it (under ``--params``).
Each run is ``Episode(scenario, planner, seed=s, run=0, params).run()``, what ``swarmpath plan
--seed s --runs 1`` runs. Markdown on stdout, one row per planner x map: successes, collisions
split into robot-driven / obstacle-driven (``metrics.contact_causes``), median and worst gap to
the exact optimum over the successful runs, median planning wall time and CPU time per run.
``--jsonl`` also writes every run as a JSON line (for re-tabulating without re-running).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np


def load(name: str) -> Any:
    from swarmpath.world import get_map
    from swarmpath.world.importers import load_movingai_map, load_ros_map
    from swarmpath.world.scenario_io import load_scenario

    if name.endswith((".json", ".yml")) or (name.endswith(".yaml") and "image" not in
                                            Path(name).read_text()):
        return load_scenario(name)
    if name.endswith(".yaml"):
        return load_ros_map(name).scenario
    if ".map#" in name:
        from swarmpath.world.movingai import movingai_cell_center

        path, row = name.split("#")
        lines = Path(path + ".scen").read_text().splitlines()[1:]
        f = lines[int(row)].split("\t")
        h = int(f[3])
        start = movingai_cell_center(int(f[4]), int(f[5]), h)
        goal = movingai_cell_center(int(f[6]), int(f[7]), h)
        return load_movingai_map(path, start=start, goal=goal,
                                 name=f"{Path(path).stem}#{row}").scenario
    if name.endswith(".map"):
        return load_movingai_map(name).scenario
    return get_map(name)


def seeds_of(text: str) -> list[int]:
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--planners", default="ICOOT,IHPO,MFB,HPSO-MFB")
    ap.add_argument("--maps", default="all")
    ap.add_argument("--seeds", default="1-5")
    ap.add_argument("--params", default="{}")
    ap.add_argument("--knowledge", default=None)
    ap.add_argument("--jsonl", default=None)
    a = ap.parse_args()
    from swarmpath.planners import Episode, get_planner
    from swarmpath.world import list_maps

    maps = list_maps() if a.maps == "all" else a.maps.split(",")
    params = json.loads(a.params)
    if a.knowledge:
        for p in a.planners.split(","):
            if "knowledge" in get_planner(p).defaults:
                params[p] = {"knowledge": a.knowledge, **params.get(p, {})}
    sink = open(a.jsonl, "a") if a.jsonl else None
    print("| planner | map | success | collisions (robot / obstacle-driven) | median gap | "
          "worst gap | median planning s (wall / CPU) | failures by class |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for m in maps:
        scenario = load(m)
        label = Path(m).name if ("/" in m or "." in m) else m
        for p in a.planners.split(","):
            rows = []
            for s in seeds_of(a.seeds):
                cpu = time.process_time()
                o = Episode(scenario, p, seed=s, run=0, params=params.get(p)).run()
                rec = {"planner": p, "map": label, "seed": s, "success": o.success,
                       "reason": o.reason, "collisions": o.collisions,
                       "robot": o.robot_driven_contacts, "obstacle": o.obstacle_driven_contacts,
                       "length": o.length, "gap": o.gap, "seconds": o.seconds,
                       "failure_class": o.failure_class, "failure_detail": o.failure_detail,
                       "cpu": time.process_time() - cpu}
                rows.append(rec)
                if sink:
                    sink.write(json.dumps(rec) + "\n")
                    sink.flush()
                print(f"{p} {label} seed {s}: {o.reason}", file=sys.stderr)
            ok = [r for r in rows if r["success"]]
            gaps = [100 * r["gap"] for r in ok if r["gap"] is not None]
            med = f"{float(np.median(gaps)):.2f} %" if gaps else "-"
            worst = f"{max(gaps):.2f} %" if gaps else "-"
            coll = sum(r["collisions"] for r in rows)
            rob = sum(r["robot"] for r in rows)
            obs = sum(r["obstacle"] for r in rows)
            touched = sum(1 for r in rows if r["collisions"])
            wall = float(np.median([r["seconds"] for r in rows]))
            cpu_s = float(np.median([r["cpu"] for r in rows]))
            classes = Counter(r["failure_class"] for r in rows if not r["success"])
            why = ", ".join(f"{k} {v}" for k, v in sorted(classes.items())) or "-"
            print(f"| {p} | {label} | {len(ok)}/{len(rows)} | {coll} ({rob} / {obs}) in "
                  f"{touched} runs | {med} | {worst} | {wall:.2f} / {cpu_s:.2f} | {why} |",
                  flush=True)
    if sink:
        sink.close()


if __name__ == "__main__":
    main()
