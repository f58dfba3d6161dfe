"""A race as a document and in a study's tables: pure functions shared by the service (its store,
``GET /jobs/{id}/race``, the summary) and ``swarmpath bench --race``, so both show the same thing.

The race document: ``{"settings", "comparisons", "blocks": [{"block", "rounds", "finished",
"cells": [{"cell", "algorithm", "runs", "racing", "stopped_round", "reason", "key",
"finished_runs"}], "duels": [Duel.to_json()]}]}``; a block's ``block`` holds at least its
``function`` and ``dim`` (the service: every field its cells share).

In a raced study's table the markers are the race's decisions against the reference, never a
rank-sum test (after optional stopping its p-value means nothing): :func:`with_race` gives a
study's :class:`~swarmpath.evidence.benchmark_stats.Statistics` the race's comparison,
:func:`apply_race` does the same to a job summary's rows. Fixed-sample-size intervals (the
Hodges-Lehmann shift's) and the "not significantly worse than the best" marks are left out for
the same reason; A12, the shift's estimate and the Bayesian posterior stay (estimates, and a
posterior, do not depend on the stopping rule).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, cast

from swarmpath.evidence.racing import EVERY_ROUND, BlockRace, RaceSettings, closing_rejections

if TYPE_CHECKING:
    from swarmpath.evidence.benchmark_stats import Statistics

#: Columns a raced study's rows add: the runs its race gave the cell, whether it still races
#: (``racing``) or why it stopped (``decided``, ``max_runs``), the round it stopped in, its
#: decision against the reference (``different``, ``equivalent``, ``open``) and that
#: comparison's paired score theta with its confidence-sequence interval.
RACE_COLUMNS = ("race_runs", "race_state", "race_round", "race_decision", "race_theta",
                "race_low", "race_high")
RACE_TEST = "race: betting confidence sequence on P(run beats reference's run)"

__all__ = ["RACE_COLUMNS", "RACE_TEST", "apply_race", "block_json", "cell_fields", "close_race",
           "comparison_json", "first_round_json", "race_legend", "race_line", "study_race",
           "with_race"]


def block_json(race: BlockRace, members: Sequence[tuple[int, str]]) -> dict[str, Any]:
    """A block's part of the race document (without ``block``, ``key`` and ``finished_runs``):
    ``members`` are its cells as (cell index, algorithm) in race order."""
    return {
        "rounds": race.rounds,
        "finished": race.finished,
        "cells": [{"cell": i, "algorithm": name, "runs": race.allowance[name],
                   "racing": race.racing[name], "stopped_round": race.stopped_round[name],
                   "reason": race.stop_reason[name]} for i, name in members],
        "duels": [d.to_json() for d in race.duels],
    }


def first_round_json(settings: RaceSettings, members: Sequence[tuple[int, str]]
                     ) -> dict[str, Any]:
    """:func:`block_json` of a block that has no round completed yet."""
    return {"rounds": 0, "finished": False, "duels": [],
            "cells": [{"cell": i, "algorithm": name, "runs": settings.allowance(0),
                       "racing": True, "stopped_round": None, "reason": None}
                      for i, name in members]}


def close_race(race: dict[str, Any]) -> dict[str, Any]:
    """The race document with the rank-sum look's decisions (``final_test: rank-sum``; any other
    race is returned as it is). The look spans blocks, so it is taken here, over the whole
    study, and not in a block's replay: Holm at :attr:`RaceSettings.closing_alpha` over the
    study's comparisons that the confidence sequence has not declared different, the p-values
    those still open at ``max_runs`` got there (``closing_p``; the others count as 1). A duel it
    rejects becomes a difference with ``final: true``, decided in its block's last round after
    its ``max_runs`` pairs. A pure function of the document; while blocks still race its
    decisions are a subset of the finished study's (:func:`closing_rejections`)."""
    settings = race["settings"]
    if settings.get("final_test") != "rank-sum":
        return race
    blocks = [{**b, "duels": [dict(d) for d in b.get("duels", ())]} for b in race["blocks"]]
    duels = [(b, d) for b in blocks for d in b["duels"]]
    declared = sum(d["decision"] == "different" and not d["final"] for _, d in duels)
    looked = [(b, d) for b, d in duels if d.get("closing_p") is not None]
    rejected = closing_rejections([float(d["closing_p"]) for _, d in looked],
                                  int(race["comparisons"]) - declared,
                                  RaceSettings(**settings).closing_alpha)
    for (b, d), reject in zip(looked, rejected, strict=True):
        if reject and d["closing_better"] is not None:
            d.update(decision="different", better=d["closing_better"], final=True,
                     marker="+" if d["closing_better"] == d["a"] else "-",
                     round=b["rounds"] - 1, decided_after=d["pairs"])
    return {**race, "blocks": blocks}


