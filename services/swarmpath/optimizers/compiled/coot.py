"""Compiled kernels of COOT, mCOOT and ICOOT: one run per call, the numpy reference's numbers.

The reference is :mod:`swarmpath.optimizers.coot` (with ``mcoot`` and ``icoot``): its docstrings
state the algorithm. Here an iteration is one loop over the run's agents in the order in which
COOT.m moves them (the reference replays that sweep with array operations), with every
floating-point operation of the reference, in its order (the package's rules):

* draws: the reference's layout of an iteration's uniforms, in its grouped draws (per coot flag,
  follow, chain and two scalars; two vectors per coot; per leader flag, sign and two scalars; two
  vectors per leader; then mCOOT's picks or ICOOT's two rows of U(0, 1)). Every branch gets its
  numbers whether it uses them or not, as in the reference;
* the in-place chain (eq 15), the coot/leader swap and the leader acceptance sweep are COOT.m's
  sequential loops, which the reference reproduces with chain depths and record sweeps;
* mCOOT's jumping coots are the m smallest picks, their opposites evaluated in ascending order
  of the picks (``mcoot.py``); ICOOT's r^-p and r^p go through numpy's own power loop
  (:mod:`.ufuncs`: on AVX-512 its SVML pow differs from the C library's in the last bit for
  about 5% of arguments, which moved ICOOT runs after about 450 iterations).

One compiled ``run`` serves the three algorithms: ``params[0]`` says which (:func:`pack`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.base import ParameterError
from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.functions import cospi, dot, evaluate
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import power, with_objective
from swarmpath.registry import ParamValue

COOT, MCOOT, ICOOT = 0, 1, 2
_VARIANTS = {"COOT": COOT, "mCOOT": MCOOT, "ICOOT": ICOOT}
_RANDOMS = ("mixed", "vector", "scalar")
_TARGETS = ("centred", "literal", "offset", "midpoint")


def _packer(name: str):
    def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
        power_ = float(p.get("density_power", 2.0))
        omega = math.pi ** (power_ / 2.0) / math.gamma(power_ / 2.0 + 1.0)  # as icoot.py
        return np.array([
            _VARIANTS[name], int(p["leaders"]), float(p["leader_fraction"]),
            _RANDOMS.index(str(p["randoms"])), p["gbest"] == "any", p["mirror"] == "minus",
            p["leader_update"] == "code", p["counter"] == "code",
            p.get("opposition", "dynamic") == "dynamic", float(p.get("jump_rate", 0.0)),
            bool(p.get("opposition_init", False)),
            _TARGETS.index(str(p.get("random_target", "centred"))),
            p.get("acc", "one") == "density", float(p.get("cell", 0.1)), power_,
            float(p.get("leader_gain", 1.0)), omega,
        ], dtype=np.float64)

    return pack


def _checker(name: str):
    def check(p: Mapping[str, ParamValue], agents: int) -> None:
        """``COOT.__init__``'s check of N_L (the kernel computes N_L as it does)."""
        nl = int(p["leaders"]) or math.ceil(float(p["leader_fraction"]) * agents)
        if not 1 <= nl < agents:
            raise ParameterError(
                f"{name}.leaders must leave at least one coot: got {nl} of {agents} agents"
            )

    return check


@njit(cache=True)
def _clip(v, lo, hi):
    """np.minimum(np.maximum(v, lo), hi) for a number."""
    if v < lo:
        v = lo
    if v > hi:
        v = hi
    return v


@njit(cache=True)
def _smallest(keys, m, out):
    """Indices of the m smallest keys in ascending order, ties by index (a stable argsort's
    first m): a partial insertion sort."""
    count = 0
    for i in range(keys.size):
        v = keys[i]
        if count == m and not v < keys[out[m - 1]]:
            continue
        pos = min(count, m - 1)
        while pos > 0 and v < keys[out[pos - 1]]:
            out[pos] = out[pos - 1]
            pos -= 1
        out[pos] = i
        if count < m:
            count += 1


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
def _take(stream, size, u, at):
    """One draw of ``size`` uniforms of the reference, copied to u[at:at + size]."""
    o = take(stream, RANDOM, size)
    u[at : at + size] = stream[1][RANDOM][o : o + size]


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


def loop(evaluate_, rng, fid, shifted, shift, lb, ub, N, T, params):
    """``run`` with the objective ``evaluate_`` (``functions.evaluate``'s signature), for
    ``scripts/bench/kernels.py``'s fused loop (compiled per objective, not cached)."""
    return with_objective(run, evaluate_)(rng, fid, shifted, shift, lb, ub, N, T, params)


