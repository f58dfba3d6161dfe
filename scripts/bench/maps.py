#!/usr/bin/env python3
"""Success, gap and contacts by cause of planners on maps, over seeds (run 0 of each seed).

    .venv/bin/python scripts/bench/maps.py --planners ICOOT,IHPO --maps all --seeds 1-5
        [--params JSON] [--knowledge map] [--jsonl FILE [--resume]] [--by-map]
    .venv/bin/python scripts/bench/maps.py --table FILE.jsonl[,FILE2.jsonl] [--by-map | --matrix]

``--maps`` takes preset names (``all`` = every registered preset), scenario ``.json`` files,
nav2 map ``.yaml`` files and MovingAI ``.map`` files (their importers' default start and goal;
``X.map#i``: row i of ``X.map.scen``, its start and goal; ``X.map#a-b``: rows a to b;
``X.map#a-b/s``: every s-th of them). ``--knowledge map`` sets the parameter ``knowledge`` of
every planner that has it (under ``--params``).
Each run is ``Episode(scenario, planner, seed=s, run=0, params).run()``, what ``swarmpath plan
--seed s --runs 1`` runs. Markdown on stdout, one row per planner x map: successes, collisions
split into robot-driven / obstacle-driven (``metrics.contact_causes``), median and worst gap to
the exact optimum over the successful runs, median planning wall time and CPU time per run.
The exact optimum has no wall-clock budget unless ``--optimum-budget S`` (the episode's
default of 30 s gave up on Berlin_1_256 at load 20, and the time limit of a run follows it).
``--by-map`` puts the rows of one ``.scen`` together (one table row per planner x map file);
``--matrix`` (with ``--table``) prints planners x map files, each cell successes / runs, median /
worst gap and the failures by class.
``--jsonl`` also writes every run as a JSON line (for re-tabulating without re-running:
``--table``); with ``--resume`` the runs already in that file (same planner, map, seed and
parameters) are not run again but are counted in the table, so a stopped run goes on where it
stopped.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

_BASES: dict[str, Any] = {}  # a .map imported once, its .scen rows are copies with new ends


def scen_rows(name: str) -> list[str]:
    """``X.map#i``, ``X.map#a-b`` or ``X.map#a-b/s`` -> one ``X.map#i`` per row; else [name]."""
    m = re.fullmatch(r"(.+\.map)#(\d+)(?:-(\d+)(?:/(\d+))?)?", name)
    if not m or m.group(3) is None:
        return [name]
    a, b, step = int(m.group(2)), int(m.group(3)), int(m.group(4) or 1)
    return [f"{m.group(1)}#{i}" for i in range(a, b + 1, step)]


def scen_row(path: str, row: int) -> tuple[list[str], Any]:
    """The ``.scen`` row's columns and the map with the row's start and goal."""
    from swarmpath.world.importers import load_movingai_map
    from swarmpath.world.movingai import movingai_cell_center

    lines = Path(path + ".scen").read_text().splitlines()[1:]
    f = lines[row].split("\t")
    h = int(f[3])
    if path not in _BASES:
        _BASES[path] = load_movingai_map(path).scenario
    scenario = dataclasses.replace(
        _BASES[path], name=f"{Path(path).stem}#{row}",
        start=movingai_cell_center(int(f[4]), int(f[5]), h),
        goal=movingai_cell_center(int(f[6]), int(f[7]), h))
    problems = [m for k, m in scenario.problems() if k in ("start", "goal")]
    if problems:
        raise SystemExit(f"{path}#{row}: {'; '.join(problems)}")
    return f, scenario


def load(name: str) -> tuple[Any, dict[str, Any]]:
    """The scenario and what the table keeps about it (the .scen bucket and octile length)."""
    from swarmpath.world import get_map
    from swarmpath.world.importers import load_movingai_map, load_ros_map
    from swarmpath.world.scenario_io import load_scenario

    if name.endswith((".json", ".yml")) or (name.endswith(".yaml") and "image" not in
                                            Path(name).read_text()):
        return load_scenario(name), {}
    if name.endswith(".yaml"):
        return load_ros_map(name).scenario, {}
    if ".map#" in name:
        path, row = name.split("#")
        f, scenario = scen_row(path, int(row))
        return scenario, {"bucket": int(f[0]), "octile": float(f[8])}
    if name.endswith(".map"):
        return load_movingai_map(name).scenario, {}
    return get_map(name), {}


def seeds_of(text: str) -> list[int]:
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def label_of(m: str) -> str:
    return Path(m).name if ("/" in m or "." in m) else m


def key_of(rec: dict[str, Any]) -> tuple[Any, ...]:
    return (rec["planner"], rec["map"], rec["seed"], json.dumps(rec.get("params"),
                                                                sort_keys=True))


