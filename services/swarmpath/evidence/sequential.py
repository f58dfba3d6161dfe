"""Anytime-valid comparison of two algorithms' paired runs: the statistics behind racing.

A race looks at its data after every round and stops when a comparison is decided, so a test whose
error rate holds only at one fixed sample size (the rank-sum test of :mod:`.compare`) would be
repeated until it fires: optional stopping inflates its false differences without bound. This
module uses a **confidence sequence** instead: a sequence of intervals that contains the true
value at *every* sample size at once with probability at least 1 - alpha, so any stopping rule
built on it keeps its error rate (Howard, Ramdas, McAuliffe and Sekhon, Ann. Statist. 49 (2021)).

The quantity. Run r of algorithm A and run r of algorithm B are paired: they draw from the same
run streams (seed, r) and, for transformed functions, meet the same shifted and rotated instance.
Each pair scores

    Z_r = 1 if a_r < b_r,  0 if a_r > b_r,  1/2 if a_r = b_r      (lower is better)

and theta = E[Z] = P(A < B) + P(A = B) / 2, the probability that A's run beats B's (Vargha and
Delaney's A measure, here of the paired runs). Pairs are independent and identically distributed
over r. When A and B are the same algorithm, or any two algorithms whose pair (a_r, b_r) is
exchangeable, theta = 1/2 exactly; theta = 1/2 +- delta is Vargha and Delaney's scale of effect
size (0.06 negligible, 0.14 small, 0.21 medium).

The confidence sequence. Z is bounded in [0, 1], so the betting construction of Waudby-Smith and
Ramdas ("Estimating means of bounded random variables by betting", J. R. Stat. Soc. B 86 (2024)
1-27, hedged capital process, section 4, with the predictable plug-in bets of eq. (26)) applies
without any assumption on the algorithms' distributions: for a candidate m,

    K+_t(m) = prod_{i<=t} (1 + l+_i(m) (Z_i - m)),   K-_t(m) = prod_{i<=t} (1 - l-_i(m) (Z_i - m))

are nonnegative martingales when theta = m, so is their mean, and by Ville's inequality the
hedged capital K_t(m) = max(K+_t(m), K-_t(m)) / 2 (at most that mean) ever reaches 1/alpha with
probability at most alpha. The set {m : K_s(m) < 1/alpha for every s <= t} is the confidence
sequence. It is an interval: K+ does not increase with m and K- does not decrease, so the max
is quasi-convex in m (W-S & R's hedged process; the mean itself is not quasi-convex, and an
equivalence decided from two rejected end points needs the interval). Bets:
l_t = sqrt(2 log(2/alpha) / (s2_{t-1} t log(1 + t))), l+ = min(l, c/m), l- = min(l, c/(1 - m)),
c = 1/2, with the running mean mu_t = (1/2 + sum Z)/(t + 1) and variance
s2_t = (1/4 + sum (Z_i - mu_i)^2)/(t + 1). Every bet uses only earlier pairs: that is what makes
the product a martingale.

Decisions (at level alpha): **different** when m = 1/2 has been rejected (the interval lies above
1/2: A better; below: B better); **equivalent** (with a margin delta > 0) when both 1/2 - delta and
1/2 + delta have been rejected but 1/2 has not, i.e. the interval lies inside (1/2 - delta,
1/2 + delta). Under theta = 1/2 a difference is declared with probability at most alpha, at any
stopping time; under |theta - 1/2| >= delta equivalence is declared with probability at most alpha.
Pure numpy; no state between calls: a decision is a function of the paired values only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

#: Truncation of the bets (W-S & R's c): each factor stays >= 1 - c = 1/2, so one pair can at most
#: halve the capital; 1/2 is their default for the hedged process.
BET_CAP = 0.5

__all__ = [
    "BET_CAP", "PairDecision", "confidence_sequence", "decide", "pair_scores", "rejection_times",
    "sign_test",
]


def pair_scores(a: ArrayLike, b: ArrayLike) -> Array:
    """Z_r for the pairs (a_r, b_r), r = 0..n-1 with n = min(len(a), len(b)); a pair with a NaN
    (a run without a value: it crashed) is dropped. Infinite values are real, worst results."""
    x = np.asarray(a, dtype=float)
    y = np.asarray(b, dtype=float)
    n = min(x.size, y.size)
    x, y = x[:n], y[:n]
    keep = ~(np.isnan(x) | np.isnan(y))
    x, y = x[keep], y[keep]
    return np.where(x < y, 1.0, np.where(x > y, 0.0, 0.5))


def _bets(z: Array, alpha: float) -> Array:
    """The predictable plug-in bets l_t (before truncation), t = 1..n: each from Z_1..Z_{t-1}."""
    n = z.size
    t = np.arange(1, n + 1, dtype=float)
    mu = (0.5 + np.cumsum(z)) / (t + 1.0)  # mu_t, t = 1..n
    sq = np.cumsum((z - mu) ** 2)
    s2 = (0.25 + sq) / (t + 1.0)  # s2_t, t = 1..n
    s2_prev = np.concatenate(([0.25], s2[:-1]))  # s2_0 = 1/4
    return np.sqrt(2.0 * math.log(2.0 / alpha) / (s2_prev * t * np.log1p(t)))


def _log_capitals(z: Array, m: Array, alpha: float) -> tuple[Array, Array]:
    """log of the two products of K_t(m) for t = 1..n (rows) and each m (columns): the bet on
    theta > m (it grows when A wins more than m of the pairs) and the bet on theta < m."""
    lam = _bets(z, alpha)[:, None]
    m = np.asarray(m, dtype=float)[None, :]
    with np.errstate(divide="ignore"):
        up = np.minimum(lam, BET_CAP / m)
        down = np.minimum(lam, BET_CAP / (1.0 - m))
    d = z[:, None] - m
    return np.cumsum(np.log1p(up * d), axis=0), np.cumsum(np.log1p(-down * d), axis=0)


def _log_capital(z: Array, m: Array, alpha: float) -> Array:
    """log K_t(m), the hedged capital (half the larger bet): shape (n, len(m))."""
    log_up, log_down = _log_capitals(z, m, alpha)
    return np.asarray(np.maximum(log_up, log_down) - math.log(2.0))


def rejection_times(z: ArrayLike, m: ArrayLike, alpha: float) -> NDArray[np.int64]:
    """For each candidate m, the number of pairs after which K(m) first reached 1/alpha (m left
    the confidence sequence), or 0 if it never did within the pairs given."""
    zz = np.asarray(z, dtype=float)
    mm = np.atleast_1d(np.asarray(m, dtype=float))
    if not 0.0 < alpha < 1.0:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    if zz.size == 0:
        return np.zeros(mm.size, dtype=np.int64)
    hit = _log_capital(zz, mm, alpha) >= math.log(1.0 / alpha)
    first = np.argmax(hit, axis=0) + 1
    return np.where(hit.any(axis=0), first, 0).astype(np.int64)


@dataclass(frozen=True)
class PairDecision:
    """The outcome of one two-sample comparison after ``n`` pairs.

    ``decision`` is ``"different"``, ``"equivalent"`` or ``"open"``; ``better`` is ``"a"`` or
    ``"b"`` for a difference (whose runs tend to be lower); ``at`` the number of pairs after which
    it was decided (0 while open); ``theta`` the observed mean score (a's share of wins, ties
    half); ``low``/``high`` the confidence sequence's interval for theta after n pairs."""

    n: int
    decision: str
    better: str | None
    at: int
    theta: float
    low: float
    high: float


