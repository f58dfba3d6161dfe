#!/usr/bin/env python3
"""Races with planned group-sequential looks (``racing.looks``; docs/statistics.md, Racing) on the
ICOOT paper's Table 2: replayed over full 1000-run studies, and over null studies.

    .venv/bin/python scripts/bench/racing_looks.py replay --full full.json [full2.json]
                                                          [--designs NAME,...]
    .venv/bin/python scripts/bench/racing_looks.py null [--studies 200] [--seed 1] [--partial]
                                                        [--designs NAME,...]
    .venv/bin/python scripts/bench/racing_looks.py step --full full.json [--function F2]
                                                        [--repeats 5]
    .venv/bin/python scripts/bench/racing_looks.py power [--races 200] [--seed 1]
                                                         [--designs NAME,...]

Each design of :data:`DESIGNS` is a ``racing`` field (min_runs 10, batch 10, alpha 0.05,
max_runs 1000). ``replay``: the race of Table 2 replayed over each full study's runs with the
product's own code (``table2_race.replayed_race``: :func:`swarmpath.evidence.racing.
race_block` per function and the study's closing look, what the store runs as results arrive;
run r of a cell is the same run raced or not), its runs against the 78,000 of the full study,
and every +/=/- against the full study's (rank-sum, Holm over the table, alpha 0.05), the
disagreements listed. ``null``: ``--studies`` studies of Table 2's shape (13 blocks of 6
algorithms, 1000 independent standard normal runs a cell: nothing differs) raced by each design:
the share of studies with any difference declared (each one false), at most alpha = 0.05 within
its Monte Carlo error when the design is valid; ``--partial``: in every block three algorithms
are far worse than the rest and two are the reference under other names, so that shares
recycled from the first reach comparisons that do not differ (a false difference: one of those
two declared). ``step``: the cost of the store's race steps on
one function of a full study: the block replayed once per completed round as the store does
(race_block over each cell's runs so far), the whole race step by step, with the default design
with the looks' memo (race_tests.LookMemo, one per race as the store keeps one), without it, and
without looks ("plain"), the three alternating ``--repeats`` times; process CPU time, medians,
per step and for the last 10 steps; the memo's decisions checked equal to the memo-less ones at
every step. ``power``: ``--races`` races of one comparison at the level of one of Table 2's 65
(alpha 0.05 / 65, max_runs 1000) per theta = P(A's run beats B's) (normal runs, A shifted),
each raced by every design over the same runs: how often each declares the right difference,
stops as futile, stays open, and its runs; and the verdicts a design loses against the first
design named (declared there, not here): futility's cost in power. Markdown to stdout, progress
to stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from service import TABLE2_ALGORITHMS, TABLE2_FUNCTIONS, note
from table2_race import bench_values, full_verdicts, replayed_race

from swarmpath.evidence.race_report import study_race
from swarmpath.evidence.race_tests import LookMemo
from swarmpath.evidence.racing import RaceSettings, race_block
from swarmpath.service.racing import RacingSpec

EVERY_ROUND = tuple(range(20, 1000, 10))
#: name -> the racing fields besides min_runs 10, batch 10, alpha 0.05 ("default": the job
#: spec's default, through RacingSpec; "plain": no looks, the default before it).
DESIGNS: dict[str, dict[str, Any]] = {
    "default": {},
    "plain": dict(looks=()),
    "obf-50": dict(looks=tuple(range(50, 1000, 50)), look_share=0.8, sequence_share=0.05),
    "pocock-100": dict(looks=tuple(range(100, 1000, 100)), look_share=0.5, sequence_share=0.1,
                       spending="pocock"),
    "pocock-50": dict(looks=tuple(range(50, 1000, 50)), look_share=0.8, sequence_share=0.05,
                      spending="pocock"),
    "pocock-rounds": dict(looks=EVERY_ROUND, look_share=0.8, sequence_share=0.05,
                          spending="pocock"),
    # the default's parts one at a time (pocock-rounds: neither) and its futility at other
    # thresholds
    "recycle": dict(looks=EVERY_ROUND, look_share=0.8, sequence_share=0.05, spending="pocock",
                    recycle=True),
    "futility": dict(looks=EVERY_ROUND, look_share=0.8, sequence_share=0.05, spending="pocock",
                     futility=0.05),
    **{f"futility-{g:g}": dict(looks=EVERY_ROUND, look_share=0.8, sequence_share=0.05,
                               spending="pocock", futility=g, recycle=True)
       for g in (0.02, 0.1, 0.2)},
}
MAX_RUNS = 1000


def settings_of(name: str) -> RaceSettings:
    if name == "default":  # what a job spec's racing {min_runs 10, batch 10} races with
        return RacingSpec(min_runs=10, batch=10, alpha=0.05).settings(MAX_RUNS)
    return RaceSettings(max_runs=MAX_RUNS, alpha=0.05, min_runs=10, batch=10, **DESIGNS[name])


def describe(name: str) -> str:
    """A design in a table: its name, spending, looks and shares of alpha."""
    d = settings_of(name)
    runs = d.look_runs
    if not runs:
        return (f"{name}: no looks, sequence {d.sequence_share:g} / closing "
                f"{d.closing_alpha / d.alpha:.2g}")
    return (f"{name}: {d.spending}, looks {runs[0]}-{runs[-1]} ({len(runs)}), sequence "
            f"{d.sequence_share:g} / looks {d.look_share:g} / closing "
            f"{d.closing_alpha / d.alpha:.2g}, futility {d.futility:g}"
            f"{', recycled' if d.recycle else ''}")


def _runs(race: dict[str, Any]) -> int:
    return sum(c["runs"] for b in race["blocks"] for c in b["cells"])


def replay(args: argparse.Namespace) -> None:
    docs = [json.loads(Path(f).read_text()) for f in args.full]
    values = [bench_values(d) for d in docs]
    verdicts = [full_verdicts(v, MAX_RUNS) for v in values]
    full = len(TABLE2_ALGORITHMS) * len(TABLE2_FUNCTIONS) * MAX_RUNS
    print("design: spending, looks (how many), shares of alpha (sequence / looks / closing "
          f"rank-sum look), futility\n\n| design | full study | runs | fewer than {full:,} | "
          "decided at a look | futile | agree with its full study | with the other | "
          "disagreements (raced marker (decision); full study's) |\n"
          "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |")
    for name in args.designs:
        settings = settings_of(name)
        for i, (doc, v) in enumerate(zip(docs, values, strict=True)):
            race = replayed_race(v, settings)
            duels = [(b["block"]["function"], d) for b in race["blocks"] for d in b["duels"]]
            agree = [sum(d["marker"] == verdicts[j][(f, d["a"])].marker for f, d in duels)
                     for j in range(len(docs))]
            wrong = [f"{f} {d['a']} {d['marker']} ({d['decision']}; "
                     f"{verdicts[i][(f, d['a'])].marker}, p_holm "
                     f"{verdicts[i][(f, d['a'])].p_holm:.2g})"
                     for f, d in duels if d["marker"] != verdicts[i][(f, d["a"])].marker]
            other = f"{agree[1 - i]}/{len(duels)}" if len(docs) == 2 else ""
            used = _runs(race)
            print(f"| {describe(name)} | seed {doc['settings']['seed']} | {used:,} | "
                  f"{full / used:.2f}x | "
                  f"{sum(d['look'] is not None and d['decision'] == 'different' for _, d in duels)}"
                  f" | {sum(d['decision'] == 'futile' for _, d in duels)} | "
                  f"{agree[i]}/{len(duels)} | "
                  f"{other} | {', '.join(wrong)} |", flush=True)
            note(f"{name}, seed {doc['settings']['seed']}: {used} runs")


def _null_race(values: dict[tuple[str, str], list[float]], settings: RaceSettings
               ) -> dict[str, Any]:
    """``replayed_race`` without the duels' confidence intervals (no decision uses them; they
    are most of a replay's time)."""
    m = len(TABLE2_FUNCTIONS) * (len(TABLE2_ALGORITHMS) - 1)
    blocks = [({"function": f}, race_block({a: np.asarray(values[(a, f)]) for a in
                                            TABLE2_ALGORITHMS}, TABLE2_ALGORITHMS, settings, m,
                                           intervals=False), list(enumerate(TABLE2_ALGORITHMS)))
              for f in TABLE2_FUNCTIONS]
    return study_race(settings, m, blocks)