def table(records: list[dict[str, Any]], by_map: bool) -> None:
    print("| planner | map | success | collisions (robot / obstacle-driven) | median gap | "
          "worst gap | median planning s (wall / CPU) | failures by class |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in records:  # runs with other parameters (knowledge) are rows of their own
        label = r["map"].split("#")[0] if by_map else r["map"]
        given = r.get("params") or {}
        p = r["planner"] + (f" ({given['knowledge']})" if "knowledge" in given else "")
        groups.setdefault((label, p), []).append(r)
    for (label, p), rows in groups.items():
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
        scen = len({r["map"] for r in rows})
        name = f"{label} ({scen} rows)" if by_map and scen > 1 else label
        print(f"| {p} | {name} | {len(ok)}/{len(rows)} | {coll} ({rob} / {obs}) in "
              f"{touched} runs | {med} | {worst} | {wall:.2f} / {cpu_s:.2f} | {why} |",
              flush=True)


def matrix(records: list[dict[str, Any]]) -> None:
    """One row per planner (and knowledge), one column per map file: successes / runs, median /
    worst gap, the failures by class."""
    cells: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for r in records:
        given = r.get("params") or {}
        p = r["planner"] + (f" ({given['knowledge']})" if "knowledge" in given else "")
        cells.setdefault(p, {}).setdefault(r["map"].split("#")[0], []).append(r)
    columns = list(dict.fromkeys(m for row in cells.values() for m in row))
    print("| planner | " + " | ".join(columns) + " |")
    print("| --- |" + " --- |" * len(columns))
    for p, row in cells.items():
        out = []
        for m in columns:
            rows = row.get(m, [])
            gaps = [100 * r["gap"] for r in rows if r["success"] and r["gap"] is not None]
            text = f"{sum(r['success'] for r in rows)}/{len(rows)}" if rows else "-"
            if gaps:
                text += f", {float(np.median(gaps)):.2f} / {max(gaps):.2f} %"
            classes = Counter(r["failure_class"] for r in rows if not r["success"])
            text += "".join(f", {k} {v}" for k, v in sorted(classes.items()))
            out.append(text)
        print(f"| {p} | " + " | ".join(out) + " |")


def read_jsonl(paths: str) -> list[dict[str, Any]]:
    out = []
    for p in paths.split(","):
        if Path(p).exists():
            out += [json.loads(line) for line in Path(p).read_text().splitlines()
                    if line.strip()]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--planners", default="ICOOT,IHPO,MFB,HPSO-MFB")
    ap.add_argument("--maps", default="all")
    ap.add_argument("--seeds", default="1-5")
    ap.add_argument("--params", default="{}")
    ap.add_argument("--knowledge", default=None)
    ap.add_argument("--jsonl", default=None)
    ap.add_argument("--optimum-budget", type=float, default=None, metavar="S",
                    help="wall-clock seconds for each map's exact optimum (default: none, so "
                         "neither the gap nor the episode's time limit depends on the load)")
    ap.add_argument("--resume", action="store_true",
                    help="skip the runs already in --jsonl (and count them)")
    ap.add_argument("--table", default=None, metavar="FILES",
                    help="only tabulate these --jsonl files (comma-separated)")
    ap.add_argument("--by-map", action="store_true",
                    help="one table row per planner x map file (its .scen rows together)")
    ap.add_argument("--matrix", action="store_true",
                    help="with --table: planners x map files, success and median / worst gap")
    a = ap.parse_args()
    if a.table:
        (matrix if a.matrix else lambda rs: table(rs, a.by_map))(read_jsonl(a.table))
        return
    if a.resume and not a.jsonl:
        ap.error("--resume needs --jsonl FILE")
    from swarmpath.planners import Episode, get_planner
    from swarmpath.world import list_maps

    maps = list_maps() if a.maps == "all" else [
        r for m in a.maps.split(",") for r in scen_rows(m)]
    params = json.loads(a.params)
    if a.knowledge:
        for p in a.planners.split(","):
            if "knowledge" in get_planner(p).defaults:
                params[p] = {"knowledge": a.knowledge, **params.get(p, {})}
    done = {key_of(r): r for r in read_jsonl(a.jsonl)} if a.resume else {}
    sink = open(a.jsonl, "a") if a.jsonl else None
    records = []
    for m in maps:
        label = label_of(m)
        todo = [(p, s) for p in a.planners.split(",") for s in seeds_of(a.seeds)]
        if all(key_of({"planner": p, "map": label, "seed": s, "params": params.get(p)}) in done
               for p, s in todo):
            records += [done[key_of({"planner": p, "map": label, "seed": s,
                                     "params": params.get(p)})] for p, s in todo]
            continue
        scenario, about = load(m)
        for p, s in todo:
            key = key_of({"planner": p, "map": label, "seed": s, "params": params.get(p)})
            if key in done:
                records.append(done[key])
                continue
            cpu = time.process_time()
            o = Episode(scenario, p, seed=s, run=0, params=params.get(p),
                        optimum_budget=a.optimum_budget).run()
            rec = {"planner": p, "map": label, "seed": s, "params": params.get(p), **about,
                   "success": o.success, "reason": o.reason, "collisions": o.collisions,
                   "robot": o.robot_driven_contacts, "obstacle": o.obstacle_driven_contacts,
                   "length": o.length, "optimum": o.optimum, "gap": o.gap,
                   "seconds": o.seconds, "failure_class": o.failure_class,
                   "failure_detail": o.failure_detail, "cpu": time.process_time() - cpu}
            records.append(rec)
            if sink:
                sink.write(json.dumps(rec) + "\n")
                sink.flush()
            print(f"{p} {label} seed {s}: {o.reason}", file=sys.stderr, flush=True)
    if sink:
        sink.close()
    table(records, a.by_map)


if __name__ == "__main__":
    main()