def study_race(settings: RaceSettings, comparisons: int,
               blocks: Sequence[tuple[Mapping[str, Any], BlockRace, Sequence[tuple[int, str]]]]
               ) -> dict[str, Any]:
    """The race document of a study's blocks, each given as (what its cells share, its
    :func:`~swarmpath.evidence.racing.race_block`, its members), the closing look taken."""
    return close_race({"settings": settings.to_json(), "comparisons": comparisons, "blocks": [
        {"block": dict(block), **block_json(race, members)} for block, race, members in blocks]})


CellKey = tuple[str, int, str]  # (function, dim, algorithm)


def cell_fields(race: Mapping[str, Any], reference: str
                ) -> dict[CellKey, tuple[dict[str, Any], dict[str, Any] | None]]:
    """Per (function, dim, algorithm): its :data:`RACE_COLUMNS` and its duel against
    ``reference`` seen from its side (None for the reference itself)."""
    out: dict[CellKey, tuple[dict[str, Any], dict[str, Any] | None]] = {}
    for block in race["blocks"]:
        vs_ref: dict[str, dict[str, Any]] = {}
        for d in block["duels"]:
            if d["b"] == reference:
                vs_ref[d["a"]] = d
            elif d["a"] == reference:
                vs_ref[d["b"]] = _flipped(d)
        function, dim = block["block"]["function"], int(block["block"]["dim"])
        for c in block["cells"]:
            duel = vs_ref.get(c["algorithm"])
            fields = {
                "race_runs": c["runs"],
                "race_state": "racing" if c["racing"] else c["reason"],
                "race_round": c["stopped_round"],
                "race_decision": None if duel is None else duel["decision"],
                "race_theta": None if duel is None else duel["theta"],
                "race_low": None if duel is None else duel["low"],
                "race_high": None if duel is None else duel["high"],
            }
            out[(function, dim, c["algorithm"])] = (fields, duel)
    return out


def comparison_json(race: Mapping[str, Any], algorithms: Sequence[str],
                    reference: str) -> dict[str, Any]:
    """The ``statistics.comparison`` of a raced study: per cell against the reference its
    marker, decision, round, pairs and paired score with its interval; counts of +/=/-."""
    counts = {a: {"+": 0, "=": 0, "-": 0} for a in algorithms if a != reference}
    tests = []
    for (function, dim, algorithm), (_fields, duel) in cell_fields(race, reference).items():
        if duel is None:
            continue
        counts[algorithm][duel["marker"]] += 1
        tests.append({"function": function, "dim": dim, "algorithm": algorithm,
                      "n": duel["pairs"], "marker": duel["marker"],
                      "decision": duel["decision"], "round": duel["round"],
                      "theta": duel["theta"], "low": duel["low"], "high": duel["high"]})
    return {"test": RACE_TEST, "reference": reference, "alpha": race["settings"]["alpha"],
            "correction": "bonferroni", "comparisons": race["comparisons"],
            "lower_is_better": True, "counts": counts, "tests": tests}


def apply_race(rows: list[dict[str, Any]], race: dict[str, Any], algorithms: Sequence[str],
               reference: str | None) -> dict[str, Any]:
    """A raced study's summary rows (one per cell, with ``algorithm``, ``function``, ``dim``):
    each gets :data:`RACE_COLUMNS`, its marker from the race against the reference, and no
    rank-sum p-values, shift interval or similar-to-the-best flag; returns the statistics'
    ``comparison`` (:func:`comparison_json`) and ``race``."""
    ref = reference or algorithms[-1]
    fields = cell_fields(race, ref)
    for row in rows:
        hit = fields.get((row["function"], int(row["dim"]), row["algorithm"]))
        if hit is None:
            continue
        row.update(hit[0])
        row["marker"] = None if hit[1] is None else hit[1]["marker"]
        row.update(p=None, p_holm=None, shift_low=None, shift_high=None, similar=False)
    return {"comparison": comparison_json(race, algorithms, ref), "race": race}


def with_race(tests: Statistics, race: dict[str, Any]) -> Statistics:
    """A study's tests with the race's markers in place of the rank-sum tests' (each test's
    A12 and shift estimate kept, its p-values and shift interval dropped), no similar-to-the-best
    marks, and the race document (``tests.race``)."""
    from swarmpath.evidence.compare import Comparison
    from swarmpath.evidence.effect import Shift

    comparison = tests.comparison
    fields = cell_fields(race, comparison.reference)
    kept = []
    for t in comparison.tests:
        function, dim = cast(tuple[str, int], t.key)
        hit = fields.get((function, int(dim), t.algorithm))
        duel = None if hit is None else hit[1]
        shift = (None if t.shift is None else
                 Shift(t.shift.estimate, math.nan, math.nan, t.shift.confidence))
        kept.append(dataclasses.replace(t, p=None, p_holm=None, statistic=None, shift=shift,
                                        marker=None if duel is None else duel["marker"]))
    raced = Comparison(RACE_TEST, comparison.algorithms, comparison.reference,
                       race["settings"]["alpha"], comparison.lower_is_better, tuple(kept),
                       correction="bonferroni")
    return dataclasses.replace(tests, comparison=raced, similar={}, race=race)


