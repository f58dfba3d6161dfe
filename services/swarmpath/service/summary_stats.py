"""The statistical tests of a job's summary (docs/statistics.md): plain functions, no I/O.

:func:`benchmark_statistics` and :func:`map_statistics` add the marker and p-value columns to the
summary's rows (in place) and return the ``statistics`` document of ``GET /jobs/{id}/summary``.
The algorithms (planners) are compared in the order of the job spec; the reference is the spec's
``reference`` or, when it is None, the last of them. A partial summary tests the runs finished so
far.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from swarmpath.evidence import report
from swarmpath.evidence.compare_maps import MEASURES, SAMPLED
from swarmpath.evidence.compare_maps import map_statistics as map_tests
from swarmpath.evidence.race_report import race_line
from swarmpath.evidence.tables import test_fields

#: Columns added to the benchmark rows, after the existing ones: the test against the reference,
#: its effect sizes, the Bayesian posterior, and the bold cells (best, similar).
BENCHMARK_TEST_COLUMNS = ("marker", "p", "p_holm", "a12", "shift", "shift_low", "shift_high",
                          "p_better", "p_equivalent", "p_worse", "verdict", "best", "similar")
#: Per sampled measure (length, gap, seconds): A12, the shift and the Bayesian posterior.
MAP_EFFECTS = ("a12", "shift", "p_better", "p_equivalent", "p_worse")
#: Columns added to the map rows: per measure its marker and Holm-adjusted p, then the effects.
MAP_TEST_COLUMNS = (*(f"{m}_{c}" for m in MEASURES for c in ("marker", "p_holm")),
                    *(f"{m}_{c}" for m in SAMPLED for c in MAP_EFFECTS))


def benchmark_statistics(
    rows: list[dict[str, Any]],
    values: Sequence[Sequence[float] | None],
    algorithms: Sequence[str],
    reference: str | None = None,
) -> dict[str, Any]:
    """``rows``: one per cell (algorithm, function, dim); ``values[i]``: row i's best fitness per
    finished run (None or empty: none yet). Adds ``marker``, ``p``, ``p_holm`` to every row."""
    samples = {
        (r["algorithm"], r["function"], int(r["dim"])): list(v)
        for r, v in zip(rows, values, strict=True) if v
    }
    tests = report.benchmark_tests(samples, algorithms, reference)
    index = tests.bayes.index() if tests.bayes is not None else {}
    for r in rows:
        key = (r["function"], int(r["dim"]))
        r.update(test_fields(tests, key, r["algorithm"], index))
        r["best"] = r["algorithm"] in tests.best.get(key, set()) if "avg" in r else None
        r["similar"] = (r["similar"] and not r["best"]) if "avg" in r else None
    return report.tests_to_json(tests)


def map_statistics(
    rows: list[dict[str, Any]],
    runs: Sequence[Sequence[Mapping[str, Any]]],
    planners: Sequence[str],
    reference: str | None = None,
) -> dict[str, Any]:
    """``rows``: one per cell (planner, map); ``runs[i]``: row i's finished runs' metrics (the
    ``swarmpath plan --json`` fields). Adds ``<measure>_marker`` and ``<measure>_p_holm`` (success,
    length, seconds) to every row."""
    records = [
        {**m, "planner": r["planner"], "map": r["map"]}
        for r, cell in zip(rows, runs, strict=True) for m in cell
    ]
    tests = map_tests(records, planners, reference)
    posterior = {m: b.index() for m, b in tests.bayes.items()}
    for r in rows:
        for measure in MEASURES:
            t = tests.comparisons[measure].get(r["map"], r["planner"])
            r[f"{measure}_marker"] = None if t is None else t.marker
            r[f"{measure}_p_holm"] = None if t is None else t.p_holm
        for measure in SAMPLED:
            t = tests.comparisons[measure].get(r["map"], r["planner"])
            post = posterior[measure].get((r["map"], r["planner"]))
            r[f"{measure}_a12"] = None if t is None else t.a12
            r[f"{measure}_shift"] = None if t is None or t.shift is None else t.shift.estimate
            for k in ("p_better", "p_equivalent", "p_worse"):
                r[f"{measure}_{k}"] = None if post is None else getattr(post, k)
    return tests.to_json()


def _p(p: Any) -> str:
    return "-" if not isinstance(p, int | float) else (f"{p:.3g}" if p >= 1e-3 else f"{p:.2e}")


def _friedman_line(label: str, f: Mapping[str, Any]) -> str:
    def rank(a: str, r: Any) -> str:
        if not isinstance(r, int | float):
            return f"{a} -"
        marker = (f["posthoc"].get(a) or {}).get("marker")
        return f"{a} {r:.2f}" + (f" {marker}" if marker else "")

    ranks = ", ".join(rank(a, r) for a, r in f["mean_ranks"].items())
    test = (f"chi2 = {f['statistic']:.3g}, p = {_p(f['p'])}" if f["statistic"] is not None
            else f["note"])
    cd = f"; Nemenyi CD = {f['nemenyi_cd']:.3g}" if f.get("nemenyi_cd") is not None else ""
    return f"Friedman {label} over {f['blocks']} blocks: {test}{cd}; mean ranks {ranks}"


def statistics_lines(summary: Mapping[str, Any]) -> list[str]:
    """The summary's +/=/- counts and Friedman tests as text lines (``swarmpath results`` prints
    them under the table; :mod:`swarmpath.evidence.legend` explains the marker columns)."""
    st = summary.get("statistics")
    if not st:
        return []
    if summary.get("kind") == "benchmark":
        comparisons = {"": st["comparison"]}
        fried = {f"D={f['dim']}": f for f in st["friedman"]}
    else:
        comparisons = {f"{m} ": c for m, c in st["comparisons"].items()}
        fried = {f"({m})": f for m, f in st["friedman"].items()}
    ref = next(iter(comparisons.values()))["reference"]
    if not any(c["counts"] for c in comparisons.values()):
        return []
    lines = []
    for label, c in comparisons.items():
        if not any(sum(n.values()) for n in c["counts"].values()):
            continue  # nothing tested (a gap on maps without an exact optimum)
        counts = ", ".join(f"{a} {n['+']}/{n['=']}/{n['-']}" for a, n in c["counts"].items())
        lines.append(f"{label}+/=/- vs {ref}: {counts}")
    lines += [_friedman_line(label, f) for label, f in fried.items()]
    if st.get("race"):
        lines.append(race_line(st["race"]))
    return lines