@njit(cache=True)
def run(rng, fid, shifted, shift, lb, ub, N, T, params):
    """One run (the package's kernel signature)."""
    d = lb.size
    variant, randoms = int(params[0]), int(params[3])
    nl = int(params[1])
    if nl == 0:
        nl = math.ceil(params[2] * N)
    gbest_any, mirror_minus = params[4] == 1.0, params[5] == 1.0
    leader_code, counter_code = params[6] == 1.0, params[7] == 1.0
    dynamic, opposition_init = params[8] == 1.0, params[10] == 1.0
    target, density_acc = int(params[11]), params[12] == 1.0
    cell, power_, leader_gain, omega = params[13], params[14], params[15], params[16]
    nc = N - nl
    jumpers = math.ceil(params[9] * nc - 1e-9) if variant == MCOOT else 0
    stream = open_stream(rng, max(N * d, 2 * nc * d, 2 * N))
    mask = np.ones(2 * N, dtype=np.bool_)
    scratch = np.empty((4, d))
    span = ub - lb
    mid = 0.5 * (lb + ub)
    cells = cell * span
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    evals = 0
    curve = np.empty(T)
    F = np.empty(2 * N)
    rest_min = np.empty(d)
    call = np.zeros(10, dtype=np.int64)

    # ---- initialization: N uniform agents (mCOOT: and their opposites, the better kept)
    X = np.empty((2 * N, d))
    o = take(stream, RANDOM, N * d)
    buf = stream[1][RANDOM]
    for i in range(N):
        for j in range(d):
            X[i, j] = lb[j] + span[j] * buf[o + i * d + j]
    if variant == MCOOT and opposition_init:
        for i in range(N):
            for j in range(d):
                X[N + i, j] = _clip(lb[j] + ub[j] - X[i, j], lb[j], ub[j])
        evaluate(stream, fid, shifted, shift, lb, ub, X, F, mask, scratch)
        evals += 2 * N
        record_first_min(F, X, 2 * N, best, best_x)
        for i in range(N):
            if F[N + i] < F[i]:
                F[i] = F[N + i]
                X[i] = X[N + i]
    else:
        evaluate(stream, fid, shifted, shift, lb, ub, X[:N], F[:N], mask[:N], scratch)
        evals += N
        record_first_min(F, X, N, best, best_x)
    CP, CF, LP, LF, g, gf, leader_of = split(X, F, N, nl)
    o_v1, _, o_lflag, o_lv1, _, o_extra = offsets(nc, nl, d)
    size = o_extra
    if variant == MCOOT and jumpers:
        size += nc
    if variant == ICOOT:
        size += nc + nl
    u = np.empty(size)
    acc_c = np.ones(nc)
    acc_l = np.ones(nl)
    use_acc = variant == ICOOT and density_acc
    g0 = np.empty(d)
    temp = np.empty((nl, d))
    TF = np.empty(nl)
    pick = np.empty(nc, dtype=np.int64)
    opp = np.empty((nc, d))
    lo_all = np.empty(d)
    hi_all = np.empty(d)
    if counter_code:
        inv = 1.0 / (T + 1)
    else:
        inv = 1.0 / T

    for t in range(1, T + 1):
        step = t + 1 if counter_code else t
        A = 1.0 - step * inv
        B = 2.0 - step * inv
        _take(stream, 5 * nc, u, 0)
        _take(stream, 2 * nc * d, u, o_v1)
        _take(stream, 4 * nl, u, o_lflag)
        _take(stream, 2 * nl * d, u, o_lv1)
        if variant == MCOOT and jumpers:
            _take(stream, nc, u, o_extra)
        elif variant == ICOOT and nc == nl:  # equal shapes: one grouped draw
            _take(stream, 2 * nc, u, o_extra)
        elif variant == ICOOT:
            _take(stream, nc, u, o_extra)
            _take(stream, nl, u, o_extra + nc)
        if use_acc:
            accelerate(CP, cells, power_, omega, rest_min, call, u, acc_c, acc_l)
        move_coots(CP, LP, leader_of, u, randoms, A, acc_c, use_acc, variant == ICOOT, target, g,
                   lb, ub, span, mid)
        evaluate(stream, fid, shifted, shift, lb, ub, CP, CF, mask[:nc], scratch)
        evals += nc
        record_first_min(CF, CP, nc, best, best_x)

        # ---- mCOOT: generation jumping of the coots with the smallest picks, in their order
        if variant == MCOOT and jumpers:
            _smallest(u[o_extra : o_extra + nc], jumpers, pick)
            for j in range(d):
                if dynamic:
                    lo = CP[0, j]
                    hi = CP[0, j]
                    for i in range(1, nc):
                        lo = min(lo, CP[i, j])
                        hi = max(hi, CP[i, j])
                    for i in range(nl):
                        lo = min(lo, LP[i, j])
                        hi = max(hi, LP[i, j])
                    lo_all[j] = lo
                    hi_all[j] = hi
                else:
                    lo_all[j] = lb[j]
                    hi_all[j] = ub[j]
            for q in range(jumpers):
                for j in range(d):
                    opp[q, j] = _clip(lo_all[j] + hi_all[j] - CP[pick[q], j], lb[j], ub[j])
            evaluate(stream, fid, shifted, shift, lb, ub, opp[:jumpers], F[:jumpers],
                     mask[:jumpers], scratch)
            evals += jumpers
            record_first_min(F, opp, jumpers, best, best_x)
            for q in range(jumpers):
                if F[q] < CF[pick[q]]:
                    CP[pick[q]] = opp[q]
                    CF[pick[q]] = F[q]

        gf = swap(CP, CF, LP, LF, leader_of, gbest_any, g, gf)
        propose_leaders(LP, g, g0, temp, u, nc, randoms, B * leader_gain, acc_l, use_acc,
                        mirror_minus, lb, ub)
        evaluate(stream, fid, shifted, shift, lb, ub, temp, TF, mask[:nl], scratch)
        evals += nl
        record_first_min(TF, temp, nl, best, best_x)
        gf = accept_leaders(LP, LF, temp, TF, g0, g, gf, leader_code)
        curve[t - 1] = best[0]
    return best[0], best_x, curve, evals


for _name in _VARIANTS:
    register_kernel(Kernel(_name, run, _packer(_name), check=_checker(_name)))
