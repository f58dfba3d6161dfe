"""One swarm decision of the MFB and HPSO-MFB planners compiled: the optimizer's whole loop.

The reference is the numpy loop of ``SwarmLocalPlanner._decide`` with
:class:`~swarmpath.optimizers.mfb.MFB` or :class:`~swarmpath.optimizers.hpso_mfb.HPSOMFB` on
one run whose objective is ``local.score``: the bat move of ``BatSwarms._bat_move`` for G
sub-swarms (G = 1: MFB) and, for HPSO-MFB, the PSO step on (alpha, gamma) between epochs.
Every floating-point operation is the reference's, in its order: the draws one ``rng.random``
per draw of the reference; the swarm's mean loudness added as numpy adds it (pairwise, eight
accumulators, for G = 1; ``A @ member.T`` adds each sub-swarm's bats in index order, the
products by 0 and 1 being exact); ``exp`` through numpy's own loop on the arrays the reference
builds. MFB's pulse-rate level exp(-gamma t) (a numpy scalar in the reference) comes from
numpy itself (:func:`levels`).

Implemented: every parameter value of MFB; HPSO-MFB but ``restart = "cold"``, and with at
least two particles (those run the numpy loop).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit

import swarmpath.optimizers.compiled  # noqa: F401 - first: numba's versioned cache directory
from swarmpath.optimizers.compiled.bat_move import move_bats
from swarmpath.optimizers.compiled.coot_phases import _clip
from swarmpath.optimizers.compiled.ufuncs import exp_inplace
from swarmpath.planners.compiled_coot import record, stalled_after
from swarmpath.planners.compiled_score import score_into

Array = np.ndarray
_BETA_TIME = ("normalized", "literal", "uniform")


def pack(name: str, p: Mapping[str, Any], agents: int) -> Array | None:
    """The kernel's parameter vector, or None for a setting it does not implement."""
    hpso = name == "HPSO-MFB"
    particles = min(int(p.get("particles", 1)), agents)
    if agents < 2 or (hpso and (p["restart"] == "cold" or particles < 2)):
        return None
    return np.array([
        hpso, p["f_min"], p["f_max"], p["rho"], p["sigma"], p["A0_min"], p["A0_max"],
        p["r0_min"], p["r0_max"], _BETA_TIME.index(str(p["beta_time"])), p["beta_r"] == "pulse",
        p["beta_per"] == "dimension", p["velocity"] == "toward", p["walk_scale"] == "span",
        p["accept"] == "best", p["move"] == "always", p["update"] == "iteration",
        p.get("alpha", 0.9), particles, p.get("pso_iterations", 1), p.get("c1", 0.0),
        p.get("c2", 0.0), p.get("w", 0.0), p.get("vmax", 0.0), p.get("alpha_low", 0.0),
        p.get("alpha_high", 0.0), p.get("gamma_low", 0.0), p.get("gamma_high", 0.0),
        p.get("split", "divide") == "divide", p.get("restart", "warm") == "none",
        p.get("best", "global") == "global",
    ], dtype=np.float64)


def levels(p: Mapping[str, Any], iterations: int) -> Array:
    """MFB's exp(-gamma t), t = 1..T, as ``BatSwarms._bat_move`` computes it (numpy scalars)."""
    gamma = p.get("gamma", 1.0)
    return np.array([np.exp(-np.asarray(gamma) * t) for t in range(1, iterations + 1)])


@njit(cache=True)
def _mean_loudness(A: Array, group: Array, G: int, out: Array) -> None:
    """Mean loudness of each sub-swarm: G = 1 numpy's pairwise sum over the bats, else each
    sub-swarm's bats in index order (``A @ member.T``), divided by the count."""
    Nb = A.size
    if G == 1:
        if Nb < 8:
            s = 0.0
            for i in range(Nb):
                s += A[i]
        else:
            r = A[:8].copy()
            i = 8
            while i < Nb - Nb % 8:
                for j in range(8):
                    r[j] += A[i + j]
                i += 8
            s = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
            while i < Nb:
                s += A[i]
                i += 1
        out[0] = s / Nb
        return
    for g in range(G):
        s = 0.0
        n = 0
        for i in range(Nb):
            if group[i] == g:
                s += A[i]
                n += 1
        out[g] = s / float(n)


@njit(cache=True)
def _evaluate(S, F, geo, hits, k, best, best_x, group, G, Fb, Zb, epoch, track):
    """``BatSwarms._evaluate_bats``: score, record, each sub-swarm's best (first minimum)."""
    score_into(S, geo, hits, k, F)
    record(F, S, S.shape[0], best, best_x)
    for g in range(G):
        at = -1
        for i in range(S.shape[0]):
            if group[i] == g and (at < 0 or F[i] < F[at]):
                at = i
        cand = F[at] if at >= 0 else np.inf
        if cand < Fb[g]:
            Fb[g] = cand
            Zb[g] = S[at]
        if track and cand < epoch[g]:
            epoch[g] = cand


