#!/usr/bin/env python3
"""Success, gap and contacts by cause of planners on maps, over seeds (run 0 of each seed).

    .venv/bin/python scripts/bench/maps.py --planners ICOOT,IHPO --maps all --seeds 1-5
        [--params JSON] [--knowledge map] [--jsonl FILE [--resume]] [--by-map]
    .venv/bin/python scripts/bench/maps.py --table FILE.jsonl[,FILE2.jsonl] [--by-map | --matrix |
        --buckets]
    .venv/bin/python scripts/bench/maps.py --check-scen tests/data/maze-32-32-4-even-10.scen#0-199

``--maps`` takes preset names (``all`` = every registered preset), scenario ``.json`` files,
nav2 map ``.yaml`` files and MovingAI ``.map`` files (their importers' default start and goal;
``X.map#i``: row i of ``X.map.scen``, its start and goal; ``X.map#a-b``: rows a to b;
``X.map#a-b/s``: every s-th of them; ``X.map#bN``: the first N rows of every bucket, in file
order). ``F.scen#...`` (same row choices) takes the rows of a scenario file of the MAPF benchmark
(``random-32-32-20-even-10.scen``), whose map is the file its rows name, beside it.
``--knowledge map`` sets the parameter ``knowledge`` of every planner that has it (under
``--params``).
``--check-scen NAMES`` (rows chosen as in ``--maps``) runs no planner: per ``.scen`` file, how
many rows' own optimal length equals an octile shortest path computed here on the map's grid
(8-connected, diagonal sqrt 2, no corner cutting: scipy's Dijkstra), and how the exact optimum
of the disk robot (any angle, what the gap is measured against) compares with it.
Each run is ``Episode(scenario, planner, seed=s, run=0, params).run()``, what ``swarmpath plan
--seed s --runs 1`` runs. Markdown on stdout, one row per planner x map: successes, collisions
split into robot-driven / obstacle-driven (``metrics.contact_causes``), median and worst gap to
the exact optimum over the successful runs, median planning wall time and CPU time per run.
The exact optimum has no wall-clock budget unless ``--optimum-budget S`` (the episode's
default of 30 s gave up on Berlin_1_256 at load 20, and the time limit of a run follows it).
``--by-map`` puts the rows of one ``.scen`` together (one table row per planner x map file);
``--matrix`` (with ``--table``) prints planners x map files, each cell successes / runs, median /
worst gap and the failures by class; ``--buckets`` one table per ``.scen`` file, planners x
MovingAI buckets.
``--jsonl`` also writes every run as a JSON line (for re-tabulating without re-running:
``--table``); with ``--resume`` the runs already in that file (same planner, map, seed and
parameters) are not run again but are counted in the table, so a stopped run goes on where it
stopped.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import re
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

_BASES: dict[str, Any] = {}  # a .map imported once, its .scen rows are copies with new ends
_ROWS: dict[str, list[Any]] = {}  # a .scen parsed once
_SCEN_NAME = r"(.+\.(?:map|scen))#(?:b(\d+)|(\d+)(?:-(\d+)(?:/(\d+))?)?)"


def scen_files(path: str) -> tuple[str, str]:
    """(the .scen, the .map) of ``X.map`` (its ``X.map.scen``) or of a MAPF benchmark ``F.scen``
    (the map its first row names, in the same directory)."""
    if not path.endswith(".scen"):
        return path + ".scen", path
    lines = Path(path).read_text().splitlines()
    first = lines[1].split("\t") if len(lines) > 1 else []
    if len(first) < 9:
        raise SystemExit(f"{path}: no scenario row after the 'version' line")
    return path, str(Path(path).parent / first[1])


def scen_table(path: str) -> list[Any]:
    """The rows of the .scen of ``path`` (:func:`swarmpath.world.movingai_scen.parse_scen`)."""
    from swarmpath.world.movingai_scen import parse_scen

    scen, _ = scen_files(path)
    if scen not in _ROWS:
        _ROWS[scen] = parse_scen(Path(scen).read_text(), scen)
    return _ROWS[scen]


def scen_rows(name: str) -> list[str]:
    """``X#i``, ``X#a-b``, ``X#a-b/s`` or ``X#bN`` (X a ``.map`` or ``.scen``) -> one ``X#i`` per
    row; else [name]."""
    from swarmpath.world.movingai_scen import bucket_counts, choose_rows

    m = re.fullmatch(_SCEN_NAME, name)
    if not m or (m.group(2) is None and m.group(4) is None):
        return [name]
    if m.group(2) is not None:  # the first N rows of every bucket
        rows = scen_table(m.group(1))
        chosen = choose_rows(rows, buckets=list(bucket_counts(rows)), per_bucket=int(m.group(2)))
        return [f"{m.group(1)}#{r.row}" for r in chosen]
    a, b, step = int(m.group(3)), int(m.group(4)), int(m.group(5) or 1)
    return [f"{m.group(1)}#{i}" for i in range(a, b + 1, step)]


def scen_row(path: str, row: int) -> tuple[Any, Any]:
    """The ``.scen`` row (:class:`~swarmpath.world.movingai_scen.ScenRow`) and the map with the
    row's start and goal."""
    from swarmpath.world.importers import load_movingai_map
    from swarmpath.world.movingai import movingai_cell_center

    r = scen_table(path)[row]
    _, grid = scen_files(path)
    if grid not in _BASES:
        _BASES[grid] = load_movingai_map(grid).scenario
    base = _BASES[grid]
    height = round(base.size[1])
    scenario = dataclasses.replace(
        base, name=f"{Path(path).stem}#{row}",
        start=movingai_cell_center(*r.start, height), goal=movingai_cell_center(*r.goal, height))
    problems = [m for k, m in scenario.problems() if k in ("start", "goal")]
    if problems:
        raise SystemExit(f"{path}#{row}: {'; '.join(problems)}")
    return r, scenario


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
    if ".map#" in name or ".scen#" in name:
        path, row = name.split("#")
        r, scenario = scen_row(path, int(row))
        return scenario, {"bucket": r.bucket, "octile": r.octile}
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