def _rejected(z: Array, m: float, alpha: float) -> bool:
    return bool(rejection_times(z, [m], alpha)[0])


def confidence_sequence(z: ArrayLike, alpha: float, tol: float = 1e-4) -> tuple[float, float]:
    """The interval of theta left after the pairs ``z`` (the running intersection over every
    prefix), its ends found to ``tol`` by bisection outwards from a point inside it; (0, 1) with
    no pairs. The interval is what is left once every m rejected at some prefix is removed."""
    zz = np.asarray(z, dtype=float)
    if zz.size == 0:
        return 0.0, 1.0
    inner = min(max(float(zz.mean()), tol), 1.0 - tol)
    if _rejected(zz, inner, alpha):  # the mean left the set: look for a survivor on a grid
        grid = np.linspace(tol, 1.0 - tol, 999)
        alive = grid[rejection_times(zz, grid, alpha) == 0]
        if alive.size == 0:  # cannot happen under the guarantee's event; say so rather than guess
            return math.nan, math.nan
        inner = float(alive[alive.size // 2])

    def edge(outer: float) -> float:
        if not _rejected(zz, outer, alpha):
            return outer
        good, bad = inner, outer
        while abs(bad - good) > tol:
            mid = 0.5 * (good + bad)
            good, bad = (good, mid) if _rejected(zz, mid, alpha) else (mid, bad)
        return good

    return edge(tol), edge(1.0 - tol)


def sign_test(z: ArrayLike, alpha: float) -> str | None:
    """The exact two-sided sign test of theta = 1/2 at a fixed number of pairs (ties dropped):
    ``"a"`` or ``"b"`` for the side that wins more pairs when p <= alpha, else None. Valid for
    any two distributions, as the confidence sequence is, but only at a sample size chosen
    before looking (a race's closing look at max_runs)."""
    from scipy.stats import binomtest  # scipy.stats costs ~0.8 s to import: only when needed

    zz = np.asarray(z, dtype=float)
    wins, losses = int(np.sum(zz == 1.0)), int(np.sum(zz == 0.0))
    if wins + losses == 0 or wins == losses:
        return None
    if binomtest(wins, wins + losses, 0.5).pvalue > alpha:
        return None
    return "a" if wins > losses else "b"


def decide(z: ArrayLike, alpha: float, margin: float = 0.0, interval: bool = True) -> PairDecision:
    """The comparison after the pairs ``z`` (see the module text): different, equivalent within
    ``margin`` on the theta scale (0 = never), or open. ``interval=False`` skips the confidence
    interval (``low``/``high`` NaN), the costly part, when only the decision is needed."""
    zz = np.asarray(z, dtype=float)
    if not 0.0 <= margin < 0.5:
        raise ValueError(f"margin must be in [0, 0.5), got {margin}")
    n = int(zz.size)
    theta = float(zz.mean()) if n else math.nan
    low, high = (confidence_sequence(zz, alpha) if n else (0.0, 1.0)) if interval else (
        math.nan, math.nan)
    points = [0.5] + ([0.5 - margin, 0.5 + margin] if margin > 0 else [])
    times = rejection_times(zz, points, alpha)
    differ = int(times[0])
    same = int(max(times[1], times[2])) if margin > 0 and times[1] and times[2] else 0
    # whichever was reached first stops the race (both can hold: an effect smaller than the
    # margin but not zero); each is an error with probability at most alpha
    if differ and not (same and same < differ):
        # the bet that won: on theta > 1/2 (A's runs lower) or on theta < 1/2
        log_up, log_down = _log_capitals(zz[:differ], np.array([0.5]), alpha)
        better = "a" if log_up[-1, 0] > log_down[-1, 0] else "b"
        return PairDecision(n, "different", better, differ, theta, low, high)
    if same:
        return PairDecision(n, "equivalent", None, same, theta, low, high)
    return PairDecision(n, "open", None, 0, theta, low, high)
