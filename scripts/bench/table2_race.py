"""The ICOOT paper's Table 2 raced and judged (docs/benchmarks.md, Racing): its job spec, the
race replayed over a full study's runs with the product's code, a full study's documents and
verdicts, and the agreement of a race with them. Shared by ``racing.py``, ``racing_looks.py``
and ``racing_oracle.py``; no command of its own."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from service import TABLE2_ALGORITHMS, TABLE2_FUNCTIONS

from swarmpath.evidence import report
from swarmpath.evidence.race_report import study_race
from swarmpath.evidence.racing import CLOSING, RaceSettings, race_block


def table2_spec(max_runs: int, margin: float, seed: int, backend: str,
                final_test: str = CLOSING[0]) -> dict[str, Any]:
    return {"kind": "benchmark", "algorithms": TABLE2_ALGORITHMS, "functions": TABLE2_FUNCTIONS,
            "dims": [30], "agents": 30, "iterations": 500, "runs": max_runs, "seed": seed,
            "backend": backend,
            "racing": {"min_runs": 10, "batch": 10, "alpha": 0.05, "margin": margin,
                       "final_test": final_test}}


def replayed_race(values: dict[tuple[str, str], list[float]], settings: RaceSettings
                  ) -> dict[str, Any]:
    """The race of Table 2 replayed over the full study's runs (run r of a cell is the same run
    raced or not, and a raced job's race is this replay: tests/test_service_racing.py,
    tests/test_bench_race.py), as ``GET /jobs/{id}/race`` shows a job's."""
    comparisons = len(TABLE2_FUNCTIONS) * (len(TABLE2_ALGORITHMS) - 1)
    blocks = []
    for f in TABLE2_FUNCTIONS:
        per = {a: np.where(np.isnan(v := np.asarray(values[(a, f)], dtype=float)), np.inf, v)
               for a in TABLE2_ALGORITHMS}
        blocks.append(({"function": f, "dim": 30},
                       race_block(per, TABLE2_ALGORITHMS, settings, comparisons),
                       list(enumerate(TABLE2_ALGORITHMS))))
    return study_race(settings, comparisons, blocks)


def race_decisions(race: dict[str, Any]) -> list[Any]:
    """A race's allowances, stops and duels per function (what a replay must reproduce)."""
    return [(b["block"]["function"],
             sorted((c["algorithm"], c["runs"], c["reason"], c["stopped_round"])
                    for c in b["cells"]), b["duels"]) for b in race["blocks"]]


def agreement(race: dict[str, Any], values: dict[tuple[str, str], list[float]],
              max_runs: int) -> None:
    """Runs used, and every raced +/=/- against the full study's (rank-sum, Holm over the
    table, alpha 0.05, what ``swarmpath bench`` prints), the disagreements listed."""
    samples = {(a, f, 30): values[(a, f)][:max_runs] for a in TABLE2_ALGORITHMS
               for f in TABLE2_FUNCTIONS}
    tests = report.benchmark_tests(samples, TABLE2_ALGORITHMS, None)
    cells = [c for b in race["blocks"] for c in b["cells"]]
    used = sum(c["runs"] for c in cells)
    full = len(cells) * max_runs
    s = race["settings"]
    decided = sum(c["reason"] == "decided" for c in cells)
    print(f"race: alpha {s['alpha']} over {race['comparisons']} comparisons, min_runs "
          f"{s['min_runs']}, batch {s['batch']}, margin {s['margin']}, max_runs {max_runs}: "
          f"**{used} runs of {full} ({full / used:.1f}x fewer)**, {decided}/{len(cells)} cells "
          f"decided")
    agree = n = 0
    rows, kinds = [], {"different": 0, "equivalent": 0, "futile": 0, "open": 0}
    for b in race["blocks"]:
        f = b["block"]["function"]
        runs = {c["algorithm"]: c["runs"] for c in b["cells"]}
        for d in b["duels"]:
            t = tests.comparison.get((f, 30), d["a"])
            full_marker = t.marker if t is not None else None
            n += 1
            kinds[d["decision"]] += 1
            agree += d["marker"] == full_marker
            if d["marker"] != full_marker:
                interval = ("" if d["theta"] is None else
                            f", theta {d['theta']:.3f} [{d['low']:.3f}, {d['high']:.3f}]")
                rows.append(f"| {f} | {d['a']} | {d['marker']} ({d['decision']}, "
                            f"{runs[d['a']]} runs{interval}) | {full_marker} (A12 "
                            f"{t.a12 if t is not None else float('nan'):.3f}, p_holm "
                            f"{t.p_holm if t is not None else float('nan'):.2g}) |")
    final = sum(d["final"] for b in race["blocks"] for d in b["duels"])
    print(f"decisions: {kinds['different']} different ({final} by the closing look "
          f"{s.get('final_test')}), {kinds['equivalent']} equivalent, {kinds['futile']} "
          f"stopped as futile, {kinds['open']} open at max_runs; **verdicts agreeing with the "
          f"full {max_runs}-run study: {agree}/{n} ({100 * agree / n:.1f} %)**\n")
    per_function = " | ".join(f"{b['block']['function']} {sum(c['runs'] for c in b['cells'])}"
                              for b in race["blocks"])
    print(f"runs per function (6 cells): {per_function}\n")
    if rows:
        print("| function | algorithm vs ICOOT | raced | full study |\n| --- | --- | --- | --- |")
        print("\n".join(rows))
    print()


def bench_values(doc: dict[str, Any]) -> dict[tuple[str, str], list[float]]:
    """Each cell's best values of a ``swarmpath bench --json`` document (null: NaN)."""
    return {(c["algorithm"], c["function"]): [math.nan if v is None else float(v)
                                              for v in c["best_fitness"]] for c in doc["cells"]}


def save_full(path: Path, spec: dict[str, Any], values: dict[tuple[str, str], list[float]],
               seconds: float) -> None:
    """The full job's runs as the cells of a ``swarmpath bench --json`` document (what
    ``--full`` and ``seeds`` read)."""
    from swarmpath import __version__

    settings = {k: v for k, v in spec.items() if k not in ("kind", "racing")}
    cells = [{"algorithm": a, "function": f, "dim": 30,
              "best_fitness": [None if math.isnan(v) else v for v in values[(a, f)]]}
             for f in TABLE2_FUNCTIONS for a in TABLE2_ALGORITHMS]
    path.write_text(json.dumps({"swarmpath": __version__, "seconds": seconds,
                                "settings": settings, "cells": cells}))


def full_verdicts(values: dict[tuple[str, str], list[float]], max_runs: int) -> dict[Any, Any]:
    """(function, algorithm) -> the full study's test against ICOOT (rank-sum, Holm over the
    table, alpha 0.05: what ``swarmpath bench`` prints)."""
    samples = {(a, f, 30): values[(a, f)][:max_runs] for a in TABLE2_ALGORITHMS
               for f in TABLE2_FUNCTIONS}
    tests = report.benchmark_tests(samples, TABLE2_ALGORITHMS, None)
    return {(f, a): tests.comparison.get((f, 30), a) for f in TABLE2_FUNCTIONS
            for a in TABLE2_ALGORITHMS[:-1]}


def spec_settings(max_runs: int, margin: float, final_test: str, alpha: float = 0.05
                   ) -> RaceSettings:
    """The race a job spec's ``racing`` of :func:`table2_spec` runs with: the service's own path
    (``RacingSpec.settings``), so the product's default design."""
    from swarmpath.service.racing import RacingSpec

    return RacingSpec(min_runs=10, batch=10, alpha=alpha, margin=margin,
                      final_test=final_test).settings(max_runs)
