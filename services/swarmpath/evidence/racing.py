"""Racing: how many runs each cell of a benchmark study gets, decided from the runs themselves.

A block is one (function, dimension) of a study: the cells of its algorithms are raced against
each other. Runs are scheduled in rounds: in round k every cell still racing may have
``a_k = min(min_runs + k * batch, max_runs)`` runs. When every racing cell of a block has its
``a_k`` runs, the block's comparisons (every algorithm against the reference, or every pair) are
updated with :func:`swarmpath.evidence.sequential.decide`; a comparison decided (different, or
equivalent within the margin) stays decided; a cell stops when every comparison it is part of is
decided, or at ``max_runs``; the others go on to round k + 1.

Everything here is a pure function of the runs' values in run order: :func:`race_block` replays a
block from round 0, so a coordinator that restarts (or a second one reading the same store) finds
the same rounds and decisions, and a study extended later with a larger ``max_runs`` continues
from the runs it has. Run r of a cell is the run r of the unraced study (the same streams); racing
only decides how many of them are computed.

The error rate: each comparison's confidence sequence holds at level ``alpha / m`` where m is the
number of comparisons of the whole study (Bonferroni), so the probability that any comparison of
the study declares a difference between algorithms that do not differ (theta = 1/2), or an
equivalence between algorithms that differ by more than the margin, is at most ``alpha``,
whenever the race stops. See docs/statistics.md, "Racing".

The closing look (``final_test``, docs/statistics.md "Racing"): a comparison still open when its
cells reach ``max_runs`` gets one fixed-n test there, at a level the confidence sequence does not
use (union bound: a false difference needs one of the two parts to err). ``"rank-sum"`` (the
default): the sequence gets ``alpha * SEQUENCE_SHARE / m`` per comparison; the look is the full
study's own test, the two-sided rank-sum test of the two cells' ``max_runs`` runs, with Holm's
procedure at ``alpha * (1 - SEQUENCE_SHARE)`` over the study's comparisons the sequence has not
declared different (:func:`closing_rejections`; the race document's :func:`close_race
<swarmpath.evidence.race_report.close_race>` applies it: it spans blocks). ``"sign"`` (the look
of earlier jobs): the exact sign test of theta = 1/2 on the ``max_runs`` pairs at ``alpha /
(2 m)``, the sequence at ``alpha / (2 m)``. ``"none"``: the sequence alone at ``alpha / m``. The
look happens once, at a run count fixed before the race (``max_runs``), so optional stopping does
not touch it.

Planned looks (``looks``, a group-sequential design; docs/statistics.md "Racing"): run counts
fixed before the race, each one of the rounds' allowances below ``max_runs``, or
:data:`EVERY_ROUND` (every round's after the first; :data:`DEFAULT_DESIGN`, the default of new
races, looks so). At each, every
comparison still open gets the two-sided rank-sum test of its two cells' runs so far, and is
declared different when its p is below that look's nominal level: the looks of one comparison
spend ``alpha * look_share / m`` together, across the looks by the spending function
``spending`` with their correlation sqrt(n_i / n_j) (:mod:`swarmpath.evidence.group_sequential`),
so a comparison's looks err with probability at most that, wherever the race stops it. The look
is taken in the block's own replay (Bonferroni over the study: no block waits for another). The
shares of alpha: the sequence ``sequence_share``, the looks ``look_share``, the rank-sum closing
look the rest (``none``: the sequence gets all but the looks' share); by the union bound a false
difference anywhere in the study has probability at most alpha.

Recycling (``recycle``, with planned looks): at a look, a comparison declared different (by the
sequence or a look) passes its share of the looks' alpha to the comparisons of its block still
open, Holm's step-down within the block: with D of the block's K comparisons declared, each open
one is tested at the boundary of level ``alpha * look_share * K / ((K - D) * m)``, and a rejection
at a look raises the others' level at the same look. Blocks keep their Bonferroni shares, so no
block waits for another. Valid because, until a comparison that does not differ is declared,
only comparisons that differ have passed shares on: each of the k0 that do not differ is tested
at a level at most the block's looks' share / k0 at every look, and a boundary of a smaller
level is higher (checked: tests/test_group_sequential.py), so a false difference at the looks of
a block needs one of them to cross its boundary at that level, probability at most the block's
share (Maurer and Bretz, Stat. Biopharm. Res. 5 (2013) 311-320, for graphical procedures of
this kind); a false difference by the sequence is its own event, counted in its share.

Futility (``futility``, with planned looks and the rank-sum closing look): at a look, a
comparison the look did not decide stops (decision :data:`FUTILE`, marker =) when its predictive
power is below ``futility``: the probability, by its own trend with a flat prior on the effect
(:func:`swarmpath.evidence.group_sequential.predictive_power`), that the two-sided rank-sum test
at ``max_runs`` rejects at the closing look's level ``alpha * closing share`` (Holm's largest
threshold there, so the chance is not understated). It is not a verdict and the levels are not
recomputed for it (a non-binding rule): stopping a comparison only takes away its later chances
to be declared different, and in the closing look's Holm it counts as p = 1, which leaves every
other comparison's adjusted p where it was or raises it. So the study's error rate stays at
most alpha; what futility costs is power (a comparison stopped that the closing look would have
called), measured in docs/benchmarks.md, Racing.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from swarmpath.evidence.group_sequential import predictive_power
from swarmpath.evidence.race_settings import (
    CLOSING,
    DEFAULT_DESIGN,
    EVERY_ROUND,
    PAIRS,
    SEQUENCE_SHARE,
    RaceSettings,
    default_design,
)
from swarmpath.evidence.race_tests import LookMemo, rank_sum_tests
from swarmpath.evidence.sequential import PairDecision, decide, pair_scores, sign_test

__all__ = ["CLOSING", "DEFAULT_DESIGN", "EVERY_ROUND", "FUTILE", "PAIRS", "SEQUENCE_SHARE",
           "BlockRace", "Duel", "RaceSettings", "closing_rejections", "comparisons_per_block",
           "default_design", "race_block"]

#: The decision of a comparison stopped for futility: not a verdict (its marker is =, as an
#: open comparison's), only the end of its runs.
FUTILE = "futile"


def comparisons_per_block(algorithms: Sequence[str], pairs: str) -> list[tuple[str, str]]:
    """The block's comparisons as (algorithm, other): against the reference (the last name of
    ``algorithms``: order them so) or every pair, in table order."""
    if pairs == "all":
        return list(itertools.combinations(algorithms, 2))
    *others, ref = algorithms
    return [(a, ref) for a in others]


@dataclass(frozen=True)
class Duel:
    """One comparison of a block: ``a`` against ``b``, its latest :class:`PairDecision`, and the
    round that decided it (None while open or when it ran out of runs)."""

    a: str
    b: str
    result: PairDecision
    round: int | None
    #: decided by the closing look at max_runs, not by the confidence sequence
    final: bool = False
    #: open at max_runs under the rank-sum look: its two-sided p there and the side its runs
    #: lean to ("a", "b"; None on a perfect balance); the study's Holm decides (close_race)
    closing_p: float | None = None
    closing_better: str | None = None
    #: decided by the planned look at this many runs (module text), not by the sequence
    look: int | None = None
    #: stopped for futility: its predictive power at that look (module text)
    power: float | None = None

    @property
    def marker(self) -> str:
        """+, = or - for ``a`` against ``b`` (the table's markers): + a better, - a worse, =
        equivalent or undecided."""
        if self.result.decision == "different":
            return "+" if self.result.better == "a" else "-"
        return "="

    def to_json(self) -> dict[str, Any]:
        r = self.result
        return {"a": self.a, "b": self.b, "decision": r.decision, "better":
                None if r.better is None else (self.a if r.better == "a" else self.b),
                "marker": self.marker, "round": self.round, "pairs": r.n, "decided_after": r.at,
                "theta": _number(r.theta), "low": _number(r.low), "high": _number(r.high),
                "final": self.final, "closing_p": self.closing_p, "closing_better":
                None if self.closing_better is None else getattr(self, self.closing_better),
                "look": self.look, "power": self.power}


def _number(v: float) -> float | None:
    """JSON has no NaN: an undefined score or interval (no pairs yet) is null."""
    return v if math.isfinite(v) else None


@dataclass(frozen=True)
class BlockRace:
    """A block's race after the runs given: rounds completed, each cell's allowance (the runs it
    may have now), whether it still races, the round it stopped in and why, and the duels."""

    rounds: int
    allowance: dict[str, int]
    racing: dict[str, bool]
    stopped_round: dict[str, int | None]
    stop_reason: dict[str, str | None]
    duels: list[Duel]

    @property
    def finished(self) -> bool:
        return not any(self.racing.values())

    def runs_used(self) -> int:
        return sum(self.allowance.values())


def race_block(
    values: Mapping[str, ArrayLike],
    algorithms: Sequence[str],
    settings: RaceSettings,
    comparisons: int,
    intervals: bool = True,
    memo: LookMemo | None = None,
) -> BlockRace:
    """Replay a block's race over the values available: ``values[name]`` holds the best values
    of that cell's runs 0, 1, ... in run order (NaN for a run that failed; only runs with a
    result, contiguous from run 0). ``algorithms`` are the block's names with the reference last
    (for ``pairs="reference"``); ``comparisons`` is the number of comparisons of the whole study
    (the Bonferroni divisor). ``intervals=False`` leaves the duels' confidence intervals out
    (NaN; the costly part, which no decision uses: simulations of many races). ``memo`` keeps
    the planned looks' tests from one replay to the next (the same decisions, without testing
    every past look again: :mod:`swarmpath.evidence.race_tests`)."""
    level, final_level = settings.levels(comparisons)
    look_at = settings.look_levels(comparisons)
    # with recycle: the looks' levels per number of the block's comparisons declared (one dict
    # per count, built once per replay, not once per look)
    recycled: dict[int, dict[int, float]] = {0: look_at}
    arrays = {name: np.asarray(values.get(name, ()), dtype=float) for name in algorithms}
    pairs = comparisons_per_block(algorithms, settings.pairs)
    mine = {name: [p for p in pairs if name in p] for name in algorithms}
    decided: dict[tuple[str, str], Duel] = {}
    closing: dict[tuple[str, str], tuple[float, str | None]] = {}
    racing = {name: True for name in algorithms}
    stopped: dict[str, int | None] = {name: None for name in algorithms}
    reason: dict[str, str | None] = {name: None for name in algorithms}
    allowance = {name: settings.allowance(0) for name in algorithms}
    round_ = 0
    while any(racing.values()):
        need = settings.allowance(round_)
        active = [name for name in algorithms if racing[name]]
        for name in active:
            allowance[name] = need
        if any(arrays[name].size < need for name in active):
            break  # the round is not complete: its missing runs are what may be leased now
        looked: list[tuple[str, str, PairDecision]] = []
        for a, b in pairs:
            if (a, b) not in decided and (racing[a] or racing[b]):
                z = pair_scores(arrays[a][:need], arrays[b][:need])
                result = decide(z, level, settings.margin, interval=False)
                if result.decision != "open":
                    decided[(a, b)] = Duel(a, b, result, round_)
                elif need in look_at:
                    looked.append((a, b, result))
                elif settings.closing_alpha and need >= settings.max_runs:
                    # open with both cells at max_runs: the rank-sum look's p (module text)
                    closing[(a, b)] = rank_sum_tests([(arrays[a][:need], arrays[b][:need])])[0]
                elif final_level and need >= settings.max_runs:
                    # open with both cells at max_runs: the one fixed-n look (module text)
                    better = sign_test(z, final_level)
                    if better is not None:
                        decided[(a, b)] = Duel(a, b, PairDecision(
                            result.n, "different", better, result.n, result.theta, math.nan,
                            math.nan), round_, final=True)
        # a planned look: the rank-sum test at its nominal level (module text), all the open
        # comparisons of the round in one vectorized call (they have the same run count)
        samples = [(arrays[a][:need], arrays[b][:need]) for a, b, _ in looked]
        tests = rank_sum_tests(samples) if memo is None else memo.tests(samples)
        pending = list(zip(looked, tests, strict=True))
        while pending:  # with recycle, Holm's step-down: each rejection raises the others' level
            level_now = look_at[need]
            if settings.recycle:
                declared = sum(d.result.decision == "different" for d in decided.values())
                if declared not in recycled:
                    recycled[declared] = settings.look_levels(
                        comparisons, len(pairs) / max(len(pairs) - declared, 1))
                level_now = recycled[declared][need]
            crossed = [(a, b, result, lean) for (a, b, result), (look_p, lean) in pending
                       if look_p < level_now and lean is not None]
            for a, b, result, lean in crossed:
                decided[(a, b)] = Duel(a, b, PairDecision(
                    result.n, "different", lean, result.n, result.theta, math.nan, math.nan),
                    round_, look=need)
            pending = [x for x in pending if x[0][:2] not in decided]
            if not crossed or not settings.recycle:
                break
        for (a, b, result), (look_p, _lean) in pending:
            if settings.futility:  # a comparison the closing look will hardly call stops
                power = predictive_power(look_p, need / settings.max_runs,
                                         settings.closing_alpha)
                if power < settings.futility:
                    decided[(a, b)] = Duel(a, b, PairDecision(
                        result.n, FUTILE, None, result.n, result.theta, math.nan, math.nan),
                        round_, look=need, power=power)
        for name in active:
            if mine[name] and all(p in decided for p in mine[name]):
                racing[name], stopped[name], reason[name] = False, round_, "decided"
            elif need >= settings.max_runs:
                racing[name], stopped[name], reason[name] = False, round_, "max_runs"
        round_ += 1
    duels = []
    for a, b in pairs:
        # the reported interval and score use every pair the two cells have so far
        n = min(allowance[a], allowance[b], arrays[a].size, arrays[b].size)
        result = decide(pair_scores(arrays[a][:n], arrays[b][:n]), level, settings.margin,
                        interval=intervals)
        if (a, b) in decided:
            d = decided[(a, b)].result
            result = PairDecision(result.n, d.decision, d.better, d.at, result.theta,
                                  result.low, result.high)
            duels.append(Duel(a, b, result, decided[(a, b)].round, decided[(a, b)].final,
                              look=decided[(a, b)].look, power=decided[(a, b)].power))
        else:  # a crossing inside an incomplete round waits for the round's end
            p, side = closing.get((a, b), (None, None))
            duels.append(Duel(a, b, _open(result), None, closing_p=p, closing_better=side))
    return BlockRace(round_, allowance, racing, stopped, reason, duels)


def closing_rejections(pvalues: Sequence[float], family: int, alpha: float) -> list[bool]:
    """The rank-sum look's decisions: Holm's step-down procedure at ``alpha`` over ``family``
    hypotheses of which ``pvalues`` are the ones known (every other counts as p = 1, never
    rejected); a hypothesis is rejected where its adjusted p is below ``alpha``, as the full
    study's table marks it (:mod:`swarmpath.evidence.compare`). Holm is monotone: a smaller
    family or smaller p-values only add rejections, so decisions taken while some blocks still
    race stand when they finish."""
    from swarmpath.evidence.markers import holm

    known = list(pvalues)
    if family < len(known):
        raise ValueError(f"a family of {family} cannot hold {len(known)} p-values")
    adjusted = holm(known + [1.0] * (family - len(known)))
    return [bool(q < alpha) for q in adjusted[: len(known)]]


def _open(result: PairDecision) -> PairDecision:
    if result.decision == "open":
        return result
    return PairDecision(result.n, "open", None, 0, result.theta, result.low, result.high)
