"""The phases of a COOT/ICOOT iteration compiled, shared by the optimizers' kernel
(:mod:`.coot`'s ``run``) and the planners' decision kernel
(:mod:`swarmpath.planners.compiled_coot`): the two differ only in where their uniforms come from
and in the objective, so each draws an iteration's uniforms into ``u`` (the layout of
:func:`offsets`) and calls these in the reference's order. Every floating-point operation is the
reference's, in its order (:mod:`.coot`'s docstring).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.functions import cospi, dot
from swarmpath.optimizers.compiled.ufuncs import power


@njit(cache=True)
def _clip(v, lo, hi):
    """np.minimum(np.maximum(v, lo), hi) for a number."""
    if v < lo:
        v = lo
    if v > hi:
        v = hi
    return v


@njit(cache=True)
def _swarm_terms(CP, nc, cells, p, omega, rest_min, call):
    """ICOOT's (D, 1 - 1/|alpha|) of the coots CP[:nc] (``ICOOT.swarm_terms``)."""
    d = CP.shape[1]
    widest = -np.inf
    for j in range(d):
        lo = CP[0, j]
        hi = CP[0, j]
        arg = 0
        for i in range(1, nc):
            v = CP[i, j]
            if v < lo:
                lo = v
                arg = i
            if v > hi:
                hi = v
        e = (hi - lo) / cells[j]
        if e > widest:
            widest = e
        second = np.inf
        for i in range(nc):
            if i != arg and CP[i, j] < second:
                second = CP[i, j]
        rest_min[j] = (second - lo) / cells[j]
    r = 0.5 * widest + 1.0
    density = power(r, -p, call)
    beta2 = math.sqrt(dot(rest_min, rest_min, d)) if nc >= 2 else 0.0
    alpha = omega * power(r, p, call) * beta2 - nc
    free = 1.0 - 1.0 / max(abs(alpha), 1.0)
    return density, free


@njit(cache=True)
def offsets(nc, nl, d):
    """Where each group of an iteration's uniforms starts in u: per coot flag, follow, chain and
    two scalars from 0; the coots' two vectors (o_v1, o_v2); per leader flag, sign and two
    scalars (o_lflag); the leaders' two vectors (o_lv1, o_lv2); the variant's extra draws
    (o_extra)."""
    o_v1 = 5 * nc
    o_v2 = o_v1 + nc * d
    o_lflag = o_v2 + nc * d
    o_lv1 = o_lflag + 4 * nl
    o_lv2 = o_lv1 + nl * d
    return o_v1, o_v2, o_lflag, o_lv1, o_lv2, o_lv2 + nl * d


@njit(cache=True)
def split(X, F, N, nl):
    """The swarm after initialization: (coots, their values, leaders, their values, gBest, its
    value, each coot's leader); the first N - nl agents are the coots."""
    nc = N - nl
    k = 0
    for i in range(1, N):
        if F[i] < F[k]:
            k = i
    leader_of = np.empty(nc, dtype=np.int64)
    for i in range(nc):
        leader_of[i] = (i + 1) % nl
    return (X[:nc].copy(), F[:nc].copy(), X[nc:N].copy(), F[nc:N].copy(), X[k].copy(), F[k],
            leader_of)


@njit(cache=True)
def accelerate(CP, cells, power_, omega, rest_min, call, u, acc_c, acc_l):
    """ICOOT's density acceleration of the coots and leaders (from the iteration's extra
    uniforms)."""
    nc, nl = acc_c.size, acc_l.size
    o_extra = offsets(nc, nl, CP.shape[1])[5]
    density, free = _swarm_terms(CP, nc, cells, power_, omega, rest_min, call)
    s = (1.0 - density) + free
    for i in range(nc):
        acc_c[i] = abs(s - 2.0 * u[o_extra + i])
    for i in range(nl):
        acc_l[i] = abs(s - 2.0 * u[o_extra + nc + i])


