#!/usr/bin/env python3
"""How few runs could ANY procedure spend on the ICOOT paper's Table 2 and still give the full
study's verdicts? An oracle that knows the full 1000-run study (docs/benchmarks.md, Racing).

    .venv/bin/python scripts/bench/racing_oracle.py --full full.json [full2.json] [--min-n 10]
                                                    [--step 10] [--max-runs 1000] [--disagree 3]
    .venv/bin/python scripts/bench/racing_oracle.py --designs --full full.json full2.json
                                                    [--null 200]

For each comparison (an algorithm against ICOOT in one function) and each n from ``--min-n`` to
``--max-runs`` in steps of ``--step`` (the race's rounds: min_runs 10, batch 10), the fixed-n
rank-sum test on the first n runs of both cells (scipy's
``mannwhitneyu``, as the full study) at a fixed level gives a verdict (+, =, -); the comparison is
*settled* at the smallest n from which that verdict is the full study's and stays so up to
``--max-runs``. The oracle stops a cell when every comparison it is part of is settled: the
reference takes part in all five of its function, so it runs as long as the slowest. Two levels:
``holm``, each comparison at the threshold Holm's procedure gave it in the full study (alpha
0.05 / (65 - its rank)), and ``0.05``, every comparison at alpha 0.05 unadjusted (differences
settle sooner, equalities later). ``--disagree k`` lets the oracle give up up to k comparisons
(each then costs ``--min-n`` runs and counts as a disagreement; 95 % of 65 allows 3), chosen to
save the most runs (every subset tried).

``--designs``: valid designs (group-sequential: fixed-n rank-sum looks at planned run counts,
alpha split between them, the sequence and the closing look; :data:`DESIGNS`) replayed over the
full studies as a race would run them (the runs each uses, the agreement); ``--null N``: the
same designs over N simulated studies in which nothing differs (their error rate).

No valid procedure knows the verdicts it is aiming at, so each of these totals is a lower bound
for the runs a procedure needs to agree that often with the full study (at the same ``--min-n``),
in the sense that an honest test at n runs cannot be expected to call a verdict that a fixed-n
test at the full study's own level does not call at n. Markdown to stdout.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from service import TABLE2_ALGORITHMS, TABLE2_FUNCTIONS, note
from table2_race import bench_values, full_verdicts

from swarmpath.evidence.compare import rank_sum_many
from swarmpath.evidence.markers import holm
from swarmpath.evidence.sequential import decide, pair_scores

ALPHA = 0.05
REFERENCE = TABLE2_ALGORITHMS[-1]


def levels(verdicts: dict[Any, Any], rule: str) -> dict[Any, float]:
    """Each comparison's level: its Holm threshold in the full study, or ``rule`` as a number."""
    if rule != "holm":
        return dict.fromkeys(verdicts, float(rule))
    order = sorted(verdicts, key=lambda k: verdicts[k].p)
    m = len(order)
    return {k: ALPHA / (m - i) for i, k in enumerate(order)}


def settled_at(values: dict[tuple[str, str], list[float]], verdicts: dict[Any, Any],
               level: dict[Any, float], grid: list[int]) -> dict[Any, int | None]:
    """Per comparison (function, algorithm): the smallest n of ``grid`` from which the fixed-n
    test at its level gives the full study's marker at every n of the grid up to its last;
    None if not even there."""
    keys = list(verdicts)
    ok = np.zeros((len(keys), len(grid)), dtype=bool)
    for j, n in enumerate(grid):
        tests = rank_sum_many([(values[(a, f)][:n], values[(REFERENCE, f)][:n])
                               for f, a in keys])
        for i, (k, res) in enumerate(zip(keys, tests, strict=True)):
            marker = "="
            if res is not None and res[1] < level[k]:
                f, a = k  # U counts the algorithm's runs above the reference's
                sizes = [np.count_nonzero(~np.isnan(np.asarray(values[(x, f)][:n], dtype=float)))
                         for x in (a, REFERENCE)]
                marker = "+" if res[0] < sizes[0] * sizes[1] / 2.0 else "-"
            ok[i, j] = marker == verdicts[k].marker
        if n % 100 == 0:
            note(f"n = {n}")
    out: dict[Any, int | None] = {}
    for i, k in enumerate(keys):
        bad = np.flatnonzero(~ok[i])
        out[k] = None if not ok[i, -1] else grid[int(bad[-1]) + 1 if bad.size else 0]
    return out


def oracle_runs(settled: dict[Any, int | None], give_up: frozenset[Any], min_n: int,
                max_runs: int) -> int:
    """Runs of the oracle: per function each algorithm's cell until its comparison is settled,
    the reference's until its slowest is (a comparison given up, or never settled: ``min_n``)."""
    total = 0
    for f in TABLE2_FUNCTIONS:
        ns = [min_n if (k := (f, a)) in give_up or settled[k] is None else int(settled[k] or 0)
              for a in TABLE2_ALGORITHMS[:-1]]
        total += sum(ns) + max(ns)
    return total