@njit(cache=True)
def bats_decide(rng: Any, lb: Array, ub: Array, N: int, T: int, params: Array, decay: Array,
                geo: Array, hits: Array, k: Array, patience: int,
                tol: float) -> tuple[float, Array, int]:
    """(best value, best point, iterations done) of one decision."""
    d = lb.size
    hpso = params[0] == 1.0
    f_min, f_max, rho, sigma = params[1], params[2], params[3], params[4]
    beta_time, pulse, per_dim = int(params[9]), params[10] == 1.0, params[11] == 1.0
    toward, span_walk, accept_best = params[12] == 1.0, params[13] == 1.0, params[14] == 1.0
    always, per_iteration, alpha_mfb = params[15] == 1.0, params[16] == 1.0, params[17]
    G = int(params[18]) if hpso else 1
    Nb = N if (not hpso or params[28] == 1.0) else G * N
    K = math.ceil(T / int(params[19])) if hpso else T
    restart_none, shared = params[29] == 1.0, (G == 1 or params[30] == 1.0)
    e = d if per_dim else 1
    span = ub - lb
    group = np.arange(Nb) % G
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    call = np.zeros(5, dtype=np.int64)

    # ---- fresh bats (``_init_bats``), then HPSO's particles
    X = np.empty((Nb, d))
    draw = rng.random(Nb * d)
    for i in range(Nb):
        for j in range(d):
            X[i, j] = lb[j] + span[j] * draw[i * d + j]
    draw = rng.random(Nb * 2)
    A0 = np.empty(Nb)
    r0 = np.empty(Nb)
    for i in range(Nb):
        A0[i] = params[5] + (params[6] - params[5]) * draw[2 * i]
        r0[i] = params[7] + (params[8] - params[7]) * draw[2 * i + 1]
    A = A0.copy()
    r = np.zeros(Nb)
    V = np.zeros((Nb, d))
    Fb = np.full(G, np.inf)
    Zb = np.zeros((G, d))
    epoch = np.full(G, np.inf)
    F = np.empty(Nb)
    _evaluate(X, F, geo, hits, k, best, best_x, group, G, Fb, Zb, epoch, hpso)
    box_lo = np.array([params[24], params[26]])
    box_hi = np.array([params[25], params[27]])
    pos = np.empty((G, 2))
    if hpso:
        draw = rng.random(G * 2)
        for g in range(G):
            for c in range(2):
                pos[g, c] = box_lo[c] + (box_hi[c] - box_lo[c]) * draw[g * 2 + c]
    vel = np.zeros((G, 2))
    pbest = pos.copy()
    pbest_f = np.full(G, np.inf)

    S = np.empty((Nb, d))
    Fnew = np.empty(Nb)
    freq = np.empty(Nb * e)
    amean = np.empty(G)
    level = np.empty(Nb)
    before = best[0]
    stalled = 0
    t = 0
    while t < T:
        t += 1
        clock, length = t, T
        if hpso and not restart_none:
            start = (t - 1) // K * K
            length = min(start + K, T) - start
            clock = t - start
        # ---- one bat move (``_bat_move``), clock (t, T) of eqs 10 and 15
        u = rng.random(Nb * (d + 2 + e))
        o_acc, o_beta = Nb * (d + 1), Nb * (d + 2)
        if beta_time == 2:
            freq[:] = u[o_beta:]
        else:
            for i in range(Nb * e):
                freq[i] = -rho * (r[i // e] if pulse else u[o_beta + i])
            exp_inplace(freq, call)
            tt = clock / length if beta_time == 0 else float(clock)
            for i in range(Nb * e):
                freq[i] = tt * freq[i]
        for i in range(Nb * e):
            freq[i] = f_min + (f_max - f_min) * freq[i]
        kb = 0
        for g in range(1, G):
            if Fb[g] < Fb[kb]:
                kb = g
        _mean_loudness(A, group, G, amean)
        move_bats(X, V, S, Zb, freq, per_dim, u, 0, r, amean, G, shared, kb, sigma, toward,
                  span_walk, lb, ub)
        fb_before = Fb.copy()
        _evaluate(S, Fnew, geo, hits, k, best, best_x, group, G, Fb, Zb, epoch, hpso)
        if hpso:
            for i in range(Nb):
                level[i] = -pos[group[i], 1] * clock
            exp_inplace(level, call)
        else:
            level[:] = decay[clock - 1]
        for i in range(Nb):
            fb = fb_before[kb if shared else group[i]]
            ok = u[o_acc + i] < A[i] and (Fnew[i] < fb if accept_best else Fnew[i] <= F[i])
            if always or ok:
                X[i] = S[i]
                F[i] = Fnew[i]
            alpha = pos[group[i], 0] if hpso else alpha_mfb
            lv = r0[i] * (1.0 - level[i])
            if per_iteration or ok:
                A[i] = alpha * A[i]
                r[i] = lv
        # ---- HPSO: the PSO step on (alpha, gamma) after each epoch but the last
        if hpso and t % K == 0 and t < T:
            for g in range(G):
                if epoch[g] < pbest_f[g]:
                    pbest[g] = pos[g]
                    pbest_f[g] = epoch[g]
            j = 0
            for g in range(1, G):
                if pbest_f[g] < pbest_f[j]:
                    j = g
            draw = rng.random(G * 4)
            for g in range(G):
                for c in range(2):
                    v = (params[22] * vel[g, c]
                         + params[20] * draw[g * 4 + c] * (pbest[g, c] - pos[g, c])
                         + params[21] * draw[g * 4 + 2 + c] * (pbest[j, c] - pos[g, c]))
                    vmax = params[23] * (box_hi[c] - box_lo[c])
                    vel[g, c] = _clip(v, -vmax, vmax)
                    pos[g, c] = _clip(pos[g, c] + vel[g, c], box_lo[c], box_hi[c])
            epoch[:] = np.inf
            if not restart_none:  # warm: a new MFB run from where the bats are
                V[:] = 0.0
                A[:] = A0
                r[:] = 0.0
        stalled = stalled_after(before, best[0], stalled, tol)
        before = best[0]
        if patience > 0 and stalled >= patience and before < 1e6:
            break
    return best[0], best_x, t