@njit(cache=True)
def move_coots(CP, LP, leader_of, u, randoms, A, acc_c, use_acc, icoot, target, g, lb, ub,
               span, mid):
    """The coots' moves of one iteration, in order and in place (eqs 12-17, ICOOT 30-31);
    ``span`` is ub - lb and ``mid`` 0.5 * (lb + ub)."""
    nc, d = CP.shape
    o_v1, o_v2 = offsets(nc, LP.shape[0], d)[:2]
    o_follow, o_chain, o_s1, o_s2 = nc, 2 * nc, 3 * nc, 4 * nc
    for i in range(nc):
        follow = u[o_follow + i] < 0.5
        if randoms == 0:
            vec = u[i] >= 0.5
        else:
            vec = randoms == 1
        if not follow and i > 0 and u[o_chain + i] < 0.5:  # eq 15, predecessor moved
            for j in range(d):
                CP[i, j] = (CP[i - 1, j] + CP[i, j]) * 0.5
            continue
        if follow:
            fa = 2.0 * acc_c[i] if use_acc else 2.0
            lead = leader_of[i]
            w = 0.0 if vec else cospi(4.0 * u[o_s1 + i]) * u[o_s2 + i] * fa + 1.0
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


@njit(cache=True)
def swap(CP, CF, LP, LF, leader_of, gbest_any, g, gf):
    """COOT.m's coot/leader swap (strict <); with ``gbest`` "any" the best leader then takes
    the gBest if it is better. Returns the gBest's value (g is updated in place)."""
    d = CP.shape[1]
    for i in range(leader_of.size):
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
        k = 0
        for i in range(1, LF.size):
            if LF[i] < LF[k]:
                k = i
        if LF[k] < gf:
            gf = LF[k]
            g[:] = LP[k]
    return gf


@njit(cache=True)
def propose_leaders(LP, g, g0, temp, u, nc, randoms, gain, acc_l, use_acc, mirror_minus, lb,
                    ub):
    """The leaders' proposals of one iteration into temp (eq 18, ICOOT 32), all from the gBest
    at the start of the phase (copied to g0)."""
    nl, d = LP.shape
    o_lflag, o_lv1, o_lv2 = offsets(nc, nl, d)[2:5]
    o_lsign, o_ls1, o_ls2 = o_lflag + nl, o_lflag + 2 * nl, o_lflag + 3 * nl
    g0[:] = g
    for k in range(nl):
        if randoms == 0:
            vec = u[o_lflag + k] >= 0.5
        else:
            vec = randoms == 1
        sign = 1.0 if u[o_lsign + k] < 0.5 else -1.0
        factor = gain * acc_l[k] if use_acc else gain
        for j in range(d):
            if vec:
                c = cospi(4.0 * u[o_lv1 + k * d + j]) * u[o_lv2 + k * d + j]
            else:
                c = cospi(4.0 * u[o_ls1 + k]) * u[o_ls2 + k]
            v = (g0[j] - LP[k, j]) * (c * factor)
            if mirror_minus:
                v += sign * g0[j]
            else:
                v += g0[j]
            temp[k, j] = _clip(v, lb[j], ub[j])


@njit(cache=True)
def accept_leaders(LP, LF, temp, TF, g0, g, gf, leader_code):
    """The leaders' acceptance sweep of the scored proposals (COOT.m's, strict <). Returns the
    gBest's value (g is updated in place)."""
    holder = -1  # -1: the gBest of the phase's start
    hf = gf
    for k in range(LP.shape[0]):
        if TF[k] < hf:
            if leader_code:
                LP[k] = g0 if holder < 0 else temp[holder]
                LF[k] = hf
            holder = k
            hf = TF[k]
        if not leader_code:
            LP[k] = temp[k]
            LF[k] = TF[k]
    if holder >= 0:
        g[:] = temp[holder]
        gf = hf
    return gf