def null(args: argparse.Namespace) -> None:
    rng = np.random.default_rng(args.seed)
    false = dict.fromkeys(args.designs, 0)
    by_look = dict.fromkeys(args.designs, 0)
    # --partial: in every block PSO, SSA and FDO are far worse than the rest (shifted by 3
    # standard deviations: declared at the first looks) and mCOOT, COOT are ICOOT under other
    # names, so the shares recycled from the first reach comparisons that do not differ
    differ = set(TABLE2_ALGORITHMS[:3]) if args.partial else set()
    for s in range(args.studies):
        values = {(a, f): (rng.normal(size=MAX_RUNS) + 3.0 * (a in differ)).tolist()
                  for a in TABLE2_ALGORITHMS for f in TABLE2_FUNCTIONS}
        for name in args.designs:
            duels = [d for b in _null_race(values, settings_of(name))["blocks"]
                     for d in b["duels"] if d["a"] not in differ]
            wrong = [d for d in duels if d["decision"] == "different"]
            false[name] += bool(wrong)
            by_look[name] += any(d["look"] is not None for d in wrong)
        if (s + 1) % 5 == 0:
            note(f"{s + 1} studies: " + ", ".join(f"{v}" for v in false.values()))
    from scipy import stats

    # the claim "at most alpha" fails when more studies err than a design erring at exactly
    # alpha gives with probability 0.95 (one-sided binomial test at 5 %)
    bound = int(stats.binom.ppf(0.95, args.studies, 0.05))
    kind = (f"partial-null studies (13 blocks x 6 algorithms, {MAX_RUNS} normal runs a cell, "
            "PSO, SSA and FDO 3 standard deviations worse, mCOOT, COOT and ICOOT the same" if
            args.partial else f"null studies (13 blocks x 6 algorithms, {MAX_RUNS} standard "
            "normal runs a cell")
    print(f"{args.studies} {kind}, seed {args.seed}), raced by the product's code: studies with a "
          "false "
          "difference, the rate with its 95 % Clopper-Pearson interval; the claim (at most "
          f"alpha = 0.05) fails above {bound} of {args.studies} (a design erring at exactly "
          f"0.05 exceeds it with probability {stats.binom.sf(bound, args.studies, 0.05):.3f})"
          "\n\n| design | studies with a false difference | rate (95 % interval) | of them at "
          "a look | at most alpha |\n| --- | ---: | --- | ---: | --- |")
    for name in args.designs:
        ci = stats.binomtest(false[name], args.studies).proportion_ci()
        print(f"| {describe(name)} | {false[name]}/{args.studies} | "
              f"{false[name] / args.studies:.3f} ({ci.low:.3f}-{ci.high:.3f}) | "
              f"{by_look[name]} | {'holds' if false[name] <= bound else 'FAILS'} |")


