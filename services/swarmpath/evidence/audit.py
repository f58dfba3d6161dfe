"""Origin-bias audit: how much an optimizer loses when the optimum leaves the origin.

Pure functions over best values (no I/O). For every optimizer, function and dimension a study
runs the function plain, shifted and shifted+rotated (:data:`AUDIT_TRANSFORMS`, the same runs and
seeds); per transform the *decades lost* on a function are log10(mean gap transformed / mean gap
plain), the gap being best - f_min (f_min per dimension for F8) and a mean gap below
:data:`GAP_FLOOR` counted as the floor (an exact 0 would make the ratio infinite). Per optimizer
the audit reports the median over functions of the decades lost, the number of functions losing
more than one and more than three decades, and how many plain runs ended at exactly 0.

Kudela's centre-bias index (J. Kudela, "A critical problem in benchmarking and analysis of
evolutionary computation methods", Nature Machine Intelligence 4 (2022) 1238-1245, and "The
evolutionary computation methods no one should use", arXiv:2301.01984, 2023) is the geometric
mean over the functions (his 13: F1-F13) of mean error shifted / mean error unshifted, i.e.
10 ** (mean decades lost under ``shift``): :meth:`AuditRow.centre_bias_index`; above
:data:`KUDELA_BIASED` (10) the method is centre-biased by his criterion.

A cell is *origin-suspect* by measurement (:func:`shift_suspect`, what ``swarmpath reproduce``
marks) when it loses more than :data:`SUSPECT_DECADES` decades under ``shift`` -- the same runs
and seeds with the optimum moved -- i.e. when the optimizer owes more than a factor 1000 of its
mean gap to where the optimum was. Three decades, not one: PSO, without any move toward the
origin, loses at most 0.5 decades in a cell of icoot-table2 (30 runs) and SSA at most 1.0 but
on F2 (3.9, one shifted run of 30), while the origin-pulling moves of the COOT family lose
7-30 decades there, every plain run below every shifted one (docs/statistics.md).
Without a shifted study, :func:`origin_suspect` is the cheap hint ``bench`` and the service
print: some run ended at exactly 0 or below :data:`SUSPECT_BELOW` on a function whose optimum is
at the origin (such values usually come from a move that scales positions toward 0).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from swarmpath.functions import get_function

AUDIT_TRANSFORMS: tuple[str, ...] = ("none", "shift", "shift+rotate")
GAP_FLOOR = 1e-300
SUSPECT_BELOW = 1e-100
SUSPECT_DECADES = 3.0
#: Kudela's threshold: an index above it marks a centre-biased method
KUDELA_BIASED = 10.0
ORIGIN_MARK = "°"
ORIGIN_FOOTNOTE = (
    f"{ORIGIN_MARK} origin-suspect: exact zeros or values below {SUSPECT_BELOW:g} on a function "
    "whose optimum is at the origin; rerun with --transform shift to see the search without it."
)


def optimum_at_origin(function: str) -> bool:
    """True for the registered functions whose minimiser is the origin."""
    f = get_function(function)
    if not f.has_optimum:
        return False
    dim = f.dimensions[0] if f.dimensions else max(2, f.min_dim)
    return bool(np.all(f.base_optimum(dim) == 0.0))


def origin_suspect(function: str, values: Iterable[float]) -> bool:
    """A plain cell whose runs reached exact zeros or values below SUSPECT_BELOW while the
    function's optimum is at the origin."""
    if not optimum_at_origin(function):
        return False
    f_min = get_function(function).f_min
    return any(v - f_min < SUSPECT_BELOW for v in values if math.isfinite(v))


SHIFT_FOOTNOTE = (
    f"{ORIGIN_MARK} origin-suspect: the cell's mean gap to the optimum grows by more than "
    f"{SUSPECT_DECADES:g} decades when the function is shifted (the same runs and seeds with "
    "the optimum moved, as `swarmpath audit` computes): its result owes that much to where "
    "the optimum was."
)


def mean_gap(function: str, dim: int, values: Sequence[float]) -> float:
    """Mean of best - f_min over the runs, at least GAP_FLOOR."""
    f_min = get_function(function).f_min_for(dim)
    gaps = np.maximum(np.asarray(values, dtype=float) - f_min, 0.0)
    return max(float(np.mean(gaps)), GAP_FLOOR)


def decades_lost(function: str, dim: int, plain: Sequence[float],
                 moved: Sequence[float]) -> float:
    """log10(mean gap moved / mean gap plain): what the transform costs the cell."""
    return math.log10(mean_gap(function, dim, moved) / mean_gap(function, dim, plain))


def shift_suspect(lost: float | None) -> bool:
    """Origin-suspect by measurement: more than SUSPECT_DECADES decades lost under shift."""
    return lost is not None and lost > SUSPECT_DECADES


@dataclass
class AuditRow:
    algorithm: str
    dim: int
    #: transform -> function -> decades lost against plain
    decades: dict[str, dict[str, float]] = field(default_factory=dict)
    exact_zeros: int = 0  # plain runs that ended at exactly 0
    plain_runs: int = 0

    def median(self, transform: str) -> float:
        return float(np.median(list(self.decades[transform].values())))

    def centre_bias_index(self, transform: str = "shift") -> float:
        """Kudela's index: the geometric mean over the functions of mean gap ``transform`` /
        mean gap plain (10 ** the mean decades lost)."""
        return float(10.0 ** np.mean(list(self.decades[transform].values())))

    def centre_biased(self) -> bool:
        return self.centre_bias_index() > KUDELA_BIASED

    def losing(self, transform: str, more_than: float) -> int:
        return sum(d > more_than for d in self.decades[transform].values())

    def to_json(self) -> dict[str, object]:
        return {
            "algorithm": self.algorithm,
            "dim": self.dim,
            "exact_zeros": self.exact_zeros,
            "plain_runs": self.plain_runs,
            "centre_bias_index": self.centre_bias_index(),
            "centre_biased": self.centre_biased(),
            "transforms": {
                t: {
                    "median_decades_lost": self.median(t),
                    "functions_losing_more_than_1": self.losing(t, 1.0),
                    "functions_losing_more_than_3": self.losing(t, 3.0),
                    "decades_lost": per,
                }
                for t, per in self.decades.items()
            },
        }


Key = tuple[str, str, int, str]  # (algorithm, function, dim, transform)


def audit(
    values: Mapping[Key, Sequence[float]],
    algorithms: Sequence[str],
    functions: Sequence[str],
    dims: Sequence[int],
) -> list[AuditRow]:
    """One row per (algorithm, dim) from the best values of every (algorithm, function, dim,
    transform) of :data:`AUDIT_TRANSFORMS` that was run (every function needs 'none'; for a
    suite function 'none' is its instance translated to the origin and 'shift' the instance
    itself, as ``swarmpath audit`` runs them)."""
    rows = []
    for a in algorithms:
        for d in dims:
            row = AuditRow(a, d)
            for f in functions:
                plain = values[(a, f, d, "none")]
                row.exact_zeros += sum(v == 0.0 for v in plain)
                row.plain_runs += len(plain)
                for t in AUDIT_TRANSFORMS[1:]:
                    if (a, f, d, t) in values:  # a suite function has no shift+rotate
                        row.decades.setdefault(t, {})[f] = decades_lost(
                            f, d, plain, values[(a, f, d, t)])
            rows.append(row)
    return rows
