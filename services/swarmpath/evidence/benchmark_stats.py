"""The statistical tests of a benchmark study (:mod:`swarmpath.evidence.compare`): every
algorithm against the reference in every (function, dim) cell, the Friedman test per dimension,
and their text and JSON forms. Used by ``swarmpath bench``, ``reproduce`` and the service's
summary alike; pure functions, no I/O."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from swarmpath.evidence.stats import ALPHA, describe, json_number

# swarmpath.evidence.compare loads scipy.stats (~0.8 s): only when statistics are run
if TYPE_CHECKING:
    from swarmpath.evidence import compare
    from swarmpath.evidence.report import Cell


@dataclass(frozen=True)
class Statistics:
    """The study's tests (:mod:`swarmpath.evidence.compare`): every algorithm against the reference
    in every (function, dim) cell, one Holm family over the whole table, and per dimension the
    Friedman test over the functions on the cells' average best fitness."""

    comparison: compare.Comparison
    friedman: dict[int, compare.Friedman]  # per dim, in table order

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
) -> Statistics:
    """The tests of a study (reference: default the last algorithm; ValueError if unknown)."""
    return benchmark_tests(
        {(c.algorithm, c.function, c.dim): c.best_fitness for c in cells}, algorithms, reference,
        alpha,
    )


def benchmark_tests(
    values: Mapping[tuple[str, str, int], Sequence[float]],
    algorithms: Sequence[str],
    reference: str | None = None,
    alpha: float = ALPHA,
) -> Statistics:
    """:func:`statistics` from the best fitness of the runs per (algorithm, function, dim)
    (NaN: a run without a value; an empty cell is not tested and leaves the Friedman test)."""
    samples: dict[tuple[str, int], dict[str, Sequence[float]]] = {}
    averages: dict[int, dict[str, dict[str, float]]] = {}
    for (algorithm, function, dim), runs in values.items():
        samples.setdefault((function, dim), {})[algorithm] = runs
        arr = np.asarray(runs, dtype=float)
        kept = arr[~np.isnan(arr)]
        avg = describe(kept)["avg"] if kept.size else math.nan
        averages.setdefault(dim, {}).setdefault(function, {})[algorithm] = avg
    from swarmpath.evidence import compare

    comparison = compare.compare_samples(samples, algorithms, reference, alpha)
    ref = comparison.reference
    per_dim = {d: compare.friedman(v, algorithms, ref, alpha) for d, v in averages.items()}
    return Statistics(comparison, per_dim)


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


def legend(tests: Statistics) -> str:
    c = tests.comparison
    return (
        f"+/=/-: significantly better / no significant difference / worse than {c.reference} "
        f"(two-sided Wilcoxon rank-sum test, Holm-adjusted over the table, alpha {c.alpha:g}); "
        f"Friedman columns: mean rank over the functions (1 = best), +/- = differs from "
        f"{c.reference} by Holm's post-hoc test"
    )


def tests_to_json(tests: Statistics) -> dict[str, Any]:
    """The study's tests as JSON: the comparison (every test, its p and Holm-adjusted p, its
    marker, the counts) and the Friedman test per dimension."""

    def clean(v: Any) -> Any:
        if isinstance(v, float):
            return json_number(v)
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, list):
            return [clean(x) for x in v]
        return v

    return clean({
        "comparison": tests.comparison.to_json(key_fields=("function", "dim")),
        "friedman": [{"dim": d, **f.to_json()} for d, f in tests.friedman.items()],
    })
