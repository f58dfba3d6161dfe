"""One swarm decision of the IHPO and HPO planners compiled: the optimizer's whole loop.

The reference is the numpy loop of ``SwarmLocalPlanner._decide`` with
:class:`~swarmpath.optimizers.ihpo.IHPO` (or HPO) on one run whose objective is
``local.score``: the authors' sequential sweep in blocks (``HPO._sweep``: a block runs from an
agent to the next hunter after it, is scored in one call and kept up to its first agent that
improves on the best point). Here the same blocks, moves and scoring calls, with every
floating-point operation of the reference in its order: the draws one ``rng.random`` per draw
of the reference (two per iteration), the population mean added in agent order (numpy's
reduction over the agents' axis), the prey's cosine through numpy's own loop (in place on the
whole slab, as the reference), ``math.sin`` for CP (Python's, the C library's).

Implemented: ``update = "sequential"`` (the default; ``"synchronous"`` runs the numpy loop) and
every other parameter value of HPO and IHPO but IHPO's ``beta_draw = "dimension"``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.optimizers.compiled.coot_phases import _clip
from swarmpath.optimizers.compiled.functions import dot
from swarmpath.planners.compiled_coot import initialize, stalled_after
from swarmpath.planners.compiled_score import score_into, unary_inplace

Array = np.ndarray
_HUNTER = ("paper", "centre", "relative")
_ALPHA_ON = ("step", "displacement", "literal", "position")
_BRANCHES = ("both", "hunter", "prey")
TWO_PI = 2.0 * math.pi


def pack(name: str, p: Mapping[str, Any]) -> Array | None:
    """The kernel's parameter vector, or None for a setting it does not implement."""
    ihpo = name == "IHPO"
    if p["update"] != "sequential" or (ihpo and p["beta_draw"] == "dimension"):
        return None
    return np.array([
        ihpo, float(p["beta"]), p["prey_step"] == "2Z", p["prey_angle"] == "independent",
        _HUNTER.index(str(p["hunter"])), _ALPHA_ON.index(str(p.get("alpha_on", "literal"))),
        _BRANCHES.index(str(p.get("alpha_branches", "both"))),
        p.get("beta_draw", "agent") == "iteration", p.get("cp_c", "hpo") == "hpo",
    ], dtype=np.float64)


@njit(cache=True)
def _anchor(X: Array, kbest: int, P: Array, mu: Array) -> None:
    """``HPO._hunter_anchor``: P the agent of the kbest-th smallest distance to the mean mu
    (stable order), mu added in agent order."""
    N, d = X.shape
    for j in range(d):
        s = 0.0
        for i in range(N):
            s = s + X[i, j]
        mu[j] = s / N
    diff = np.empty(d)
    dist2 = np.empty(N)
    for i in range(N):
        for j in range(d):
            diff[j] = X[i, j] - mu[j]
        dist2[i] = dot(diff, diff, d)
    # the element at kbest - 1 of the stable argsort: the values below the kbest-th smallest
    # value v come first, then the agents at v in index order
    v = np.partition(dist2, kbest - 1)[kbest - 1]
    need = kbest - 1
    for i in range(N):
        if dist2[i] < v:
            need -= 1
    for i in range(N):
        if dist2[i] == v:
            if need == 0:
                P[:] = X[i]
                return
            need -= 1


