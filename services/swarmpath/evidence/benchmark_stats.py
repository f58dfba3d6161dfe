"""The statistical tests of a benchmark study (:mod:`swarmpath.evidence.compare`): every
algorithm against the reference in every (function, dim) cell, the Friedman test per dimension,
and their text and JSON forms. Used by ``swarmpath bench``, ``reproduce`` and the service's
summary alike; pure functions, no I/O."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from swarmpath.evidence.stats import ALPHA, STATS, describe, json_clean, location

# swarmpath.evidence.compare loads scipy.stats (~0.8 s): only when statistics are run
if TYPE_CHECKING:
    from swarmpath.evidence import compare
    from swarmpath.evidence.bayes import BayesComparison, Rope
    from swarmpath.evidence.report import Cell


@dataclass(frozen=True)
class Statistics:
    """The study's tests (:mod:`swarmpath.evidence.compare`): every algorithm against the reference
    in every (function, dim) cell, one Holm family over the whole table, with effect sizes; per
    dimension the Friedman test over the functions on the cells' average (or median) best
    fitness; the Bayesian comparison with its rope (:mod:`swarmpath.evidence.bayes`); and per
    cell the best algorithms with those not significantly worse (bold in the tables)."""

    comparison: compare.Comparison
    friedman: dict[int, compare.Friedman]  # per dim, in table order
    bayes: BayesComparison | None = None
    #: (function, dim) -> the best algorithms and those statistically similar to them
    similar: dict[tuple[str, int], set[str]] = field(default_factory=dict)
    stat: str = "mean"
    #: (function, dim) -> the best algorithms by ``stat`` (ties all)
    best: dict[tuple[str, int], set[str]] = field(default_factory=dict)
    #: a raced study's race document (evidence.race_report.with_race): its markers are the
    #: comparison's, its cells' runs, decisions and rounds are in the tables
    race: dict[str, Any] | None = None

    @property
    def reference(self) -> str:
        return self.comparison.reference

    def marker(self, c: Cell) -> str | None:
        return self.comparison.marker((c.function, c.dim), c.algorithm)


def statistics(
    cells: Sequence[Cell],
    algorithms: Sequence[str],
    reference: str | None = None,
    alpha: float = ALPHA,
    stat: str = "mean",
    rope: Rope | None = None,
) -> Statistics:
    """The tests of a study (reference: default the last algorithm; ValueError if unknown)."""
    return benchmark_tests(
        {(c.algorithm, c.function, c.dim): c.best_fitness for c in cells}, algorithms, reference,
        alpha, stat, rope,
    )


def f_star(function: str, dim: int) -> float:
    """The function's minimum at ``dim`` (0 for a name no longer registered)."""
    try:
        from swarmpath.functions import get_function

        return float(get_function(function).f_min_for(dim))
    except (KeyError, ValueError):
        return 0.0


def benchmark_tests(
    values: Mapping[tuple[str, str, int], Sequence[float]],
    algorithms: Sequence[str],
    reference: str | None = None,
    alpha: float = ALPHA,
    stat: str = "mean",
    rope: Rope | None = None,
) -> Statistics:
    """:func:`statistics` from the best fitness of the runs per (algorithm, function, dim)
    (NaN: a run without a value; an empty cell is not tested and leaves the Friedman test).
    ``stat``: what the Friedman test, the bold cells and the Bayesian comparison use (mean or
    median); ``rope``: the Bayesian comparison's (default: :data:`bayes.DEFAULT_ROPE`)."""
    from swarmpath.evidence import bayes, compare

    if stat not in STATS:
        raise ValueError(f"stat must be one of {', '.join(STATS)}, got {stat!r}")
    samples: dict[tuple[str, int], dict[str, Sequence[float]]] = {}
    locations: dict[int, dict[str, dict[str, float]]] = {}
    for (algorithm, function, dim), runs in values.items():
        samples.setdefault((function, dim), {})[algorithm] = runs
        arr = np.asarray(runs, dtype=float)
        kept = arr[~np.isnan(arr)]
        value = location(describe(kept), stat) if kept.size else math.nan
        locations.setdefault(dim, {}).setdefault(function, {})[algorithm] = value
    comparison = compare.compare_samples(samples, algorithms, reference, alpha)
    ref = comparison.reference
    per_dim = {d: compare.friedman(v, algorithms, ref, alpha) for d, v in locations.items()}
    offsets = {key: f_star(*key) for key in samples}
    posterior = bayes.compare_bayes(samples, algorithms, ref, rope or bayes.DEFAULT_ROPE, stat,
                                    offsets, group=lambda key: key[1])
    best, similar = compare.best_and_similar(samples, algorithms, stat, alpha)
    return Statistics(comparison, per_dim, posterior, similar, stat, best)


def format_p(p: float | None) -> str:
    return "-" if p is None else (f"{p:.3g}" if p >= 1e-3 else f"{p:.2e}")


