"""Group-sequential boundaries: a two-sided test looked at a few times, at run counts planned
before the data, with its error rate spent across the looks (Lan and DeMets, Biometrika 70
(1983) 659-663; Jennison and Turnbull, *Group Sequential Methods with Applications to Clinical
Trials*, 2000, ch. 7 and 19).

The statistic. At look k, after n_k runs of both algorithms, Z_k is the standardized two-sided
rank-sum statistic of the first n_k runs of each (what :func:`swarmpath.evidence.compare.rank_sum`
tests). Under the null (the two algorithms' runs i.i.d. from one distribution) the Hajek
projection of the U statistic is a sum over the runs, so (Z_1, ..., Z_K) is asymptotically
multivariate normal with corr(Z_i, Z_j) = sqrt(n_i / n_j), i <= j: the increments of a Brownian
motion W at the information times t_k = n_k / n_K (Z_k = W(t_k) / sqrt(t_k)). A boundary
c_1, ..., c_K rejects at the first k with |Z_k| >= c_k, i.e. where the look's two-sided p-value
is below p_k = 2 (1 - Phi(c_k)).

Spending. The boundary is chosen so that the probability of a first crossing at look k under the
null is alpha(t_k) - alpha(t_{k-1}), for a spending function alpha(t) increasing from 0 to the
test's level at t = 1; the probability of any crossing is then exactly the level, whatever the
looks (asymptotically). Two are offered:

- ``obrien-fleming``: alpha(t) = 2 - 2 Phi(z_{1-level/2} / sqrt(t)) (Lan-DeMets' O'Brien-Fleming
  type): almost nothing at the first looks, close to the fixed-n test's level at the last;
- ``pocock``: alpha(t) = level * ln(1 + (e - 1) t) (Lan-DeMets' Pocock type): nearly even
  nominal levels at every look.

The crossing probabilities are computed by numerical integration of W's density over the
continuation region, look after look (Armitage, McPherson and Rowe, J. R. Stat. Soc. A 132
(1969) 235-244; Jennison and Turnbull, section 19.2): deterministic numpy, no Monte Carlo, so a
boundary is the same number on every machine. Against the union bound (each look at level / K),
the correlation of the looks is what the spending saves.

Futility. :func:`predictive_power` is the probability, given the statistic at a look, that the
test at the last run count will reject: the predictive power of Spiegelhalter, Freedman and
Blackburn, "Monitoring clinical trials: conditional or predictive power?", Controlled Clinical
Trials 7 (1986) 8-17 (Jennison and Turnbull, section 10.3). On the Brownian-motion scale
S(t) = Z(t) sqrt(t) = W(t) + mu t; with a flat prior on the drift mu its posterior after S(t) is
N(S(t) / t, 1 / t), so the final statistic Z(1) = S(1) is N(Z_k / sqrt(t), (1 - t) / t) given
the look: the data's own trend, its uncertainty averaged over (conditional power would take the
trend as known, and at the first looks stop on noise). A race may stop a comparison whose
predictive power is below a threshold; stopping only takes chances to reject away, so the
boundaries stay as computed (a non-binding futility rule: the level is not touched).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np

# The normal tail, quantile and density from scipy.special (what scipy.stats.norm computes
# them with), so that a race with looks does not import scipy.stats: a one-planner `plan`
# never loads it (tests/test_cli_plan.py), and the racing module is on its import path. scipy
# itself (special here, optimize in _bounds) is imported at its first use: every `swarmpath`
# process imports this module (bench's racing options), and the two cost about 0.8 s of CPU.


def _norm_sf(x: float) -> float:
    from scipy import special

    return float(special.ndtr(-x))


def _norm_isf(p: float) -> float:
    from scipy import special

    return float(-special.ndtri(p))


def _norm_pdf(x: np.ndarray, scale: float) -> np.ndarray:
    y = x / scale
    return np.exp(-(y**2) / 2.0) / np.sqrt(2 * np.pi) / scale

#: Spending functions by name (module text); the first is the default of raced jobs' looks.
SPENDING = ("obrien-fleming", "pocock")
#: Points of the grid over each look's continuation region (trapezoid rule): a race's nominal
#: levels are within 1e-3 (relative) of a 2001-point grid's (tests/test_group_sequential.py).
GRID = 801

__all__ = ["GRID", "SPENDING", "crossing_probabilities", "nominal_levels", "predictive_power",
           "spent"]


def spent(kind: str, level: float, t: float) -> float:
    """The error spent by information time ``t`` in (0, 1] by a two-sided test at ``level``."""
    if not 0.0 < t <= 1.0:
        raise ValueError(f"information time must be in (0, 1], got {t}")
    if kind == "obrien-fleming":
        return float(2.0 * _norm_sf(_norm_isf(level / 2.0) / math.sqrt(t)))
    if kind == "pocock":
        return level * math.log1p((math.e - 1.0) * t)
    raise ValueError(f"spending must be one of {', '.join(SPENDING)}, got {kind!r}")


def _times(looks: Sequence[int]) -> np.ndarray:
    n = np.asarray(looks, dtype=float)
    if n.size == 0 or np.any(n <= 0) or np.any(np.diff(n) <= 0):
        raise ValueError(f"looks must be increasing positive run counts, got {list(looks)}")
    return n / n[-1]


def _tails(u: np.ndarray, b: float, sd: float) -> np.ndarray:
    """P(|u + N(0, sd^2)| >= b) for each u."""
    from scipy import special

    return special.ndtr((u - b) / sd) + special.ndtr((-b - u) / sd)


def _moved(x: np.ndarray, density: np.ndarray, b: float, sd: float
           ) -> tuple[np.ndarray, np.ndarray]:
    """The grid over [-b, b] and the mass there of W one increment N(0, sd^2) later, where
    ``density`` is W's mass at the points ``x`` (those that did not cross)."""
    nx, nw = _grid(b)
    # only the points within 9 sd of a new point weigh (phi(9) ~ 1e-18): a band of the kernel
    width = min(2 * math.ceil(9.0 * sd / (x[1] - x[0])) + 1, x.size)
    start = np.clip(np.searchsorted(x, nx - 9.0 * sd), 0, x.size - width)
    idx = start[:, None] + np.arange(width)[None, :]
    d = (nx[:, None] - x[idx]) / sd
    kernel = np.exp(-0.5 * d * d) / (sd * math.sqrt(2.0 * math.pi))
    return nx, (kernel * density[idx]).sum(axis=1) * nw


