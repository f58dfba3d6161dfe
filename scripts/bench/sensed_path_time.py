#!/usr/bin/env python3
"""Time of the exact shortest path in the sensed map, on the calls real runs make.

    PYTHONPATH=services .venv/bin/python scripts/bench/sensed_path_time.py \
        [--map mfb-static] [--planners ICOOT,MFB] [--seeds 1] [--repeat 5] [--passes 3]
        [--backend numba]

Runs each planner (numba backend) once per seed 1..N, records every call the aim makes to
:func:`swarmpath.world.optimum.shortest_path` (start, goal, known map, margin, box), then plays
those calls back ``--repeat`` times per pass and prints the least CPU time per call over
``--passes`` passes and a digest of the results (length and polyline of every call: equal
digests on two checkouts mean the same paths). Running it on two checkouts (PYTHONPATH) in turn
compares the search alone, without the noise of the rest of the run.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from plan_time import one_run

from swarmpath.planners import sensed_map
from swarmpath.world import get_map
from swarmpath.world.optimum import shortest_path


def record_calls(map_name: str, planners: Sequence[str], seeds: int) -> list[Any]:
    """The (args, kwargs) of every shortest-path call of the runs."""
    calls: list[Any] = []

    def recording(*args: Any, **kwargs: Any) -> Any:
        calls.append((args, kwargs))
        return shortest_path(*args, **kwargs)

    sensed_map.shortest_path = recording  # type: ignore[assignment]
    try:
        scenario = get_map(map_name)
        for planner in planners:
            for seed in range(1, seeds + 1):
                one_run(scenario, planner, seed, {"backend": "numba"})
    finally:
        sensed_map.shortest_path = shortest_path
    return calls


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--map", default="mfb-static")
    ap.add_argument("--planners", default="ICOOT,MFB")
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--passes", type=int, default=3)
    ap.add_argument("--backend", default="numba", choices=("numpy", "numba"),
                    help="shortest_path's backend for the playback (the runs record with numba)")
    args = ap.parse_args(argv)
    calls = [(a, {**k, "backend": args.backend})
             for a, k in record_calls(args.map, args.planners.split(","), args.seeds)]
    digest = hashlib.sha256()
    for a, k in calls:
        best = shortest_path(*a, **k)
        digest.update(repr(best.length).encode())
        digest.update(best.points.tobytes())
    least = float("inf")
    for _ in range(args.passes):
        started = time.process_time()
        for _ in range(args.repeat):
            for a, k in calls:
                shortest_path(*a, **k)
        least = min(least, (time.process_time() - started) / (args.repeat * len(calls)))
    print(f"{len(calls)} calls, {least * 1e3:.3f} ms CPU per call (least of {args.passes} "
          f"passes), digest {digest.hexdigest()[:12]}")


if __name__ == "__main__":
    main()
