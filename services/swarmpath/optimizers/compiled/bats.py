"""Compiled kernels of MFB and HPSO-MFB: one run per call, the numpy reference's numbers.

The reference is :class:`~swarmpath.optimizers.mfb.BatSwarms` (MFB: one sub-swarm) and
:class:`~swarmpath.optimizers.hpso_mfb.HPSOMFB` (one sub-swarm per PSO particle, bat j in
sub-swarm j mod P, and the PSO step on (alpha, gamma) after each epoch); their docstrings state
the algorithm. Every floating-point operation is the reference's, in its order: the draws as
the reference lays them out ([eps | walk | accept | beta noise] per iteration), exp through
numpy's own loop on the arrays the reference builds (eq 10's exp(-rho r), eq 15's exp(-gamma t)
for every bat), the swarm's mean loudness added as numpy adds it (:func:`pairwise_sum` for one
sub-swarm; ``BatSwarms._group_sums`` adds each sub-swarm's bats in index order), and every
parameter value of both.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.bat_move import move_bats
from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.functions import pairwise_sum
from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT
from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import exp_inplace
from swarmpath.optimizers.hpso_mfb import HPSOMFB
from swarmpath.optimizers.mfb import BAT_CHOICES
from swarmpath.registry import ParamValue

_RESTART = HPSOMFB.choices["restart"]  # warm, cold, none
WARM, COLD, NONE = range(3)


def _packer(name: str):
    def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
        hpso = name == "HPSO-MFB"
        return np.array([
            hpso, p["f_min"], p["f_max"], p["rho"], p["sigma"], p["A0_min"], p["A0_max"],
            p["r0_min"], p["r0_max"], BAT_CHOICES["beta_time"].index(str(p["beta_time"])),
            p["beta_r"] == "pulse", p["beta_per"] == "dimension", p["velocity"] == "toward",
            p["walk_scale"] == "span", p["accept"] == "best", p["move"] == "always",
            p["update"] == "iteration", p["alpha"] if not hpso else 0.0,
            p["gamma"] if not hpso else 0.0, p.get("particles", 1),
            p.get("pso_iterations", 1), p.get("c1", 0.0), p.get("c2", 0.0), p.get("w", 0.0),
            p.get("vmax", 0.0), p.get("alpha_low", 0.0), p.get("alpha_high", 0.0),
            p.get("gamma_low", 0.0), p.get("gamma_high", 0.0),
            p.get("split", "divide") == "divide",
            _RESTART.index(str(p.get("restart", "warm"))), p.get("best", "global") == "global",
        ], dtype=np.float64)

    return pack


@njit(cache=True, **NO_REFCOUNT)
def evaluate_bats(stream, objective, shifted, shift, lower, upper, S, F, everyone, work, G,
                  Fb, Zb, epoch, best, best_x):
    """``BatSwarms._evaluate_bats``: evaluate, record, each sub-swarm's z* (the first minimum of
    its bats, if below its record) and its epoch record."""
    Nb, d = S.shape
    evaluate(stream, objective, shifted, shift, lower, upper, S, F, everyone, work)
    record_first_min(F, S, Nb, best, best_x)
    for g in range(G):
        at = -1
        for i in range(g, Nb, G):
            if at < 0 or F[i] < F[at]:
                at = i
        cand = F[at] if at >= 0 else np.inf
        if cand < Fb[g]:
            Fb[g] = cand
            for j in range(d):
                Zb[g, j] = S[at, j]
        epoch[g] = min(epoch[g], cand)


@njit(cache=True)
def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    """One MFB or HPSO-MFB run (the package's kernel signature)."""
    N, d, T = agents, lower.size, iterations
    hpso = params[0] == 1.0
    f_min, f_max, rho, sigma = params[1], params[2], params[3], params[4]
    beta_time, pulse, per_dim = int(params[9]), params[10] == 1.0, params[11] == 1.0
    toward, span_walk, accept_best = params[12] == 1.0, params[13] == 1.0, params[14] == 1.0
    always, per_iteration = params[15] == 1.0, params[16] == 1.0
    G = min(int(params[19]), N) if hpso else 1
    Nb = N if (not hpso or params[29] == 1.0) else G * N
    K = math.ceil(T / int(params[20])) if hpso else T
    restart = int(params[30]) if hpso else NONE
    shared = G == 1 or params[31] == 1.0
    e = d if per_dim else 1
    stream = open_stream(rng, max(Nb * (d + 2 + e), 4 * G), False)
    buf = stream[1][RANDOM]
    work = work_for(Nb, d)
    everyone = np.ones(Nb, dtype=np.bool_)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    call = np.zeros(5, dtype=np.int64)

    # ---- fresh bats (``_init_bats``), then HPSO's particles
    X = np.empty((Nb, d))
    o = take(stream, RANDOM, Nb * d)
    for i in range(Nb):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
    o = take(stream, RANDOM, Nb * 2)
    A0 = np.empty(Nb)
    r0 = np.empty(Nb)
    for i in range(Nb):
        A0[i] = params[5] + (params[6] - params[5]) * buf[o + 2 * i]
        r0[i] = params[7] + (params[8] - params[7]) * buf[o + 2 * i + 1]
    A = A0.copy()
    r = np.zeros(Nb)
    V = np.zeros((Nb, d))
    Fb = np.full(G, np.inf)
    Zb = np.zeros((G, d))
    epoch = np.full(G, np.inf)
    F = np.empty(Nb)
    evaluate_bats(stream, objective, shifted, shift, lower, upper, X, F, everyone, work, G, Fb,
                  Zb, epoch, best, best_x)
    lo = np.array([params[25], params[27]])  # the particles' box: alpha, gamma
    hi = np.array([params[26], params[28]])
    pos = np.empty((G, 2))
    if hpso:
        o = take(stream, RANDOM, G * 2)
        for g in range(G):
            for c in range(2):
                pos[g, c] = lo[c] + (hi[c] - lo[c]) * buf[o + g * 2 + c]
    else:
        pos[0, 0] = params[17]
        pos[0, 1] = params[18]
    vel = np.zeros((G, 2))
    pbest = pos.copy()
    pbest_f = np.full(G, np.inf)

    S = np.empty((Nb, d))
    Fnew = np.empty(Nb)
    freq = np.empty(Nb * e)
    amean = np.empty(G)
    level = np.empty(Nb)
    fb_before = np.empty(G)
    ok = np.empty(Nb, dtype=np.bool_)
    for t in range(1, T + 1):
        clock, length = t, T
        if restart != NONE:
            start = (t - 1) // K * K
            length = min(start + K, T) - start
            clock = t - start
            if restart == COLD and start > 0:
                if clock == 1:  # ``_redraw_bats``: the new MFB run's initial population
                    o = take(stream, RANDOM, Nb * d)
                    for i in range(Nb):
                        for j in range(d):
                            X[i, j] = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
                    for g in range(G):
                        Fb[g] = np.inf
                    evaluate_bats(stream, objective, shifted, shift, lower, upper, X, F,
                                  everyone, work, G, Fb, Zb, epoch, best, best_x)
                    clock = 0  # no bat move in this iteration
                else:
                    clock -= 1
                    length -= 1
        if clock > 0:  # ---- one bat move (``_bat_move``) on the clock of eqs 10 and 15
            o = take(stream, RANDOM, Nb * (d + 2 + e))
            o_acc, o_beta = o + Nb * (d + 1), o + Nb * (d + 2)
            if beta_time == 2:  # "uniform": Yang's beta
                for i in range(Nb * e):
                    freq[i] = buf[o_beta + i]
            else:
                for i in range(Nb * e):
                    freq[i] = -rho * (r[i // e] if pulse else buf[o_beta + i])
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
            for g in range(G):
                fb_before[g] = Fb[g]
                if G == 1:
                    amean[0] = (0.0 + pairwise_sum(A, 0, Nb)) / Nb
                else:  # (A @ member.T) / size: the sub-swarm's bats in index order
                    s = 0.0
                    n = 0
                    for i in range(g, Nb, G):
                        s += A[i]
                        n += 1
                    amean[g] = s / float(n)
            move_bats(X, V, S, Zb, freq, per_dim, buf, o, r, amean, G, shared, kb, sigma, toward,
                      span_walk, lower, upper)
            for i in range(Nb):  # keep the acceptance numbers: a noisy evaluation takes too
                level[i] = buf[o_acc + i]
            evaluate_bats(stream, objective, shifted, shift, lower, upper, S, Fnew, everyone,
                          work, G, Fb, Zb, epoch, best, best_x)
            for i in range(Nb):  # acceptance (Yang 2010)
                fb = fb_before[kb if shared else i % G]
                ok[i] = level[i] < A[i] and (Fnew[i] < fb if accept_best else Fnew[i] <= F[i])
                if always or ok[i]:
                    F[i] = Fnew[i]
                    for j in range(d):
                        X[i, j] = S[i, j]
            for i in range(Nb):  # eq 15's exp(-gamma t), numpy's exp of every bat's
                level[i] = -pos[i % G, 1] * clock
            exp_inplace(level, call)
            for i in range(Nb):  # eqs 14-15
                if per_iteration or ok[i]:
                    A[i] = A[i] * pos[i % G, 0]
                    r[i] = r0[i] * (1.0 - level[i])
        # ---- HPSO: the PSO step on (alpha, gamma) after each epoch but the last
        if hpso and t % K == 0 and t < T:
            for g in range(G):
                if epoch[g] < pbest_f[g]:
                    pbest[g, 0] = pos[g, 0]
                    pbest[g, 1] = pos[g, 1]
                    pbest_f[g] = epoch[g]
            k = 0
            for g in range(1, G):
                if pbest_f[g] < pbest_f[k]:
                    k = g
            o = take(stream, RANDOM, G * 4)
            for g in range(G):
                for c in range(2):
                    v = (params[23] * vel[g, c]
                         + params[21] * buf[o + g * 4 + c] * (pbest[g, c] - pos[g, c])
                         + params[22] * buf[o + g * 4 + 2 + c] * (pbest[k, c] - pos[g, c]))
                    vmax = params[24] * (hi[c] - lo[c])
                    vel[g, c] = min(max(v, -vmax), vmax)
                    pos[g, c] = min(max(pos[g, c] + vel[g, c], lo[c]), hi[c])
            for g in range(G):
                epoch[g] = np.inf
            if restart != NONE:  # ``_restart_bats``: a new MFB run from where the bats are
                for i in range(Nb):
                    A[i] = A0[i]
                    r[i] = 0.0
                    for j in range(d):
                        V[i, j] = 0.0
        curve[t - 1] = best[0]
    return best[0], best_x, curve, Nb * (T + 1)


for _name in ("MFB", "HPSO-MFB"):
    register_kernel(Kernel(_name, run, _packer(_name)))
