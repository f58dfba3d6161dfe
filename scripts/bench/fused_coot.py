"""Independent fused loops of COOT, mCOOT and ICOOT (default parameters), for
``scripts/bench/kernels.py``: COOT.m's loop as its authors wrote it (coots moved one by one in
place, the coot/leader swap, the leaders' proposals and acceptance), with mCOOT's opposition
jumps and ICOOT's gBest-led random move and density acceleration. See ``fused_common.py``.
"""

from __future__ import annotations

import math

import numpy as np
from fused_common import cos_two_pi, keep_best, numpy_power, square_sum
from numba import njit

COOT, MCOOT, ICOOT = 0, 1, 2


def make_coot(objective, variant):
    """The loop of one of the three, N_L = ceil(0.1 N) leaders, COOT.m's counter (Max_iter =
    T + 1), mixed scalar/vector randoms, mirrored leader moves; mCOOT: 30% of the coots jump to
    their dynamic opposite, opposite initial agents; ICOOT: target gBest + Q - centre, density
    acceleration (cells of 0.1 of the box, power 2), leader gain 2."""
    omega = math.pi ** (2.0 / 2.0) / math.gamma(2.0 / 2.0 + 1.0)

    @njit
    def loop(rng, lower, upper, N, T):
        d = lower.size
        nl = math.ceil(0.1 * N)
        nc = N - nl
        jumpers = math.ceil(0.3 * nc - 1e-9) if variant == MCOOT else 0
        scratch = np.empty(d)
        best = np.array([np.inf])
        best_x = np.zeros(d)
        # initial agents: coots first, then leaders (mCOOT: and their opposites, the better)
        X = np.empty((2 * N, d))
        F = np.empty(2 * N)
        u = rng.random(N * d)
        m = 2 * N if variant == MCOOT else N
        for i in range(N):
            for j in range(d):
                X[i, j] = lower[j] + (upper[j] - lower[j]) * u[i * d + j]
                if variant == MCOOT:
                    X[N + i, j] = min(max((lower[j] + upper[j]) - X[i, j], lower[j]), upper[j])
        for i in range(m):
            F[i] = objective(X[i], scratch)
        keep_best(F, X, m, best, best_x)
        for i in range(N):
            if variant == MCOOT and F[N + i] < F[i]:
                F[i] = F[N + i]
                X[i] = X[N + i]
        CP = X[:nc].copy()
        CF = F[:nc].copy()
        LP = X[nc:N].copy()
        LF = F[nc:N].copy()
        k = 0
        for i in range(1, N):
            if F[i] < F[k]:
                k = i
        g = X[k].copy()
        gf = F[k]
        acc_c = np.ones(nc)
        acc_l = np.ones(nl)
        temp = np.empty((nl, d))
        TF = np.empty(nl)
        g0 = np.empty(d)
        opp = np.empty((max(jumpers, 1), d))
        FO = np.empty(max(jumpers, 1))
        pick = np.empty(max(jumpers, 1), dtype=np.int64)
        taken = np.zeros(nc, dtype=np.bool_)
        extra = nc if variant == MCOOT else (nc + nl if variant == ICOOT else 0)
        size = 5 * nc + 2 * nc * d + 4 * nl + 2 * nl * d + extra
        u = np.empty(size)
        cells = 0.1 * (upper - lower)
        for t in range(1, T + 1):
            A = 1.0 - (t + 1) * (1.0 / (T + 1))
            B = 2.0 - (t + 1) * (1.0 / (T + 1))
            for q in range(size):
                u[q] = rng.random()
            v1 = 5 * nc
            v2 = v1 + nc * d
            lf = v2 + nc * d
            lv1 = lf + 4 * nl
            lv2 = lv1 + nl * d
            ex = lv2 + nl * d
            if variant == ICOOT:  # eqs 21-29 over the coots, then eq 24
                widest = -np.inf
                for j in range(d):
                    lo = CP[0, j]
                    hi = CP[0, j]
                    at = 0
                    for i in range(1, nc):
                        if CP[i, j] < lo:
                            lo = CP[i, j]
                            at = i
                        hi = max(hi, CP[i, j])
                    widest = max(widest, (hi - lo) / cells[j])
                    second = np.inf
                    for i in range(nc):
                        if i != at:
                            second = min(second, CP[i, j])
                    scratch[j] = (second - lo) / cells[j]
                r = 0.5 * widest + 1.0
                gaps = math.sqrt(square_sum(scratch, d))
                alpha = omega * numpy_power(r, 2.0) * gaps - nc
                s = (1.0 - numpy_power(r, -2.0)) + (1.0 - 1.0 / max(abs(alpha), 1.0))
                for i in range(nc):
                    acc_c[i] = abs(s - 2.0 * u[ex + i])
                for i in range(nl):
                    acc_l[i] = abs(s - 2.0 * u[ex + nc + i])
            for i in range(nc):  # the coots, in place, one by one
                follow = u[nc + i] < 0.5
                vec = u[i] >= 0.5
                if not follow and i > 0 and u[2 * nc + i] < 0.5:  # chain
                    for j in range(d):
                        CP[i, j] = (CP[i - 1, j] + CP[i, j]) * 0.5
                    continue
                lead = (i + 1) % nl
                for j in range(d):
                    a = v1 + i * d + j if vec else 3 * nc + i
                    b = v2 + i * d + j if vec else 4 * nc + i
                    x = CP[i, j]
                    if follow:
                        w = cos_two_pi(2.0 * u[a]) * u[b] * (2.0 * acc_c[i]) + 1.0
                        y = (LP[lead, j] - x) * w + x
                    else:
                        q = u[v2 + i * d + j] * (upper[j] - lower[j]) + lower[j]
                        if variant == ICOOT:
                            q += g[j] - 0.5 * (lower[j] + upper[j])
                        y = (q - x) * (u[a] * (A * acc_c[i])) + x
                    CP[i, j] = min(max(y, lower[j]), upper[j])
            for i in range(nc):
                CF[i] = objective(CP[i], scratch)
            keep_best(CF, CP, nc, best, best_x)
            if jumpers:  # the coots of the smallest picks, in their order, jump to opposites
                for i in range(nc):
                    taken[i] = False
                for q in range(jumpers):
                    c = -1
                    for i in range(nc):
                        if not taken[i] and (c < 0 or u[ex + i] < u[ex + c]):
                            c = i
                    taken[c] = True
                    pick[q] = c
                for j in range(d):
                    lo = LP[0, j]
                    hi = LP[0, j]
                    for i in range(nc):
                        lo = min(lo, CP[i, j])
                        hi = max(hi, CP[i, j])
                    for i in range(1, nl):
                        lo = min(lo, LP[i, j])
                        hi = max(hi, LP[i, j])
                    for q in range(jumpers):
                        opp[q, j] = min(max((lo + hi) - CP[pick[q], j], lower[j]), upper[j])
                for q in range(jumpers):
                    FO[q] = objective(opp[q], scratch)
                keep_best(FO, opp, jumpers, best, best_x)
                for q in range(jumpers):
                    if FO[q] < CF[pick[q]]:
                        CF[pick[q]] = FO[q]
                        CP[pick[q]] = opp[q]
            for i in range(nc):  # a coot better than its leader swaps with it
                lead = (i + 1) % nl
                if CF[i] < LF[lead]:
                    for j in range(d):
                        CP[i, j], LP[lead, j] = LP[lead, j], CP[i, j]
                    CF[i], LF[lead] = LF[lead], CF[i]
            gain = B * (2.0 if variant == ICOOT else 1.0)
            g0[:] = g
            for q in range(nl):  # the leaders' proposals, from the gBest of the phase's start
                vec = u[lf + q] >= 0.5
                sign = 1.0 if u[lf + nl + q] < 0.5 else -1.0
                for j in range(d):
                    a = lv1 + q * d + j if vec else lf + 2 * nl + q
                    b = lv2 + q * d + j if vec else lf + 3 * nl + q
                    c = cos_two_pi(2.0 * u[a]) * u[b]
                    y = (g0[j] - LP[q, j]) * (c * (gain * acc_l[q])) + sign * g0[j]
                    temp[q, j] = min(max(y, lower[j]), upper[j])
            for q in range(nl):
                TF[q] = objective(temp[q], scratch)
            keep_best(TF, temp, nl, best, best_x)
            holder = -1
            hf = gf
            for q in range(nl):  # a proposal better than gBest takes it; its leader the old
                if TF[q] < hf:
                    if holder < 0:
                        LP[q] = g0
                    else:
                        LP[q] = temp[holder]
                    LF[q] = hf
                    holder = q
                    hf = TF[q]
            if holder >= 0:
                g[:] = temp[holder]
                gf = hf
        return best[0], best_x

    return loop