def power(args: argparse.Namespace) -> None:
    from scipy import stats

    m = len(TABLE2_FUNCTIONS) * (len(TABLE2_ALGORITHMS) - 1)
    print(f"{args.races} races per theta of one comparison at the level of one of Table 2's "
          f"(alpha 0.05 / {m}, max_runs {MAX_RUNS}, min_runs 10, batch 10), normal runs with A "
          f"shifted, seed {args.seed}; every design over the same runs. right: declared "
          f"different, A better; lost: declared by {args.designs[0]} and not by this design\n\n"
          "| theta | design | right | wrong | futile | open at max | lost | median runs | mean "
          "runs |\n| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for theta in (0.5, 0.53, 0.55, 0.58, 0.6, 0.64):
        rng = np.random.default_rng([args.seed, round(theta * 1000)])
        shift = np.sqrt(2.0) * stats.norm.ppf(theta)
        samples = [(rng.normal(size=MAX_RUNS) - shift, rng.normal(size=MAX_RUNS))
                   for _ in range(args.races)]
        first: list[bool] = []
        for name in args.designs:
            settings = settings_of(name)
            duels, runs = [], []
            for a, b in samples:
                race = race_block({"A": a, "B": b}, ["A", "B"], settings, m, intervals=False)
                doc = study_race(settings, m, [({}, race, [(0, "A"), (1, "B")])])
                duels.append(doc["blocks"][0]["duels"][0])
                runs.append(race.runs_used() / 2)
            declared = [d["decision"] == "different" for d in duels]
            first = first or declared
            share = {k: sum(map(f, duels)) / args.races for k, f in (
                ("right", lambda d: d["decision"] == "different" and d["better"] == "A"),
                ("wrong", lambda d: d["decision"] == "different" and d["better"] != "A"),
                ("futile", lambda d: d["decision"] == "futile"),
                ("open", lambda d: d["decision"] == "open"))}
            lost = sum(f and not d for f, d in zip(first, declared, strict=True)) / args.races
            print(f"| {theta:g} | {name} | {share['right']:.3f} | {share['wrong']:.3f} | "
                  f"{share['futile']:.3f} | {share['open']:.3f} | {lost:.3f} | "
                  f"{np.median(runs):.0f} | {np.mean(runs):.0f} |", flush=True)
        note(f"theta {theta} done")


def _steps(values: dict[str, np.ndarray], settings: RaceSettings, memo: LookMemo | None
           ) -> tuple[list[float], list[Any]]:
    """The store's steps over one block (one race_block per completed round, each cell at the
    runs its allowance gave it): each step's CPU seconds and race."""
    m = len(TABLE2_FUNCTIONS) * (len(TABLE2_ALGORITHMS) - 1)
    have = dict.fromkeys(TABLE2_ALGORITHMS, settings.min_runs)
    seconds, races = [], []
    while True:
        t = time.process_time()
        race = race_block({a: values[a][:have[a]] for a in TABLE2_ALGORITHMS},
                          TABLE2_ALGORITHMS, settings, m, memo=memo)
        seconds.append(time.process_time() - t)
        races.append((race.allowance, race.stop_reason, [d.to_json() for d in race.duels]))
        if race.finished or race.allowance == have:
            return seconds, races
        have = dict(race.allowance)


def step(args: argparse.Namespace) -> None:
    doc = json.loads(Path(args.full[0]).read_text())
    raw = bench_values(doc)
    values = {a: np.where(np.isnan(v := np.asarray(raw[(a, args.function)])), np.inf, v)
              for a in TABLE2_ALGORITHMS}
    settings = {"memo": settings_of("default"), "no memo": settings_of("default"),
                "plain": settings_of("plain")}
    for s in settings.values():
        s.look_levels(65)  # the boundaries, once per process (cached), outside the timing
    times: dict[str, list[list[float]]] = {k: [] for k in settings}
    races: dict[str, list[Any]] = {}
    for r in range(args.repeats):
        for mode, s in settings.items():  # alternating: each repeat runs all three in turn
            seconds, races[mode] = _steps(values, s, LookMemo() if mode == "memo" else None)
            times[mode].append(seconds)
        note(f"repeat {r + 1}: " + ", ".join(f"{k} {sum(v[-1]):.2f} s" for k, v in times.items()))
    assert races["memo"] == races["no memo"], "the memo changed a decision"
    steps = len(times["memo"][0])
    common = min(steps, len(times["plain"][0]))
    print(f"{args.function} of {args.full[0].name} (seed {doc['settings']['seed']}): the store's "
          f"race steps (one replay per completed round; {steps} steps with the default design), "
          f"{args.repeats} alternating repeats, process CPU time, median over repeats; the "
          f"memo's decisions equal the memo-less ones at every step; rounds both designs "
          f"have: the first {common}\n\n"
          "| design | steps | race (all steps) | mean step | mean of the last 10 steps both "
          "have | those / plain's (median of the repeats' ratios) |\n"
          "| --- | ---: | ---: | ---: | ---: | ---: |")
    for mode, runs in times.items():
        total = float(np.median([sum(t) for t in runs]))
        last = [float(np.mean(t[common - 10:common])) for t in runs]
        ratio = np.median([x / float(np.mean(p[common - 10:common]))
                           for x, p in zip(last, times["plain"], strict=True)])
        name = {"memo": "default (looks every round), memo", "no memo": "default, no memo",
                "plain": "plain (no looks)"}[mode]
        print(f"| {name} | {len(runs[0])} | {total:.2f} s | {1000 * total / len(runs[0]):.0f} ms "
              f"| {1000 * float(np.median(last)):.0f} ms | {ratio:.2f}x |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    r = sub.add_parser("replay")
    r.add_argument("--full", type=Path, nargs="+", required=True, metavar="FILE")
    n = sub.add_parser("null")
    n.add_argument("--studies", type=int, default=200)
    n.add_argument("--seed", type=int, default=1)
    n.add_argument("--partial", action="store_true",
                   help="three algorithms of every block differ, two do not (module text)")
    st = sub.add_parser("step")
    st.add_argument("--full", type=Path, nargs=1, required=True, metavar="FILE")
    st.add_argument("--function", default="F2", choices=TABLE2_FUNCTIONS)
    st.add_argument("--repeats", type=int, default=5)
    pw = sub.add_parser("power")
    pw.add_argument("--races", type=int, default=200)
    pw.add_argument("--seed", type=int, default=1)
    for p in (r, n, pw):
        p.add_argument("--designs", type=lambda v: v.split(","), default=list(DESIGNS),
                       help=f"names of DESIGNS, comma-separated: {', '.join(DESIGNS)}")
    args = ap.parse_args(argv)
    unknown = [d for d in getattr(args, "designs", ()) if d not in DESIGNS]
    if unknown:
        ap.error(f"--designs: unknown {unknown}")
    {"replay": replay, "null": null, "step": step, "power": power}[args.what](args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