def _grid(b: float) -> tuple[np.ndarray, np.ndarray]:
    """Points and trapezoid weights over [-b, b]."""
    x = np.linspace(-b, b, GRID)
    w = np.full(GRID, x[1] - x[0])
    w[[0, -1]] /= 2.0
    return x, w


def _excess(b: float, density: np.ndarray, x: np.ndarray, sd: float, target: float) -> float:
    """The mass crossing a boundary at +-b one increment later, beyond ``target``."""
    return float(density @ _tails(x, b, sd)) - target


@functools.lru_cache(maxsize=256)
def _bounds(looks: tuple[int, ...], level: float, kind: str) -> tuple[float, ...]:
    """Boundaries c_k on the Z scale (inf: the look spends nothing)."""
    from scipy.optimize import brentq  # at first use (above)

    t = _times(looks)
    budget = [spent(kind, level, float(x)) for x in t]
    c = [float(_norm_isf(budget[0] / 2.0))]
    b = c[0] * math.sqrt(t[0])  # on W's scale
    x, w = _grid(b)
    density = _norm_pdf(x, math.sqrt(t[0])) * w  # mass of W(t_1) at the points
    for k in range(1, len(t)):
        sd = math.sqrt(t[k] - t[k - 1])
        target = budget[k] - budget[k - 1]
        if target <= 0.0:
            c.append(math.inf)
            b = math.inf
        else:
            args = (density, x, sd, target)
            hi = x[-1] + 12.0 * sd + 12.0
            if _excess(0.0, *args) <= 0.0:  # rejecting everything spends less: never the case
                raise ValueError("the spending asks for more than the continuation region holds")
            b = float(brentq(_excess, 0.0, hi, args=args, xtol=1e-12, rtol=1e-12))
            c.append(b / math.sqrt(t[k]))
        if k + 1 < len(t):
            if not math.isfinite(b):  # no rejection here: W's density widens, kept on a range
                b = x[-1] + 8.0 * sd
            x, density = _moved(x, density, b, sd)
    return tuple(c)


def nominal_levels(looks: Sequence[int], level: float, kind: str = SPENDING[0]
                   ) -> tuple[float, ...]:
    """The two-sided p-value each look must be below to reject, at run counts ``looks`` (the
    last one is t = 1), so that the probability of a rejection at any look under the null is
    ``level`` (module text)."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    if kind not in SPENDING:
        raise ValueError(f"spending must be one of {', '.join(SPENDING)}, got {kind!r}")
    c = _bounds(tuple(int(n) for n in looks), float(level), kind)
    return tuple(float(2.0 * _norm_sf(x)) for x in c)


def crossing_probabilities(looks: Sequence[int], levels: Sequence[float]) -> float:
    """The null probability that the two-sided test at ``levels[k]`` rejects at some look
    (``looks`` the run counts): the design's real error, for any nominal levels (a check of
    :func:`nominal_levels`, and of allocations that are not spent this way)."""
    t = _times(looks)
    c = [float(_norm_isf(p / 2.0)) for p in levels]
    b = c[0] * math.sqrt(t[0])
    x, w = _grid(b)
    density = _norm_pdf(x, math.sqrt(t[0])) * w
    total = float(2.0 * _norm_sf(c[0]))
    for k in range(1, len(t)):
        sd = math.sqrt(t[k] - t[k - 1])
        b = c[k] * math.sqrt(t[k])
        total += float(density @ _tails(x, b, sd))
        x, density = _moved(x, density, b, sd)
    return total


def predictive_power(p: float, t: float, level: float) -> float:
    """The predictive power (module text) of a comparison whose two-sided p at information time
    ``t`` = n_k / n_K (0 < t < 1) is ``p``: the probability that the two-sided test at the
    last run count rejects at ``level``, with a flat prior on the effect. Symmetric in the
    side: rejecting either way counts, as the test does."""
    if not 0.0 < t < 1.0:
        raise ValueError(f"t must be in (0, 1), got {t}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    z = _norm_isf(min(max(p, 0.0), 1.0) / 2.0)  # |Z_k|; p = 0 is an infinite z
    c = _norm_isf(level / 2.0)
    mean, sd = z / math.sqrt(t), math.sqrt((1.0 - t) / t)
    return _norm_sf((c - mean) / sd) + _norm_sf((c + mean) / sd)
