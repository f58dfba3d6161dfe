#!/usr/bin/env python3
"""The contacts-by-cause table of docs/benchmarks.md from the run lines of ``maps.py --jsonl``.

    .venv/bin/python scripts/bench/contacts_table.py runs.jsonl [--before base.jsonl]

One row per map, one column per planner (in the order first seen); each cell: successes / runs,
robot-driven / obstacle-driven colliding steps, in how many runs. With ``--before``, each cell
shows the before file's numbers, then ``->`` and this file's (two trees side by side: run
``maps.py`` on each checkout with the same arguments).
"""

from __future__ import annotations

import argparse
import json
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


def cell(rows: list[dict[str, Any]]) -> str:
    ok = sum(1 for r in rows if r["success"])
    robot = sum(r["robot"] for r in rows)
    obstacle = sum(r["obstacle"] for r in rows)
    touched = sum(1 for r in rows if r["collisions"])
    return f"{ok}/{len(rows)}, {robot} / {obstacle} in {touched}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs")
    ap.add_argument("--before", default=None)
    a = ap.parse_args()
    after = load(a.runs)
    before = load(a.before) if a.before else None
    maps = list(dict.fromkeys(m for m, _ in after))
    planners = list(dict.fromkeys(p for _, p in after))
    print("| preset | " + " | ".join(planners) + " |")
    print("| --- |" + " --- |" * len(planners))
    for m in maps:
        cells = []
        for p in planners:
            now = cell(after.get((m, p), []))
            if before is not None:
                now = f"{cell(before.get((m, p), []))} -> {now}"
            cells.append(now)
        print(f"| {m} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
