"""One swarm decision of the ICOOT and COOT planners compiled: the optimizer's whole loop.

The reference is the numpy loop of ``SwarmLocalPlanner._decide`` (``create``, ``initialize``,
``step`` until done or ``patience`` stalls) with :class:`~swarmpath.optimizers.icoot.ICOOT`
(or COOT) on one run whose objective is ``local.score``. The iteration is that of the
optimizers' own compiled COOT kernel (:mod:`swarmpath.optimizers.compiled.coot`, bit for bit
the numpy reference's numbers, ``tests/test_compiled_coot.py``) with two changes: the draws go
straight to the planner's generator (its ``RunStreams`` does not buffer), one ``rng.random``
per draw of the reference, in its order and sizes; and the objective is the compiled score
(:func:`.compiled_score.score_into`). A decision gives the same best point, value and number
of iterations as the numpy loop, and leaves the generator where the loop leaves it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.coot import _clip, _swarm_terms
from swarmpath.optimizers.compiled.functions import cospi
from swarmpath.planners.compiled_score import score_into

Array = np.ndarray
_RANDOMS = ("mixed", "vector", "scalar")
_TARGETS = ("centred", "literal", "offset", "midpoint")


def pack(name: str, p: Mapping[str, Any]) -> Array:
    """The kernel's parameter vector of COOT or ICOOT's resolved parameters."""
    icoot = name == "ICOOT"
    power_ = float(p.get("density_power", 2.0))
    omega = math.pi ** (power_ / 2.0) / math.gamma(power_ / 2.0 + 1.0)  # as icoot.py
    return np.array([
        icoot, int(p["leaders"]), float(p["leader_fraction"]), _RANDOMS.index(str(p["randoms"])),
        p["gbest"] == "any", p["mirror"] == "minus", p["leader_update"] == "code",
        p["counter"] == "code", _TARGETS.index(str(p.get("random_target", "centred"))),
        icoot and p["acc"] == "density", float(p.get("cell", 0.1)), power_,
        float(p.get("leader_gain", 1.0)), omega,
    ], dtype=np.float64)


@njit(cache=True)
def record(F: Array, X: Array, m: int, best: Array, best_x: Array) -> None:
    """``Optimizer.record``: NaN counts as +inf (in F too), the first minimum, strict <."""
    k = 0
    for i in range(m):
        if np.isnan(F[i]):
            F[i] = np.inf
        if F[i] < F[k]:
            k = i
    if F[k] < best[0]:
        best[0] = F[k]
        best_x[:] = X[k]


@njit(cache=True)
def stalled_after(before: float, now: float, stalled: int, tol: float) -> int:
    """The planner's count of iterations in a row without improvement (``patience``)."""
    if before - now <= tol * max(1.0, abs(before)):
        return stalled + 1
    return 0


@njit(cache=True)
def _draw(rng: Any, u: Array, at: int, size: int) -> None:
    u[at : at + size] = rng.random(size)