@njit(cache=True)
def hpo_decide(rng: Any, lb: Array, ub: Array, N: int, T: int, params: Array, geo: Array,
               hits: Array, k: Array, patience: int, tol: float) -> tuple[float, Array, int]:
    """(best value, best point, iterations done) of one decision."""
    d = lb.size
    ihpo, beta, two_z, independent = params[0] == 1.0, params[1], params[2] == 1.0, params[3] == 1.0
    hunter, on, branches = int(params[4]), int(params[5]), int(params[6])
    per_iteration, cp_hpo = params[7] == 1.0, params[8] == 1.0
    centre = 0.5 * (lb + ub)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    X = initialize(rng, lb, ub, N, geo, hits, k, best, best_x)[0]

    slabs = 2 if independent else 1
    rows = 3 if ihpo else 2
    CZ = np.empty((N, d))
    S = np.empty(N * d)
    alpha = np.ones((N, d))
    P = np.empty(d)
    mu = np.empty(d)
    anchor = np.empty(d)
    B = np.empty((N, d))
    FB = np.empty(N)
    call = np.empty(7, dtype=np.int64)
    before = best[0]
    stalled = 0
    t = 0
    while t < T:
        t += 1
        C = 1.0 - t * (0.98 / T)
        kbest = max(1, _matlab_round(N * C))
        U = rng.random(slabs * N * d)
        V = rng.random(rows * N)
        # C Z: u where u < C, else C r2 (the reference's arithmetic blend)
        for i in range(N):
            cr2 = V[i] * C
            for j in range(d):
                u = U[i * d + j]
                CZ[i, j] = (u - cr2) + cr2 if u < C else cr2
        for i in range(N):
            for j in range(d):
                if independent:
                    S[i * d + j] = (U[N * d + i * d + j] - 0.5) * TWO_PI
                else:
                    s = CZ[i, j] * (2.0 / C) - 1.0
                    S[i * d + j] = (s - np.rint(s)) * TWO_PI
        unary_inplace(True, S, call)  # cos
        for i in range(N):
            for j in range(d):
                S[i * d + j] = S[i * d + j] * CZ[i, j]
                if two_z:
                    S[i * d + j] = S[i * d + j] * (2.0 / C)
        if ihpo:
            cp = math.sin((C if cp_hpo else 1.0) - t / T)
            for i in range(N):
                a = (2.0 * V[2 * N + (0 if per_iteration else i)] - 1.0) * cp
                for j in range(d):
                    alpha[i, j] = a
            if branches != 1 and (on == 0 or on == 2):  # eq 14b: S alpha
                for i in range(N):
                    for j in range(d):
                        S[i * d + j] = S[i * d + j] * alpha[i, j]

        # ---- the authors' sweep, in blocks from an agent to the next hunter after it
        i = 0
        while i < N:
            end = i + 1
            while end < N and not V[N + end] < beta:
                end += 1
            m = end - i
            for a in range(m):  # prey (the hunter's row is replaced below)
                for j in range(d):
                    x = X[i + a, j]
                    tj = best_x[j]
                    s = S[(i + a) * d + j]
                    if not ihpo or branches == 1 or on == 0 or on == 2:
                        v = (tj - x) * s + tj
                    elif on == 1:  # displacement
                        v = x + (tj - x) * ((s + 1.0) * alpha[i + a, j])
                    else:  # position
                        v = ((tj - x) * s + tj) * alpha[i + a, j]
                    B[a, j] = v
            if V[N + i] < beta:  # agent i is a hunter
                _anchor(X, kbest, P, mu)
                for j in range(d):
                    z = CZ[i, j] / C
                    x = X[i, j]
                    aj = alpha[i, j]
                    o = centre[j]
                    if ihpo and branches != 2 and on == 2:  # eq 14a as printed
                        if hunter == 1:
                            anchor[j] = aj * (C * (P[j] - o)) + (1.0 - C) * (mu[j] - o) + o
                        else:
                            anchor[j] = aj * (C * P[j]) + (1.0 - C) * mu[j]
                    else:
                        anchor[j] = C * P[j] + (1.0 - C) * mu[j]
                    h = _hunter_move(hunter, z, x, anchor[j], o)
                    if ihpo and branches != 2 and on == 3:
                        h = aj * h
                    elif ihpo and branches != 2 and (on == 0 or on == 1):
                        h = x + aj * (h - x)
                    B[0, j] = h
            for a in range(m):
                for j in range(d):
                    B[a, j] = _clip(B[a, j], lb[j], ub[j])
            score_into(B[:m], geo, hits, k, FB)
            stop = m
            improved = False
            for a in range(m):
                if (np.inf if np.isnan(FB[a]) else FB[a]) < best[0]:
                    stop = a + 1
                    improved = True
                    break
            for a in range(stop):
                X[i + a] = B[a]
            if improved:  # the first agent that beat the best: the new best (``record``)
                best[0] = FB[stop - 1]
                best_x[:] = B[stop - 1]
            i += stop
        stalled = stalled_after(before, best[0], stalled, tol)
        before = best[0]
        if patience > 0 and stalled >= patience and before < 1e6:
            break
    return best[0], best_x, t


@njit(cache=True)
def _hunter_move(hunter: int, z: float, x: float, anchor: float, centre: float) -> float:
    """``HPO._hunter_move`` for one coordinate."""
    if hunter == 0:
        return z * anchor
    base = x if hunter == 2 else centre
    return (anchor - base) * z + base


@njit(cache=True)
def _matlab_round(x: float) -> int:
    """``hpo.matlab_round``: half away from zero."""
    a = abs(x)
    r = math.floor(a)
    if a - r >= 0.5:
        r += 1
    return int(math.copysign(r, x))
