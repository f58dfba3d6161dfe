"""The comparison table under ``swarmpath plan``'s run tables
(:mod:`swarmpath.evidence.compare_maps`).

One row per map and planner: success rate, mean length (successful runs) and mean planning time,
each followed by its marker against the reference planner; then the +/=/- counts per planner and
measure, and the Friedman test over the maps.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rich import box
from rich.table import Table

from swarmpath.evidence.compare_maps import MEASURES, MapStatistics

LABELS = {"success": "success", "length": "length", "gap": "gap", "seconds": "time"}


def _num(v: Any, digits: int) -> str:
    return "-" if v is None else f"{float(v):.{digits}f}"


def render_comparison(
    tests: MapStatistics, summaries: Sequence[Mapping[str, Any]], planners: Sequence[str]
) -> Table:
    """``summaries``: :func:`swarmpath.planners.summary.summarize` rows of the study."""
    ref = tests.reference
    table = Table(title=f"Planners against {ref}", box=box.SIMPLE_HEAD, pad_edge=False)
    names = ["Map", "Planner", "Success", "Length mean (m)", "length A12", "length P(b/e/w)",
             "Gap mean (%)", "gap A12", "gap P(b/e/w)", "Time mean (s)", "time A12",
             "time P(b/e/w)"]
    for name in names:
        table.add_column(name, justify="left" if name in ("Map", "Planner") else "right",
                         no_wrap=True)
    by_cell = {(s["map"], s["planner"]): s for s in summaries}
    maps = list(dict.fromkeys(s["map"] for s in summaries))
    posterior = {m: b.index() for m, b in tests.bayes.items()}
    for i, m in enumerate(maps):
        present = [p for p in planners if (m, p) in by_cell]
        for j, p in enumerate(present):
            s = by_cell[(m, p)]

            def mark(measure: str, m: str = m, p: str = p) -> str:
                return " " + (tests.marker(measure, m, p) or " ")

            def effects(measure: str, m: str = m, p: str = p) -> list[str]:
                t = tests.comparisons[measure].get(m, p)
                post = posterior.get(measure, {}).get((m, p))
                return ["" if t is None or t.a12 is None else f"{t.a12:.2f}",
                        "" if post is None else post.short()]

            gap = None if s.get("gap_mean") is None else 100.0 * s["gap_mean"]
            table.add_row(
                m if j == 0 else "", p,
                f"{s['successes']}/{s['runs']}" + mark("success"),
                _num(s["length_mean"], 4) + mark("length"), *effects("length"),
                _num(gap, 2) + mark("gap"), *effects("gap"),
                _num(s["seconds_mean"], 3) + mark("seconds"), *effects("seconds"),
                end_section=j + 1 == len(present) and i + 1 < len(maps),
            )
    return table


def render_counts(tests: MapStatistics, planners: Sequence[str]) -> Table:
    """Per planner: +/=/- against the reference for each measure, and the Friedman mean ranks."""
    table = Table(box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("planner")
    for measure in MEASURES:
        table.add_column(f"{LABELS[measure]} +/=/-", justify="right")
    for measure in tests.friedman:
        table.add_column(f"{LABELS[measure]} mean rank", justify="right")
    counts = {m: tests.comparisons[m].counts() for m in MEASURES}
    for p in planners:
        cols = [p]
        for measure in MEASURES:
            n = counts[measure].get(p)
            cols.append("ref" if n is None else f"{n['+']}/{n['=']}/{n['-']}")
        for f in tests.friedman.values():
            r = f.mean_ranks.get(p, float("nan"))
            post = f.posthoc.get(p, {}).get("marker", " ")
            cols.append("-" if r != r else f"{r:.2f} {post}")
        table.add_row(*cols)
    return table


def lines(tests: MapStatistics) -> list[str]:
    out = []
    for measure, f in tests.friedman.items():
        text = f"Friedman ({LABELS[measure]}) over {len(f.blocks)} maps: "
        if f.statistic is None:
            text += f.note
        else:
            text += f"chi2 = {f.statistic:.3g}, p = {f.p:.3g}"
        if f.cd is not None and f.blocks:
            text += f"; Nemenyi CD = {f.cd:.3g}"
        out.append(text)
    alpha = tests.comparisons["length"].alpha
    from swarmpath.evidence.benchmark_stats import across_line

    for measure, b in tests.bayes.items():
        out += [across_line(f"({LABELS[measure]})", "maps", b, v) for v in b.across.values()]
    out.append(
        f"+/=/-: significantly better / no significant difference / worse than {tests.reference}"
        f" (success: Fisher's exact test; length and gap over successful runs and time: "
        f"Wilcoxon rank-sum test; each Holm-adjusted over its table, alpha {alpha:g}); A12: "
        f"P(a run beats a run of {tests.reference}); P(b/e/w): posterior probability of better"
        f" / practically equivalent / worse (Bayesian bootstrap per map; its rope in the "
        f"Bayesian lines)"
    )
    return out