def race_legend(race: Mapping[str, Any], reference: str) -> str:
    """What a raced table's markers and race rows mean (the terminal legend, LaTeX captions)."""
    s = race["settings"]
    equiv = f"equiv: within {s['margin']:g} of 1/2, " if s["margin"] else ""
    if s.get("futility"):  # jobs stored before futility existed have no such setting
        equiv += (f"futile: stopped at a look where the chance that the closing look calls "
                  f"it (predictive power) was below {s['futility']:g}, = not a verdict, ")
    final = _closing_words(s)
    return (f"+/=/-: better / not decided different / worse than {reference} as the race "
            f"decided it (anytime-valid betting confidence sequence on the probability that a "
            f"run beats {reference}'s run of the same index, alpha {s['alpha']:g} over the "
            f"study's {race['comparisons']} comparisons, Bonferroni{final}; docs/statistics.md, "
            f"Racing); A paired: that probability and its interval; race: the runs the cell "
            f"got, its decision against {reference} (diff, {equiv}open) and the round rK it "
            f"stopped in (min_runs {s['min_runs']} + K x batch {s['batch']} runs, at most "
            f"{s['max_runs']})")


def race_line(race: Mapping[str, Any]) -> str:
    """One line on a race: cells stopped, runs used against the unraced study's."""
    cells = [c for b in race["blocks"] for c in b["cells"]]
    used = sum(c["runs"] for c in cells)
    full = race["settings"]["max_runs"] * len(cells)
    stopped = sum(not c["racing"] for c in cells)
    decided = sum(c["reason"] == "decided" for c in cells)
    s = race["settings"]
    final = {"rank-sum": ", closing rank-sum test", "sign": ", closing sign test"}.get(
        _closing(s), "")
    if _look_runs(s, ","):
        final += f", looks {_look_runs(s, ',')} ({s['spending']})"
    if s.get("recycle"):
        final += ", shares recycled in blocks"
    if s.get("futility"):
        final += f", futility below {s['futility']:g}"
    return (f"race (alpha {s['alpha']:g} over {race['comparisons']} comparisons, min_runs "
            f"{s['min_runs']}, batch {s['batch']}, margin {s['margin']:g}{final}): {stopped}/"
            f"{len(cells)} cells stopped ({decided} decided), {used} runs of {full} "
            f"({full / max(used, 1):.1f}x fewer)")


def _closing(settings: Mapping[str, Any]) -> str:
    """The race's closing look; a document written before it had a name holds a boolean."""
    look = settings.get("final_test", "none")
    return ("sign" if look else "none") if isinstance(look, bool) else str(look)


def _look_runs(settings: Mapping[str, Any], sep: str) -> str:
    """Where the planned looks are: 'at N, N, ...', 'every round from N', or '' (none)."""
    looks = settings.get("looks")
    if looks == EVERY_ROUND:
        first = settings["min_runs"] + settings["batch"]
        return f"every round from {first}" if first < settings["max_runs"] else ""
    return "at " + sep.join(str(n) for n in looks) if looks else ""


def _closing_words(settings: Mapping[str, Any]) -> str:
    """The planned looks and the closing look in a legend."""
    look, runs = _closing(settings), settings["max_runs"]
    looks = ""
    if _look_runs(settings, ", "):
        looks = (f"; {_look_runs(settings, ', ')} runs the rank-sum test of each open "
                 f"comparison, {settings['look_share']:g} of alpha spent across these looks "
                 f"({settings['spending']} type)")
        if settings.get("recycle"):  # documents written before recycling have no such key
            looks += (", the share of a comparison declared different passed to the open "
                      "ones of its block (Holm)")
    if look == "rank-sum":
        return (f"{looks}; the comparisons still open at {runs} runs: the rank-sum test there, "
                f"Holm at {RaceSettings(**settings).closing_alpha:g} over those not declared "
                f"different (the sequence at {settings.get('sequence_share', 0.5):g} of alpha)")
    if look == "sign":
        return f", half of it to one sign test at {runs} runs for the comparisons still open there"
    return looks


def _flipped(d: Mapping[str, Any]) -> dict[str, Any]:
    """A duel seen from its other side: its marker and interval mirrored."""
    flip = {"+": "-", "-": "+", "=": "="}

    def mirror(v: float | None) -> float | None:
        return None if v is None else 1.0 - v

    return {**d, "a": d["b"], "b": d["a"], "marker": flip[d["marker"]],
            "theta": mirror(d["theta"]), "low": mirror(d["high"]), "high": mirror(d["low"])}
