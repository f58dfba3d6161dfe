"""The invariance certificate of a planner on a map (pure functions over run records).

``swarmpath audit --maps`` runs every planner on a map and on its symmetric copies
(:mod:`swarmpath.world.symmetry`: rotated by 90, 180 and 270 degrees, mirrored, translated, start
and goal swapped), the same runs and seeds each. A planner that favours no place and no
direction gives each copy the same success rate and the same gap to the copy's exact optimum,
up to chance. Per copy the certificate tests both against the original:

* success: Fisher's exact test (two-sided) of the success counts;
* gap: the two-sided Wilcoxon rank-sum test of the successful runs' gaps (length / the copy's
  exact optimum - 1);

Holm-adjusted over the tests of one planner on one map. A copy *moves* the planner when a test
is significant at ``alpha`` **and** its effect is at least the stated tolerance (the success
rate changes by ``success_tolerance`` or more, or the median gap by ``gap_tolerance`` or more):
deterministic planners repeat values up to rounding, which a rank test alone would call
different. The verdict is ``invariant`` when no copy moves it, else ``biased`` with the copies
that did; too few successful runs to test a gap is said, not hidden.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

# scipy.stats (about 1 s to import) is imported by the functions that test: a coordinator
# imports this module at its start, for summaries it computes only when asked.
from swarmpath.evidence.compare import rank_sum
from swarmpath.evidence.markers import holm

ALPHA = 0.05
#: A copy moves the planner only when the median gap changes by at least this much (0.01 = one
#: percentage point of excess length) ...
GAP_TOLERANCE = 0.01
#: ... or the success rate by at least this much.
SUCCESS_TOLERANCE = 0.2

__all__ = ["ALPHA", "GAP_TOLERANCE", "SUCCESS_TOLERANCE", "CopyTest", "MapCertificate",
           "certify"]


def _gaps(runs: Sequence[Mapping[str, Any]]) -> list[float]:
    out = []
    for r in runs:
        g = r.get("gap")
        if r.get("success") is True and isinstance(g, int | float) and math.isfinite(g):
            out.append(float(g))
    return out


def _lengths(runs: Sequence[Mapping[str, Any]]) -> list[float]:
    return [float(r["length"]) for r in runs if r.get("success") is True]


@dataclass
class CopyTest:
    """One copy against the original: counts, medians, the tests and whether it moved."""

    transform: str
    runs: int
    successes: int
    gap_median: float | None
    length_median: float | None
    optimum: float | None
    p_success: float | None = None
    p_gap: float | None = None
    p_success_holm: float | None = None
    p_gap_holm: float | None = None
    moved: bool = False
    why: str = ""


@dataclass
class MapCertificate:
    """A planner on one map: the original, every copy, and the verdict."""

    planner: str
    map: str
    original: CopyTest
    copies: list[CopyTest] = field(default_factory=list)
    verdict: str = "invariant"
    note: str = ""

    @property
    def moved(self) -> list[str]:
        return [c.transform for c in self.copies if c.moved]

    def to_json(self) -> dict[str, Any]:
        return {"planner": self.planner, "map": self.map, "verdict": self.verdict,
                "moved": self.moved, "note": self.note, "original": asdict(self.original),
                "copies": [asdict(c) for c in self.copies]}


def _summary(transform: str, runs: Sequence[Mapping[str, Any]]) -> CopyTest:
    gaps, lengths = _gaps(runs), _lengths(runs)
    optimum = next((float(r["optimum"]) for r in runs if r.get("optimum") is not None), None)
    return CopyTest(transform, len(runs), sum(r.get("success") is True for r in runs),
                    statistics.median(gaps) if gaps else None,
                    statistics.median(lengths) if lengths else None, optimum)


def certify(planner: str, map_name: str, original: Sequence[Mapping[str, Any]],
            copies: Mapping[str, Sequence[Mapping[str, Any]]], alpha: float = ALPHA,
            gap_tolerance: float = GAP_TOLERANCE,
            success_tolerance: float = SUCCESS_TOLERANCE) -> MapCertificate:
    """The certificate of ``planner`` on ``map_name`` from the runs on the original and on each
    copy (transform -> runs); see the module docstring."""
    from scipy import stats
    base = _summary("none", original)
    base_gaps = _gaps(original)
    tests: list[CopyTest] = []
    raw: list[tuple[int, str, float]] = []  # (copy index, "success" | "gap", p)
    for transform, runs in copies.items():
        t = _summary(transform, runs)
        if t.runs and base.runs:
            table = [[t.successes, t.runs - t.successes],
                     [base.successes, base.runs - base.successes]]
            t.p_success = float(stats.fisher_exact(table, alternative="two-sided").pvalue)
            raw.append((len(tests), "success", t.p_success))
        gaps = _gaps(runs)
        if len(gaps) >= 2 and len(base_gaps) >= 2:
            test = rank_sum(gaps, base_gaps)
            if test is not None:
                t.p_gap = test[1]
                raw.append((len(tests), "gap", t.p_gap))
        tests.append(t)
    adjusted = holm(np.array([p for _, _, p in raw])) if raw else np.array([])
    for (i, what, _), p in zip(raw, adjusted, strict=True):
        setattr(tests[i], f"p_{what}_holm", float(p))
    for t in tests:
        reasons = []
        rate, base_rate = t.successes / t.runs if t.runs else 0.0, (
            base.successes / base.runs if base.runs else 0.0)
        if (t.p_success_holm is not None and t.p_success_holm < alpha
                and abs(rate - base_rate) >= success_tolerance):
            reasons.append(f"success {base.successes}/{base.runs} -> {t.successes}/{t.runs}")
        if (t.p_gap_holm is not None and t.p_gap_holm < alpha and t.gap_median is not None
                and base.gap_median is not None
                and abs(t.gap_median - base.gap_median) >= gap_tolerance):
            reasons.append(f"median gap {100 * base.gap_median:.2f} % -> "
                           f"{100 * t.gap_median:.2f} %")
        t.moved, t.why = bool(reasons), "; ".join(reasons)
    cert = MapCertificate(planner, map_name, base, tests)
    if cert.moved:
        cert.verdict = "biased"
    untested = [t.transform for t in tests if t.p_gap is None]
    if untested:
        cert.note = (f"gap not tested on {', '.join(untested)}: fewer than 2 successful runs "
                     "on the copy or the original")
    return cert
