#!/usr/bin/env python3
"""The contacts-by-cause table of docs/benchmarks.md from the run lines of ``maps.py --jsonl``.

    .venv/bin/python scripts/bench/contacts_table.py runs.jsonl [--before base.jsonl]

One row per map, one column per planner (in the order first seen); each cell: successes / runs,
robot-driven / obstacle-driven colliding steps, in how many runs. With ``--before``, each cell
shows the before file's numbers, then ``->`` and this file's (two trees side by side: run
``maps.py`` on each checkout with the same arguments). ``--gaps``: instead, the median gap to the
exact optimum over the successful runs (maps with an optimum only).
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections import defaultdict
from typing import Any


def load(path: str) -> dict[tuple[str, str], list[dict[str, Any]]]:
    runs: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    with open(path) as f:
        for line in f:
            if line.strip():
                r = json.loads(line)
                runs[(r["map"], r["planner"])].append(r)
    return runs


def planners0(runs: dict[tuple[str, str], list[dict[str, Any]]]) -> list[str]:
    return list(dict.fromkeys(p for _, p in runs))


def cell(rows: list[dict[str, Any]]) -> str:
    ok = sum(1 for r in rows if r["success"])
    robot = sum(r["robot"] for r in rows)
    obstacle = sum(r["obstacle"] for r in rows)
    touched = sum(1 for r in rows if r["collisions"])
    return f"{ok}/{len(rows)}, {robot} / {obstacle} in {touched}"


def gap_cell(rows: list[dict[str, Any]]) -> str:
    gaps = [100 * r["gap"] for r in rows if r["success"] and r["gap"] is not None]
    return f"{statistics.median(gaps):.2f} %" if gaps else "-"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs")
    ap.add_argument("--before", default=None)
    ap.add_argument("--gaps", action="store_true")
    a = ap.parse_args()
    fmt = gap_cell if a.gaps else cell
    after = load(a.runs)
    before = load(a.before) if a.before else None
    maps = list(dict.fromkeys(m for m, _ in after))
    if a.gaps:
        maps = [m for m in maps if any(r["gap"] is not None for p in planners0(after)
                                       for r in after.get((m, p), []))]
    planners = planners0(after)
    print("| preset | " + " | ".join(planners) + " |")
    print("| --- |" + " --- |" * len(planners))
    for m in maps:
        cells = []
        for p in planners:
            now = fmt(after.get((m, p), []))
            if before is not None:
                now = f"{fmt(before.get((m, p), []))} -> {now}"
            cells.append(now)
        print(f"| {m} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
