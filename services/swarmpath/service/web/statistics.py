"""The dashboard's statistics of a job, from its aggregates: +/=/- markers against the job's
reference and Friedman mean ranks (:mod:`swarmpath.compare`, imported on first use: scipy)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np


def benchmark_statistics(
    samples: Mapping[tuple[str, int], Mapping[str, np.ndarray]],
    groups: Mapping[tuple[str, int], Mapping[str, Any]],
    algorithms: Sequence[str],
    reference: str | None = None,
) -> dict[str, Any] | None:
    """+/=/- of every algorithm against ``reference`` (default: the last one listed) per
    function x dim (Wilcoxon rank-sum, Holm over the table) and Friedman mean ranks per dimension
    (:mod:`swarmpath.compare`). None with fewer than two algorithms."""
    if len(algorithms) < 2:
        return None
    from swarmpath.compare import compare_samples, friedman

    comparison = compare_samples(samples, algorithms, reference)
    markers: dict[str, dict[str, str]] = {}
    for (function, dim), per in samples.items():
        for a in per:
            m = comparison.marker((function, dim), a)
            if m is not None:
                markers.setdefault(f"{function}/{dim}", {})[a] = m
    ranks: dict[str, Any] = {}
    for dim in sorted({d for _, d in groups}):
        values = {f: g["means"] for (f, d), g in groups.items() if d == dim}
        fr = friedman(values, algorithms, reference)
        ranks[str(dim)] = {"mean_ranks": fr.mean_ranks, "p": fr.p, "blocks": len(fr.blocks),
                           "note": fr.note}
    return {"test": comparison.test, "reference": comparison.reference,
            "alpha": comparison.alpha, "markers": markers, "counts": comparison.counts(),
            "friedman": ranks}


def map_statistics(
    groups: Mapping[str, Mapping[str, Any]], planners: Sequence[str],
    reference: str | None = None,
) -> dict[str, Any] | None:
    """Success rates of every planner against ``reference`` (default: the last one) per map:
    Fisher's exact test, Holm over the table (:mod:`swarmpath.compare`)."""
    if len(planners) < 2:
        return None
    from swarmpath.compare import compare_success

    counts = {name: {p: (v["succeeded"], v["runs"] - v["crashed"])
                     for p, v in g["planners"].items()} for name, g in groups.items()}
    comparison = compare_success(counts, planners, reference)
    markers: dict[str, dict[str, str]] = {}
    for name, per in counts.items():
        for p in per:
            m = comparison.marker(name, p)
            if m is not None:
                markers.setdefault(name, {})[p] = m
    return {"test": comparison.test, "reference": comparison.reference,
            "alpha": comparison.alpha, "markers": markers, "counts": comparison.counts()}