@njit(cache=True)
def coot_decide(rng: Any, lb: Array, ub: Array, N: int, T: int, params: Array, geo: Array,
                hits: Array, k: Array, patience: int, tol: float) -> tuple[float, Array, int]:
    """(best value, best point, iterations done) of one decision."""
    d = lb.size
    icoot, randoms = params[0] == 1.0, int(params[3])
    nl = int(params[1])
    if nl == 0:
        nl = math.ceil(params[2] * N)
    gbest_any, mirror_minus = params[4] == 1.0, params[5] == 1.0
    leader_code, counter_code = params[6] == 1.0, params[7] == 1.0
    target, use_acc = int(params[8]), params[9] == 1.0
    cell, power_, leader_gain, omega = params[10], params[11], params[12], params[13]
    nc = N - nl
    span = ub - lb
    mid = 0.5 * (lb + ub)
    cells = cell * span
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    rest_min = np.empty(d)
    call = np.zeros(10, dtype=np.int64)
    leader_of = np.empty(nc, dtype=np.int64)
    for i in range(nc):
        leader_of[i] = (i + 1) % nl

    # ---- initialization: N uniform agents, coots first
    X = np.empty((N, d))
    F = np.empty(N)
    draw = rng.random(N * d)
    for i in range(N):
        for j in range(d):
            X[i, j] = lb[j] + span[j] * draw[i * d + j]
    score_into(X, geo, hits, k, F)
    record(F, X, N, best, best_x)
    CP = X[:nc].copy()
    CF = F[:nc].copy()
    LP = X[nc:N].copy()
    LF = F[nc:N].copy()
    g_at = 0
    for i in range(1, N):
        if F[i] < F[g_at]:
            g_at = i
    g = X[g_at].copy()
    gf = F[g_at]

    # ---- the layout of an iteration's uniforms (offsets into u)
    o_follow, o_chain, o_s1, o_s2, o_v1 = nc, 2 * nc, 3 * nc, 4 * nc, 5 * nc
    o_v2 = o_v1 + nc * d
    o_lflag = o_v2 + nc * d
    o_lsign, o_ls1, o_ls2 = o_lflag + nl, o_lflag + 2 * nl, o_lflag + 3 * nl
    o_lv1 = o_lflag + 4 * nl
    o_lv2 = o_lv1 + nl * d
    o_extra = o_lv2 + nl * d
    u = np.empty(o_extra + (nc + nl if icoot else 0))
    acc_c = np.ones(nc)
    acc_l = np.ones(nl)
    g0 = np.empty(d)
    temp = np.empty((nl, d))
    TF = np.empty(nl)
    inv = 1.0 / (T + 1) if counter_code else 1.0 / T
    before = best[0]
    stalled = 0
    t = 0
    while t < T:
        t += 1
        step = t + 1 if counter_code else t
        A = 1.0 - step * inv
        B = 2.0 - step * inv
        _draw(rng, u, 0, 5 * nc)
        _draw(rng, u, o_v1, 2 * nc * d)
        _draw(rng, u, o_lflag, 4 * nl)
        _draw(rng, u, o_lv1, 2 * nl * d)
        if icoot:  # c_accU, l_accU (one draw when of equal shape: the same numbers)
            _draw(rng, u, o_extra, nc + nl)
        if use_acc:
            density, free = _swarm_terms(CP, nc, cells, power_, omega, rest_min, call)
            s = (1.0 - density) + free
            for i in range(nc):
                acc_c[i] = abs(s - 2.0 * u[o_extra + i])
            for i in range(nl):
                acc_l[i] = abs(s - 2.0 * u[o_extra + nc + i])

        # ---- coots, in order and in place (eqs 12-17, ICOOT 30-31)
        for i in range(nc):
            follow = u[o_follow + i] < 0.5
            vec = u[i] >= 0.5 if randoms == 0 else randoms == 1
            if not follow and i > 0 and u[o_chain + i] < 0.5:  # eq 15, predecessor moved
                for j in range(d):
                    CP[i, j] = (CP[i - 1, j] + CP[i, j]) * 0.5
                continue
            if follow:
                fa = 2.0 * acc_c[i] if use_acc else 2.0
                lead = leader_of[i]
                w = cospi(4.0 * u[o_s1 + i]) * u[o_s2 + i] * fa + 1.0
                for j in range(d):
                    if vec:
                        w = cospi(4.0 * u[o_v1 + i * d + j]) * u[o_v2 + i * d + j] * fa + 1.0
                    x = CP[i, j]
                    CP[i, j] = _clip((LP[lead, j] - x) * w + x, lb[j], ub[j])
            else:
                ra = A * acc_c[i] if use_acc else A
                w = u[o_s1 + i] * ra
                for j in range(d):
                    if vec:
                        w = u[o_v1 + i * d + j] * ra
                    x = CP[i, j]
                    q = u[o_v2 + i * d + j] * span[j] + lb[j]
                    if icoot:
                        if target == 0:
                            q += g[j] - mid[j]
                        elif target == 1:
                            q += g[j]
                        elif target == 2:
                            q += g[j]
                            q -= x
                        else:
                            q += g[j]
                            q *= 0.5
                    CP[i, j] = _clip((q - x) * w + x, lb[j], ub[j])
        score_into(CP, geo, hits, k, CF)
        record(CF, CP, nc, best, best_x)

        # ---- coot/leader swap (COOT.m's sweep, strict <)
        for i in range(nc):
            lead = leader_of[i]
            if CF[i] < LF[lead]:
                for j in range(d):
                    v = CP[i, j]
                    CP[i, j] = LP[lead, j]
                    LP[lead, j] = v
                v = CF[i]
                CF[i] = LF[lead]
                LF[lead] = v
        if gbest_any:
            at = 0
            for i in range(1, nl):
                if LF[i] < LF[at]:
                    at = i
            if LF[at] < gf:
                gf = LF[at]
                g[:] = LP[at]

        # ---- leaders (eq 18, ICOOT 32), all from the gBest at the start of the phase
        g0[:] = g
        gain = B * leader_gain
        for m in range(nl):
            vec = u[o_lflag + m] >= 0.5 if randoms == 0 else randoms == 1
            sign = 1.0 if u[o_lsign + m] < 0.5 else -1.0
            factor = gain * acc_l[m] if use_acc else gain
            for j in range(d):
                if vec:
                    c = cospi(4.0 * u[o_lv1 + m * d + j]) * u[o_lv2 + m * d + j]
                else:
                    c = cospi(4.0 * u[o_ls1 + m]) * u[o_ls2 + m]
                v = (g0[j] - LP[m, j]) * (c * factor)
                if mirror_minus:
                    v += sign * g0[j]
                else:
                    v += g0[j]
                temp[m, j] = _clip(v, lb[j], ub[j])
        score_into(temp, geo, hits, k, TF)
        record(TF, temp, nl, best, best_x)
        holder = -1  # -1: the gBest of the phase's start
        hf = gf
        for m in range(nl):
            if TF[m] < hf:
                if leader_code:
                    LP[m] = g0 if holder < 0 else temp[holder]
                    LF[m] = hf
                holder = m
                hf = TF[m]
            if not leader_code:
                LP[m] = temp[m]
                LF[m] = TF[m]
        if holder >= 0:
            g[:] = temp[holder]
            gf = hf
        stalled = stalled_after(before, best[0], stalled, tol)
        before = best[0]
        if patience > 0 and stalled >= patience and before < 1e6:
            break
    return best[0], best_x, t