def best_give_up(settled: dict[Any, int | None], k: int, min_n: int, max_runs: int
                 ) -> tuple[int, frozenset[Any]]:
    """The fewest runs when the oracle may disagree on k comparisons (those it cannot settle
    count first), and which ones it gives up."""
    forced = frozenset(c for c, n in settled.items() if n is None)
    free = [c for c, n in settled.items() if n is not None and n > min_n]
    best = (oracle_runs(settled, forced, min_n, max_runs), forced)
    for size in range(1, max(k - len(forced), 0) + 1):
        for extra in itertools.combinations(free, size):
            chosen = forced | frozenset(extra)
            runs = oracle_runs(settled, chosen, min_n, max_runs)
            if runs < best[0]:
                best = (runs, chosen)
    return best


#: Valid designs replayed (``--designs``): the confidence sequence's share of alpha, fixed-n
#: rank-sum looks at planned run counts before max_runs and the share each gets (``holm``: Holm
#: over the study's open comparisons at that look, a barrier across blocks; ``bonferroni``: each
#: comparison at share / 65, decidable per block), and the closing look's share (Holm over the
#: study at max_runs). Every share is spent on its own event, so by the union bound (and Holm's
#: argument per look: docs/statistics.md, Racing) a false difference has probability at most
#: alpha = 0.05 whatever the shares, as long as they sum to 1.
DESIGNS: dict[str, tuple[float, list[int], float, str, float]] = {
    "default (sequence 0.5, closing 0.5)": (0.5, [], 0.0, "holm", 0.5),
    "looks 200-900 bonferroni (sequence 0.2, looks 0.4, closing 0.4)":
        (0.2, [200, 300, 400, 500, 600, 700, 800, 900], 0.4, "bonferroni", 0.4),
    "looks 100-900 holm (sequence 0.1, looks 0.5, closing 0.4)":
        (0.1, [100, 200, 300, 400, 500, 600, 700, 800, 900], 0.5, "holm", 0.4),
    "looks 200, 400, 600 holm (sequence 0.1, looks 0.6, closing 0.3)":
        (0.1, [200, 400, 600], 0.6, "holm", 0.3),
    "looks 150-750 holm (sequence 0.05, looks 0.8, closing 0.15)":
        (0.05, [150, 300, 450, 600, 750], 0.8, "holm", 0.15),
    "looks 50-950 holm (sequence 0.05, looks 0.8, closing 0.15)":
        (0.05, list(range(50, 1000, 50)), 0.8, "holm", 0.15),
}


def design_replay(values: dict[tuple[str, str], list[float]], design: tuple[
        float, list[int], float, str, float], grid: list[int]) -> tuple[dict[Any, int],
                                                                        dict[Any, str]]:
    """Per comparison the runs at which the design decides it and its marker (+, -, or = when
    still open at the last run count): the sequence checked at every n of ``grid`` (a race's
    rounds), the looks at their run counts, the closing look at the last."""
    seq, looks, look_share, rule, closing = design
    keys = [(f, a) for f in TABLE2_FUNCTIONS for a in TABLE2_ALGORITHMS[:-1]]
    m, last = len(keys), grid[-1]
    when: dict[Any, int] = {}
    marker: dict[Any, str] = {}
    for k in keys:  # the sequence: its first round whose n reaches the crossing
        f, a = k
        z = pair_scores(values[(a, f)][:last], values[(REFERENCE, f)][:last])
        d = decide(z, ALPHA * seq / m, interval=False)
        if d.decision == "different":
            when[k] = next(n for n in grid if n >= d.at)
            marker[k] = "+" if d.better == "a" else "-"
    plan = [(n, ALPHA * look_share / len(looks), rule) for n in looks] + [
        (last, ALPHA * closing, "holm")]
    for n, level, how in plan:
        open_ = [k for k in keys if k not in when or when[k] > n]
        tests = rank_sum_many([(values[(a, f)][:n], values[(REFERENCE, f)][:n])
                               for f, a in open_])
        ps = [1.0 if t is None else t[1] for t in tests]
        reject = (holm(ps) < level) if how == "holm" else np.asarray(ps) < level / m
        for k, t, r in zip(open_, tests, reject, strict=True):
            if r and t is not None:
                when[k] = n
                marker[k] = "+" if t[0] < n * n / 2.0 else "-"
    for k in keys:
        when.setdefault(k, last)
        marker.setdefault(k, "=")
    return when, marker