def friedman_lines(tests: Statistics) -> list[str]:
    """One line per dimension: the Friedman statistic, p and Nemenyi critical difference."""
    lines = []
    for dim, f in tests.friedman.items():
        text = f"Friedman D={dim} over {len(f.blocks)} functions: "
        if f.statistic is None:
            text += f.note
        else:
            text += f"chi2 = {f.statistic:.3g}, p = {format_p(f.p)}"
            if f.note:
                text += f" ({f.note})"
        if f.cd is not None:
            text += f"; Nemenyi CD = {f.cd:.3g}"
        lines.append(text)
    return lines


def across_line(label: str, blocks_name: str, b: BayesComparison,
                per: Mapping[str, Mapping[str, Any]]) -> str:
    """One line of the signed-rank test over the blocks of a group (a dimension, the maps)."""
    parts = [f"{a} {v['p_better']:.2f}/{v['p_equivalent']:.2f}/{v['p_worse']:.2f} "
             f"({v['verdict']})" for a, v in per.items()]
    blocks = max((v["blocks"] for v in per.values()), default=0)
    return (f"Bayesian signed-rank {label} over {blocks} {blocks_name}, P(better/equivalent/"
            f"worse) than {b.reference} ({b.stat}, {b.rope.describe()}): " + "; ".join(parts))


def bayes_lines(tests: Statistics) -> list[str]:
    """Per dimension and algorithm: the Bayesian signed-rank test over the functions."""
    b = tests.bayes
    if b is None:
        return []
    return [across_line(f"D={dim}", "functions", b, per) for dim, per in b.across.items()]


def _effects_text(tests: Statistics, raced: bool = False) -> str:
    """What the rows A12, shift, 95% CI and P(b/e/w) mean (the terminal legend and captions);
    ``raced``: the rows of a raced table (no shift: its interval assumes a fixed sample size)."""
    ref = tests.comparison.reference
    rope = f", {tests.bayes.rope.describe()}" if tests.bayes is not None else ""
    shift = "" if raced else (f"shift: Hodges-Lehmann estimate of (algorithm - {ref}) with its "
                              "95 % interval; ")
    return (f"A12: Vargha-Delaney probability that a run beats a run of {ref} (0.5: no effect); "
            f"{shift}P(b/e/w): posterior probabilities of better / practically equivalent / worse "
            f"(Bayesian bootstrap of the {tests.stat}{rope}; decision at 0.95)")


def legend(tests: Statistics) -> str:
    c = tests.comparison
    what = "median" if tests.stat == "median" else "avg"
    if tests.race is not None:
        from swarmpath.evidence.race_report import race_legend

        return (f"{race_legend(tests.race, c.reference)}; * the best {what} (bold); "
                f"{_effects_text(tests, raced=True)}; Friedman columns: mean rank over the "
                f"functions (1 = best), +/- = differs from {c.reference} by Holm's post-hoc test")
    return (
        f"+/=/-: significantly better / no significant difference / worse than {c.reference} "
        f"(two-sided Wilcoxon rank-sum test, Holm-adjusted over the table, alpha {c.alpha:g}); "
        f"* the best {what}, ~ not significantly worse than it (the same test; both bold); "
        f"{_effects_text(tests)}; Friedman columns: mean rank over the functions (1 = best), "
        f"+/- = differs from {c.reference} by Holm's post-hoc test"
    )


def tests_to_json(tests: Statistics) -> dict[str, Any]:
    """The study's tests as JSON: the comparison (every test, its p and Holm-adjusted p, its
    marker, the counts) and the Friedman test per dimension."""
    if tests.race is not None:
        from swarmpath.evidence.race_report import comparison_json

        comparison = comparison_json(tests.race, tests.comparison.algorithms,
                                     tests.comparison.reference)
    else:
        comparison = tests.comparison.to_json(key_fields=("function", "dim"))
    doc = {
        "stat": tests.stat,
        "comparison": comparison,
        "friedman": [{"dim": d, **f.to_json()} for d, f in tests.friedman.items()],
        "similar": [{"function": f, "dim": d, "best": sorted(tests.best.get((f, d), ())),
                     "algorithms": sorted(names)} for (f, d), names in tests.similar.items()],
    }
    if tests.bayes is not None:
        doc["bayes"] = tests.bayes.to_json(("function", "dim"), "dim")
    if tests.race is not None:
        doc["race"] = tests.race
    return json_clean(doc)


def latex_legend(tests: Statistics) -> str:
    """What a LaTeX table's bold cells, superscripts and effect rows mean (its caption)."""
    c = tests.comparison
    what = "median" if tests.stat == "median" else "mean"
    if tests.race is not None:
        from swarmpath.evidence.race_report import race_legend

        return (f"Bold: the best {what}. Superscript {race_legend(tests.race, c.reference)}. "
                f"{_effects_text(tests, raced=True)}.")
    return (
        f"Bold: the best {what} and those not significantly worse (two-sided Wilcoxon "
        f"rank-sum test against the best, Holm-adjusted, alpha {c.alpha:g}). Superscript "
        f"+/=/-: significantly better / no significant difference / worse than {c.reference} "
        f"(the same test, Holm-adjusted over the table). {_effects_text(tests)}."
    )