def octile_lengths(blocked: np.ndarray, pairs: list[tuple[tuple[int, int], tuple[int, int]]]
                   ) -> list[float]:
    """Shortest 8-connected path lengths between cells (x, y from the top left) of a blocked mask
    (row 0 = the top line): a straight step costs 1, a diagonal one sqrt 2 and needs both
    cells beside it free (MovingAI's rule, Sturtevant 2012). Dijkstra from each start (scipy)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra

    h, w = blocked.shape
    free = ~blocked
    index = np.arange(h * w).reshape(h, w)
    tails, heads, costs = [], [], []
    for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
        x0, x1 = max(0, -dx), w - max(0, dx)
        ok = free[: h - dy, x0:x1] & free[dy:, x0 + dx:x1 + dx]
        if dy and dx:  # no corner cutting: the two cells the diagonal passes between are free
            ok &= free[: h - dy, x0 + dx:x1 + dx] & free[dy:, x0:x1]
        tails.append(index[: h - dy, x0:x1][ok])
        heads.append(index[dy:, x0 + dx:x1 + dx][ok])
        costs.append(np.full(int(ok.sum()), np.sqrt(2.0) if dy and dx else 1.0))
    graph = csr_matrix((np.concatenate(costs), (np.concatenate(tails), np.concatenate(heads))),
                       shape=(h * w, h * w))
    starts = sorted({s for s, _ in pairs})
    dist = dijkstra(graph, directed=False, indices=[index[y, x] for x, y in starts])
    at = {s: k for k, s in enumerate(starts)}
    return [float(dist[at[s], index[g[1], g[0]]]) for s, g in pairs]


def check_scen(names: list[str], exact: bool = True) -> list[dict[str, Any]]:
    """One row per .scen file: its rows' own optimal lengths against :func:`octile_lengths` on
    the map, and (``exact``) the disk robot's exact optimum against the octile length."""
    from swarmpath.planners.episode import optimum_of
    from swarmpath.world.movingai import parse_movingai_map

    by_file: dict[str, list[int]] = {}
    for name in names:
        for item in scen_rows(name):
            path, _, row = item.partition("#")
            if not row:
                raise SystemExit(f"{name}: choose .scen rows (X.map#... or F.scen#...)")
            by_file.setdefault(path, []).append(int(row))
    out = []
    for path, ids in by_file.items():
        rows = [scen_table(path)[i] for i in ids]
        _, grid = scen_files(path)
        blocked = parse_movingai_map(Path(grid).read_text(), grid)
        mine = octile_lengths(blocked, [(r.start, r.goal) for r in rows])
        diff = [abs(a - r.octile) for a, r in zip(mine, rows, strict=True)]
        entry: dict[str, Any] = {
            "file": Path(path).name if path.endswith(".scen") else Path(path).name + ".scen",
            "rows": len(rows), "buckets": len({r.bucket for r in rows}),
            # to the printed digits: the DAO files (arena) print 6 significant ones
            "octile_agree": sum(d <= 5e-6 * max(1.0, r.octile)
                                for d, r in zip(diff, rows, strict=True)),
            "octile_max_diff": max(diff), "bucket_agree": sum(
                r.bucket == int(r.octile // 4) for r in rows)}
        if exact:
            ratios, above_line = [], 0
            for i, r in zip(ids, rows, strict=True):
                length, why = optimum_of(scen_row(path, i)[1], None)
                if length is None:
                    raise SystemExit(f"{path}#{i}: no exact optimum: {why}")
                ratios.append(length / r.octile if r.octile else 1.0)
                above_line += length >= math.dist(r.start, r.goal) - 1e-9
            entry.update(exact_le_octile=sum(q <= 1 + 1e-9 for q in ratios),
                         exact_ge_line=above_line,
                         ratio_min=min(ratios), ratio_median=float(np.median(ratios)),
                         ratio_max=max(ratios))
        out.append(entry)
    return out


def print_check(rows: list[dict[str, Any]]) -> None:
    print("| .scen | rows (buckets) | own optimum = octile here | largest difference | "
          "bucket = floor(optimum / 4) | straight line <= exact optimum | exact optimum <= "
          "octile | exact / octile (min / median / max) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for e in rows:
        ex = (f"{e['exact_ge_line']}/{e['rows']} | {e['exact_le_octile']}/{e['rows']} | "
              f"{e['ratio_min']:.4f} / {e['ratio_median']:.4f} / {e['ratio_max']:.4f}"
              if "ratio_min" in e else "- | - | -")
        print(f"| {e['file']} | {e['rows']} ({e['buckets']}) | {e['octile_agree']}/{e['rows']} | "
              f"{e['octile_max_diff']:.1e} | {e['bucket_agree']}/{e['rows']} | {ex} |")


def buckets(records: list[dict[str, Any]]) -> None:
    """Per map file (the rows of one .scen), planners x MovingAI buckets: successes / runs and
    the median gap (:func:`swarmpath.evidence.buckets.bucket_rows`)."""
    from swarmpath.evidence.buckets import bucket_rows

    files: dict[str, list[dict[str, Any]]] = {}
    for r in records:
        if r.get("bucket") is not None:
            given = r.get("params") or {}
            p = r["planner"] + (f" ({given['knowledge']})" if "knowledge" in given else "")
            files.setdefault(r["map"].split("#")[0], []).append({**r, "planner": p})
    for name, runs in files.items():
        rows = bucket_rows(runs, {r["map"]: r["bucket"] for r in runs})
        columns = sorted({row["bucket"] for row in rows})
        print(f"\n{name}, by bucket (successes / runs, median gap):\n")
        print("| planner | " + " | ".join(f"b{b}" for b in columns) + " |")
        print("| --- |" + " --- |" * len(columns))
        cells: dict[str, dict[int, str]] = {}
        for row in rows:
            gap = row["gap_median"]
            cells.setdefault(row["planner"], {})[row["bucket"]] = (
                f"{row['successes']}/{row['runs']}"
                + (f", {100 * gap:.2f} %" if gap is not None else ""))
        for p, by in cells.items():
            print(f"| {p} | " + " | ".join(by.get(b, "-") for b in columns) + " |")


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
    ap.add_argument("--buckets", action="store_true",
                    help="with --table: per .scen file, planners x buckets")
    ap.add_argument("--check-scen", default=None, metavar="NAMES",
                    help="no runs: the .scen rows' optimal lengths against an octile search "
                         "and the exact optimum (comma-separated X.map#... / F.scen#...)")
    ap.add_argument("--no-exact", action="store_true",
                    help="with --check-scen: the octile check only")
    a = ap.parse_args()
    if a.check_scen:
        print_check(check_scen(a.check_scen.split(","), exact=not a.no_exact))
        return
    if a.table:
        records = read_jsonl(a.table)
        if a.buckets:
            buckets(records)
        elif a.matrix:
            matrix(records)
        else:
            table(records, a.by_map)
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
