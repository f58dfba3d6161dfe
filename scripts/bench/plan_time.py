#!/usr/bin/env python3
"""Planning time per run of the swarm planners on one map, and a digest of every run.

    PYTHONPATH=services .venv/bin/python scripts/bench/plan_time.py \
        [--map mfb-static] [--planners ICOOT,IHPO,MFB,HPSO-MFB] [--seeds 10] [--repeat 1]
        [--params '{"backend": "numba"}']

Each planner runs once per seed 1..N (run 0 of each seed) through :class:`Episode`, as
``swarmpath plan`` does. Per run: the CPU time of the planner's decisions (process time, less
distorted by other jobs on a shared machine than the wall time ``seconds`` the episode reports,
also shown) and a digest (SHA-256 of the run's outcome without its timing: path, metrics).
``--repeat K`` runs each episode K times and keeps its least CPU time (the digests must agree).
Markdown on stdout: median and p90 per planner; ``--runs`` adds one line per run. Running the
script on two checkouts (PYTHONPATH) compares their speed and shows whether the runs are the same.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np
from decide_time import timed_episode  # scripts/bench/decide_time.py

from swarmpath.path_metrics import PATH_METRICS
from swarmpath.planners.episode import TIMING_FIELDS
from swarmpath.world import get_map

SWARM = ("ICOOT", "IHPO", "MFB", "HPSO-MFB")


def one_run(scenario: Any, planner: str, seed: int,
            params: dict[str, Any] | None = None) -> tuple[float, float, str, Any]:
    """(CPU s, wall s of the decisions, digest, outcome) of run 0 of ``seed``."""
    cpu, out = timed_episode(scenario, planner, seed, params)
    data = out.to_dict()
    # the digest covers what the run did: not the host's timings, nor the metrics derived
    # from the path (so digests stay comparable with those recorded before they existed)
    for key in (*TIMING_FIELDS, *PATH_METRICS, "frame_origin"):
        data.pop(key)
    digest = hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]
    return cpu, out.seconds, digest, out


def p90(values: Sequence[float]) -> float:
    return float(np.percentile(values, 90))


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--map", default="mfb-static")
    ap.add_argument("--planners", default=",".join(SWARM))
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--runs", action="store_true", help="one line per run too")
    ap.add_argument("--params", default=None,
                    help="parameters for every planner (JSON), e.g. '{\"backend\": \"numba\"}'")
    args = ap.parse_args(argv)
    scenario = get_map(args.map)
    params = json.loads(args.params) if args.params else None
    rows = ["| planner | runs | median CPU s | p90 CPU s | median wall s | digest of the runs |",
            "| --- | ---: | ---: | ---: | ---: | --- |"]
    lines = []
    for planner in args.planners.split(","):
        cpu, wall, digests = [], [], []
        for seed in range(1, args.seeds + 1):
            best = None
            for _ in range(max(1, args.repeat)):
                c, w, d, out = one_run(scenario, planner, seed, params)
                if best is not None and d != best[2]:
                    raise SystemExit(f"{planner} seed {seed}: a repeat gave another run")
                best = (c, w, d, out) if best is None or c < best[0] else best
            assert best is not None
            cpu.append(best[0])
            wall.append(best[1])
            digests.append(best[2])
            lines.append(f"{planner} seed {seed}: CPU {best[0]:.3f} s, wall {best[1]:.3f} s, "
                         f"{best[3].steps} steps, length {best[3].length:.4f}, {best[2]}")
            print(lines[-1], file=sys.stderr, flush=True)
        whole = hashlib.sha256("".join(digests).encode()).hexdigest()[:12]
        rows.append(f"| {planner} | {len(cpu)} | {statistics.median(cpu):.3f} | {p90(cpu):.3f} | "
                    f"{statistics.median(wall):.3f} | {whole} |")
    one, five, fifteen = os.getloadavg()
    print("\n".join(rows))
    print(f"\nload average at the end: {one:.1f} / {five:.1f} / {fifteen:.1f}")
    if args.runs:
        print("\n" + "\n".join(lines))


if __name__ == "__main__":
    main()