def designs(args: argparse.Namespace, grid: list[int]) -> None:
    print("\n| full study | design | runs | fewer | agree with its full study | disagreements "
          "|\n| --- | --- | ---: | ---: | ---: | --- |")
    for path in args.full:
        doc = json.loads(path.read_text())
        values = {k: [np.inf if np.isnan(x) else x for x in v]
                  for k, v in bench_values(doc).items()}
        verdicts = full_verdicts(bench_values(doc), args.max_runs)
        for name, design in DESIGNS.items():
            when, marker = design_replay(values, design, grid)
            runs = sum(sum(when[(f, a)] for a in TABLE2_ALGORITHMS[:-1])
                       + max(when[(f, a)] for a in TABLE2_ALGORITHMS[:-1])
                       for f in TABLE2_FUNCTIONS)
            wrong = [k for k in when if marker[k] != verdicts[k].marker]
            full = len(TABLE2_ALGORITHMS) * len(TABLE2_FUNCTIONS) * args.max_runs
            print(f"| seed {doc['settings']['seed']} | {name} | {runs:,} | {full / runs:.1f}x | "
                  f"{len(when) - len(wrong)}/{len(when)} | "
                  f"{', '.join(f'{f} {a} {marker[(f, a)]}' for f, a in wrong)} |")


def null_studies(args: argparse.Namespace, grid: list[int]) -> None:
    """Each design over ``--null`` studies of Table 2's shape in which no algorithm differs
    (every cell 1000 independent standard normal runs): the share of studies with a false
    difference, at most alpha = 0.05 within its Monte Carlo error if the design is valid."""
    rng = np.random.default_rng(args.seed)
    studies = [{(a, f): rng.normal(size=args.max_runs).tolist() for a in TABLE2_ALGORITHMS
                for f in TABLE2_FUNCTIONS} for _ in range(args.null)]
    print(f"\n{args.null} null studies (13 blocks x 6 algorithms, {args.max_runs} normal runs a "
          f"cell, seed {args.seed}): studies with a false difference (95 % MC interval)\n\n"
          "| design | false | rate |\n| --- | ---: | --- |")
    for name, design in DESIGNS.items():
        false = sum(any(m != "=" for m in design_replay(v, design, grid)[1].values())
                    for v in studies)
        rate = false / args.null
        half = 1.96 * np.sqrt(max(rate * (1 - rate), 0.05 * 0.95) / args.null)
        print(f"| {name} | {false}/{args.null} | {rate:.3f} ({max(rate - half, 0):.3f}-"
              f"{rate + half:.3f}) |")
        note(f"{name}: {false}/{args.null}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--full", type=Path, nargs="+", required=True)
    ap.add_argument("--min-n", type=int, default=10)
    ap.add_argument("--step", type=int, default=10)
    ap.add_argument("--max-runs", type=int, default=1000)
    ap.add_argument("--disagree", type=int, default=3)
    ap.add_argument("--levels", default="holm,0.05")
    ap.add_argument("--designs", action="store_true",
                    help="instead: replay the valid designs of DESIGNS over the full studies")
    ap.add_argument("--null", type=int, default=0,
                    help="with --designs: also this many null studies (their error rate)")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    target = len(TABLE2_ALGORITHMS) * len(TABLE2_FUNCTIONS) * args.max_runs / 5
    grid = [*range(args.min_n, args.max_runs, args.step), args.max_runs]
    if args.designs:
        designs(args, grid)
        if args.null:
            null_studies(args, grid)
        return 0
    print(f"oracle over the full studies' first n runs, n = {args.min_n}, "
          f"{args.min_n + args.step}, ..., {args.max_runs}; 5x fewer than "
          f"{len(TABLE2_ALGORITHMS) * len(TABLE2_FUNCTIONS) * args.max_runs:,} runs is "
          f"{target:,.0f}\n")
    print("| full study | level | runs, all 65 agree | settled after 500+ runs (n) | "
          + " | ".join(f"runs, {k} given up" for k in range(1, args.disagree + 1))
          + " | given up |\n| --- | --- | ---: | --- | "
          + " | ".join("---:" for _ in range(args.disagree)) + " | --- |")
    for path in args.full:
        doc = json.loads(path.read_text())
        values = bench_values(doc)
        verdicts = full_verdicts(values, args.max_runs)
        for rule in args.levels.split(","):
            note(f"{path.name}, level {rule} ...")
            settled = settled_at(values, verdicts, levels(verdicts, rule), grid)
            slow = sorted(((n if n is not None else args.max_runs + 1), f, a)
                          for (f, a), n in settled.items()
                          if n is None or n >= args.max_runs // 2)
            cols = []
            chosen: frozenset[Any] = frozenset()
            for k in range(1, args.disagree + 1):
                runs, chosen = best_give_up(settled, k, args.min_n, args.max_runs)
                cols.append(f"{runs:,}")
            late = ", ".join(f"{f} {a} {'never' if n > args.max_runs else n}"
                             for n, f, a in slow)
            gone = ", ".join(f"{f} {a}" for f, a in sorted(chosen))
            all_runs = oracle_runs(settled, frozenset(), args.min_n, args.max_runs)
            never = sum(n is None for n in settled.values())
            first = f"{all_runs:,}" if not never else f"{all_runs:,} ({never} never settle)"
            print(f"| {path.name} (seed {doc['settings']['seed']}) | {rule} | {first} | "
                  f"{late} | {' | '.join(cols)} | {gone} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
