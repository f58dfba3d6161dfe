#!/usr/bin/env python3
"""Racing (docs/statistics.md, Racing): its error rate, its power, and the ICOOT paper's Table 2
raced through ``swarmpath up``.

    .venv/bin/python scripts/bench/racing.py error [--seeds 5] [--max-runs 100] [--alpha 0.05]
    .venv/bin/python scripts/bench/racing.py power [--races 300] [--max-runs 1000]
    .venv/bin/python scripts/bench/racing.py table2 [--max-runs 1000] [--margin 0.05]
                                                    [--workers 2] [--full FILE] [--full-up]
                                                    [--again] [--full-only --save-full FILE]
                                                    [--final-test rank-sum|sign|none]
    .venv/bin/python scripts/bench/racing.py seeds --full FILE FILE [--final-test LOOK]
    .venv/bin/python scripts/bench/racing.py needed [--races 200]

``error``: races between one optimizer and itself on two seeds' streams (exchangeable runs: any
declared difference is a false one), for every registered optimizer on F1-F13 (5 dims, 10
agents, 50 iterations), each race at level alpha alone, with each closing look; prints the rate
of false differences per optimizer and overall with its 95 % Monte Carlo interval. The same
optimizer under two names (every pair a tie) never differs: ``tests/test_racing.py`` checks that.

``power``: races between samples with a known theta = P(A's run beats B's) (normal runs shifted
by sqrt(2) Phi^-1(theta)), at the level of a 65-comparison table (Table 2 against its reference:
alpha 0.05/65), min 10, batch 10: the share decided right, decided wrong, the runs used.

``table2``: the Table 2 setting (PSO, SSA, FDO, mCOOT, COOT, ICOOT x F1-F13, 30 dims, 30 agents,
500 iterations, the numba backend when numba is installed) raced through ``swarmpath up
--workers N`` with ``max_runs`` runs per cell at most, beside the full study's verdicts
(rank-sum tests, Holm over the table, alpha 0.05: what ``swarmpath bench`` prints), read from
``--full FILE`` (a ``swarmpath bench --json`` document of the same setting and seed) or run
through the same service (``--full-up``; with both, the job's runs are checked equal to the
file's; ``--again`` runs the raced job once more after the full one, so the two raced times
bracket the full one). Prints the runs used, the wall times, the agreement of
every +/=/- and each disagreement with its race interval and the full study's A12 and p.
Markdown to stdout, progress to stderr.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent))
from service import TABLE2_ALGORITHMS, TABLE2_FUNCTIONS, Up, elapsed, note
from table2_race import (
    agreement,
    bench_values,
    full_verdicts,
    race_decisions,
    replayed_race,
    save_full,
    spec_settings,
    table2_spec,
)

from swarmpath.evidence.race_report import study_race
from swarmpath.evidence.racing import CLOSING, RaceSettings, race_block
from swarmpath.evidence.sequential import rejection_times
from swarmpath.optimizers import list_optimizers, minimize


def _decision(values: dict[str, np.ndarray], settings: RaceSettings) -> str:
    """The decision of a race of A against B alone (one comparison), its closing look taken."""
    race = race_block(values, ["A", "B"], settings, 1, intervals=False)
    doc = study_race(settings, 1, [({}, race, [(0, "A"), (1, "B")])])
    return str(doc["blocks"][0]["duels"][0]["decision"])


def error(args: argparse.Namespace) -> None:
    """Each null race four times over the same runs: with the job spec's default design (looks
    every round, recycling, futility, the rank-sum closing look) and with each closing look at
    max_runs alone (``final_test``: rank-sum; sign; none, the confidence sequence alone)."""
    names = ["default", *CLOSING]
    looks = [spec_settings(args.max_runs, 0.0, CLOSING[0], args.alpha)] + [
        RaceSettings(max_runs=args.max_runs, alpha=args.alpha, min_runs=10, batch=10,
                     final_test=look) for look in CLOSING]
    functions = [f"F{i}" for i in range(1, 14)]
    print(f"{args.seeds} seed pairs x F1-F13 x {len(list_optimizers())} optimizers, max_runs "
          f"{args.max_runs}, min_runs 10, batch 10, alpha {args.alpha} per race; each race "
          f"with the default design and with each closing look alone, no planned looks "
          f"(final_test: {', '.join(CLOSING)})\n")
    print("| optimizer | races | of them not all ties | "
          + " | ".join(f"false differences, {look} | rate" for look in names)
          + " |\n| --- | ---: | ---: | " + " | ".join("---: | ---:" for _ in names) + " |")
    total = varied = 0
    wrong = [0] * len(names)
    for name in list_optimizers():
        races = live = 0
        false = [0] * len(names)
        for f in functions:
            for s in range(args.seeds):
                a = minimize(name, f, 5, 10, 50, seed=1000 + s, runs=args.max_runs).best_fitness
                b = minimize(name, f, 5, 10, 50, seed=9000 + s, runs=args.max_runs).best_fitness
                races += 1
                live += bool(np.any(a != b))  # every pair tied: a difference is impossible
                for i, settings in enumerate(looks):
                    false[i] += _decision({"A": a, "B": b}, settings) == "different"
        total, varied = total + races, varied + live
        wrong = [w + x for w, x in zip(wrong, false, strict=True)]
        print(f"| {name} | {races} | {live} | "
              + " | ".join(f"{x} | {x / races:.3f}" for x in false) + " |")
        note(f"{name}: " + ", ".join(f"{look} {x}/{races}"
                                      for look, x in zip(names, false, strict=True)))
    for label, n in (("all", total), ("not all ties", varied)):
        cols = []
        for w in wrong:
            rate = w / n
            half = 1.96 * math.sqrt(rate * (1 - rate) / n) if w else 3.0 / n
            cols.append(f"{w} | {rate:.4f} ({max(rate - half, 0):.4f}-{rate + half:.4f})")
        print(f"| {label} (95 % MC) | {n} | | {' | '.join(cols)} |")


def power(args: argparse.Namespace) -> None:
    rng = np.random.default_rng(args.seed)
    level = 0.05 / 65
    print(f"alpha {level:.2e} (0.05 over 65 comparisons), min_runs 10, batch 10, max_runs "
          f"{args.max_runs}, {args.races} races per row\n")
    print("| theta | margin | right | wrong | open at max | median runs | p90 runs |\n"
          "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for theta, margin in [(0.5, 0.1), (0.5, 0.05), (0.56, 0.0), (0.6, 0.0), (0.64, 0.0),
                          (0.71, 0.0), (0.8, 0.0), (0.9, 0.0), (0.6, 0.05), (0.71, 0.05)]:
        settings = RaceSettings(max_runs=args.max_runs, alpha=0.05, min_runs=10, batch=10,
                                margin=margin)  # with 65 comparisons: each at ``level``
        shift = math.sqrt(2.0) * float(stats.norm.ppf(theta))
        right = wrong = undecided = 0
        used = []
        for _ in range(args.races):
            a = rng.normal(size=args.max_runs) - shift
            b = rng.normal(size=args.max_runs)
            race = race_block({"A": a, "B": b}, ["A", "B"], settings, 65)
            d = race.duels[0].result
            truth = "equivalent" if abs(theta - 0.5) < margin else "different"
            if d.decision == "open":
                undecided += 1
            elif d.decision == truth and (d.decision != "different" or d.better == "a"):
                right += 1
            else:
                wrong += 1
            used.append(race.allowance["A"])
        n = args.races
        print(f"| {theta} | {margin} | {right / n:.3f} | {wrong / n:.3f} | {undecided / n:.3f} "
              f"| {np.median(used):.0f} | {np.percentile(used, 90):.0f} |")


def needed(args: argparse.Namespace) -> None:
    """Runs per cell a comparison of small effect theta needs, at the race's level (alpha/65)
    and at the full study's (Holm: between alpha/65 for the smallest p and alpha for the
    largest): the fixed-n rank-sum test (Noether's normal approximation, JASA 82 (1987) 645),
    and the race's own statistic, the paired score Z (Bernoulli(theta) for independent runs
    without ties), at a fixed n (binomial test) and anytime-valid (the first n whose confidence
    sequence leaves 1/2, simulated); and the power of the full 1000-run study's rank-sum test."""
    rng = np.random.default_rng(args.seed)
    race_level = 0.05 / 65
    z_power = float(stats.norm.ppf(args.power))
    print(f"power {args.power}, two-sided; race: alpha {race_level:.2e} (0.05/65), "
          f"{args.races} simulated races of up to {args.max_runs} pairs per theta\n")
    print("| theta (A12) | rank-sum n, alpha/65 | rank-sum n, alpha 0.05 | paired fixed n, "
          "alpha/65 | race n (median / p80) | race decided by 1000 | full 1000-run power, "
          "alpha/65 / 0.05 | two full studies agree |\n"
          "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for theta in (0.53, 0.55, 0.56, 0.58, 0.6, 0.64):
        d = theta - 0.5

        def rank_sum_n(level: float, d: float = d) -> float:  # per group, equal groups
            return (float(stats.norm.ppf(1 - level / 2)) + z_power) ** 2 / (6 * d * d)

        def rank_sum_power(n: int, level: float, d: float = d) -> float:
            return float(stats.norm.cdf(d * math.sqrt(6 * n) - stats.norm.ppf(1 - level / 2)))

        paired = ((float(stats.norm.ppf(1 - race_level / 2)) * 0.5
                   + z_power * math.sqrt(theta * (1 - theta))) / d) ** 2
        times = np.array([rejection_times(rng.random(args.max_runs) < theta, [0.5],
                                          race_level)[0] for _ in range(args.races)], float)
        times[times == 0] = np.inf
        p_lo, p_hi = rank_sum_power(1000, race_level), rank_sum_power(1000, 0.05)
        # two independent studies give the same verdict: both detect it or both miss it
        agree = [p * p + (1 - p) * (1 - p) for p in (p_lo, p_hi)]
        ordered = np.sort(times)  # never decided: inf, last
        med, p80 = (f"{v:.0f}" if np.isfinite(v := ordered[int(q * (len(ordered) - 1))])
                    else f">{args.max_runs}" for q in (0.5, 0.8))
        print(f"| {theta} | {rank_sum_n(race_level):.0f} | {rank_sum_n(0.05):.0f} | "
              f"{paired:.0f} | {med} / {p80} | {np.mean(times <= 1000):.2f} | "
              f"{p_lo:.2f} / {p_hi:.2f} | {min(agree):.2f}-{max(agree):.2f} |")


def _full_values_from_up(up: Up, job: str) -> dict[tuple[str, str], list[float]]:
    out: dict[tuple[str, str], list[float]] = {}
    offset = 0
    while True:
        items = up.http.get(f"/jobs/{job}/runs",
                            params={"limit": 1000, "offset": offset}).json()["items"]
        if not items:
            return out
        for r in items:
            out.setdefault((r["algorithm"], r["function"]), []).append(
                float(r.get("best_fitness", math.inf)))
        offset += len(items)


def seeds(args: argparse.Namespace) -> None:
    """Two full studies of Table 2 on other seeds: how many of their +/=/- verdicts they share
    (the comparison's own reproducibility, the ceiling of any racing agreement), and the race
    replayed over each, against both."""
    docs = [json.loads(Path(f).read_text()) for f in args.full]
    values = [bench_values(d) for d in docs]
    verdicts = [full_verdicts(v, args.max_runs) for v in values]
    names = [f"seed {d['settings']['seed']}" for d in docs]
    keys = list(verdicts[0])
    same = [k for k in keys if verdicts[0][k].marker == verdicts[1][k].marker]
    print(f"full {args.max_runs}-run studies, {names[0]} and {names[1]}: **{len(same)}/"
          f"{len(keys)} verdicts the same ({100 * len(same) / len(keys):.1f} %)**\n")
    print(f"| function | algorithm vs ICOOT | {names[0]}: marker (A12, p_holm) | {names[1]} |\n"
          "| --- | --- | --- | --- |")
    for f, a in keys:
        if (f, a) not in same:
            cols = [f"{t.marker} ({t.a12:.3f}, {t.p_holm:.2g})"
                    for t in (verdicts[0][(f, a)], verdicts[1][(f, a)])]
            print(f"| {f} | {a} | {cols[0]} | {cols[1]} |")
    settings = RaceSettings(max_runs=args.max_runs, alpha=0.05, min_runs=10, batch=10,
                            margin=args.margin, final_test=args.final_test)
    print(f"\nraces (replayed, margin {args.margin}, closing look {args.final_test}) against "
          f"each full study's "
          "verdicts:\n\n"
          f"| race over | runs used | against {names[0]} | against {names[1]} |\n"
          "| --- | ---: | ---: | ---: |")
    for name, v in zip(names, values, strict=True):
        race = replayed_race(v, settings)
        used = sum(c["runs"] for b in race["blocks"] for c in b["cells"])
        agree = [sum(d["marker"] == verdicts[i][(b["block"]["function"], d["a"])].marker
                     for b in race["blocks"] for d in b["duels"]) for i in (0, 1)]
        print(f"| {name} | {used} | {agree[0]}/{len(keys)} | {agree[1]}/{len(keys)} |")


def table2(args: argparse.Namespace) -> None:
    settings = spec_settings(args.max_runs, args.margin, args.final_test)
    if args.replay:
        doc = json.loads(Path(args.full).read_text())
        values = bench_values(doc)
        short = [k for k, v in values.items() if len(v) < args.max_runs]
        if short:
            raise SystemExit(f"--full has fewer than {args.max_runs} runs in {short[:3]}")
        print(f"replayed over `{args.full.name}` ({doc['settings']['runs']} runs a cell, seed "
              f"{doc['settings']['seed']}, swarmpath {doc['swarmpath']}, "
              f"{doc['seconds']:.0f} s)\n")
        for margin in args.margins:
            agreement(replayed_race(values, spec_settings(args.max_runs, margin,
                                                           args.final_test)),
                      values, args.max_runs)
        return
    try:
        import numba  # noqa: F401

        backend = "numba"
    except ImportError:
        backend = "numpy"
    spec = table2_spec(args.max_runs, args.margin, args.seed, backend, args.final_test)
    with tempfile.TemporaryDirectory(prefix="swarmpath-race-") as d, \
            Up(args.workers, Path(d)) as up:
        if args.full_only:  # the full job alone, its runs kept (--save-full)
            note(f"the full study (max {args.max_runs} runs per cell, {backend}) ...")
            plain = {k: v for k, v in spec.items() if k != "racing"}
            alone = up.run_job(plain, timeout=86400)
            save_full(args.save_full, spec, _full_values_from_up(up, alone["id"]),
                       elapsed(alone))
            print(f"full through swarmpath up --workers {args.workers}: {alone['runs_total']} "
                  f"runs, {elapsed(alone):.0f} s, load {alone['load'][0]:.1f} -> "
                  f"{alone['load'][1]:.1f}; runs in `{args.save_full}`")
            return
        note(f"raced Table 2 (max {args.max_runs} runs per cell, {backend}) ...")
        raced = up.run_job(spec, timeout=86400)
        race = up.http.get(f"/jobs/{raced['id']}/race").json()
        full_values: dict[tuple[str, str], list[float]]
        full_status: dict[str, Any] | None = None
        again: dict[str, Any] | None = None
        if args.full_up:
            note("the full study through the same service ...")
            plain = {k: v for k, v in spec.items() if k != "racing"}
            full_status = up.run_job(plain, timeout=86400)
            full_values = _full_values_from_up(up, full_status["id"])
            if args.save_full is not None:
                save_full(args.save_full, spec, full_values, elapsed(full_status))
            if args.again:  # raced, full, raced: the first job's warm-up shows as a difference
                note("the raced job again ...")
                again = up.run_job(spec, timeout=86400)
        if args.full is not None:
            from_file = bench_values(json.loads(Path(args.full).read_text()))
            if args.full_up:
                same_runs = all(np.array_equal(np.asarray(v, dtype=float),
                                               np.asarray(from_file[k][:args.max_runs],
                                                          dtype=float), equal_nan=True)
                                for k, v in full_values.items())
                print(f"the full job's runs equal `{args.full.name}`'s: {same_runs}")
            else:
                full_values = from_file
    full_runs = len(TABLE2_ALGORITHMS) * len(TABLE2_FUNCTIONS) * args.max_runs
    for label, status in (("raced", raced), ("full", full_status), ("raced again", again)):
        if status is not None:
            print(f"{label} through swarmpath up --workers {args.workers}: "
                  f"{status['runs_total']} of {full_runs} runs, {elapsed(status):.0f} s, "
                  f"load {status['load'][0]:.1f} -> {status['load'][1]:.1f}")
    same = race_decisions(race) == race_decisions(replayed_race(full_values, settings))
    print(f"the job's race equals its replay over the full study's runs: {same}\n")
    agreement(race, full_values, args.max_runs)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    e = sub.add_parser("error")
    e.add_argument("--seeds", type=int, default=5)
    e.add_argument("--max-runs", type=int, default=100)
    e.add_argument("--alpha", type=float, default=0.05)
    p = sub.add_parser("power")
    p.add_argument("--races", type=int, default=300)
    p.add_argument("--max-runs", type=int, default=1000)
    p.add_argument("--seed", type=int, default=1)
    t = sub.add_parser("table2")
    t.add_argument("--max-runs", type=int, default=1000)
    t.add_argument("--margin", type=float, default=0.05)
    t.add_argument("--workers", type=int, default=2)
    t.add_argument("--seed", type=int, default=1)
    t.add_argument("--final-test", choices=CLOSING, default=CLOSING[0],
                   help="the closing look at max_runs (racing.final_test)")
    t.add_argument("--replay", action="store_true", help="no service: replay the race over "
                   "--full's runs (what a raced job decides, run for run)")
    t.add_argument("--margins", type=lambda v: [float(x) for x in v.split(",")],
                   default=[0.0, 0.05], help="with --replay: the margins to replay")
    t.add_argument("--full", type=Path, help="swarmpath bench --json of the same setting (with "
                   "--full-up: the full job's runs are checked equal to its)")
    t.add_argument("--full-up", action="store_true", help="run the full study too")
    t.add_argument("--again", action="store_true",
                   help="with --full-up: the raced job once more after the full one")
    t.add_argument("--save-full", type=Path, help="with --full-up or --full-only: write the "
                   "full job's runs there (a swarmpath bench --json document's cells)")
    t.add_argument("--full-only", action="store_true",
                   help="only the full job through the service, its runs to --save-full")
    n = sub.add_parser("needed", help="runs a small effect needs: fixed-n and the race")
    n.add_argument("--races", type=int, default=200)
    n.add_argument("--max-runs", type=int, default=20000)
    n.add_argument("--power", type=float, default=0.8)
    n.add_argument("--seed", type=int, default=1)
    o = sub.add_parser("seeds", help="two full studies' verdicts against each other")
    o.add_argument("--full", type=Path, nargs=2, required=True, metavar="FILE")
    o.add_argument("--max-runs", type=int, default=1000)
    o.add_argument("--margin", type=float, default=0.0)
    o.add_argument("--final-test", choices=CLOSING, default=CLOSING[0])
    args = ap.parse_args(argv)
    if args.what == "table2" and args.full_only and args.save_full is None:
        ap.error("table2 --full-only: --save-full FILE")
    if args.what == "table2" and args.full is None and not (args.full_up or args.full_only):
        ap.error("table2: --full FILE or --full-up (or both)")
    if args.what == "table2" and args.replay and args.full is None:
        ap.error("table2 --replay: --full FILE")
    started = time.perf_counter()
    {"error": error, "power": power, "table2": table2, "seeds": seeds,
     "needed": needed}[args.what](args)
    note(f"{time.perf_counter() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
