"""Compiled kernels of COOT, mCOOT and ICOOT: one run per call, the numpy reference's numbers.

The reference is :mod:`swarmpath.optimizers.coot` (with ``mcoot`` and ``icoot``): its docstrings
state the algorithm. Here an iteration is one loop over the run's agents in the order in which
COOT.m moves them (the reference replays that sweep with array operations), with every
floating-point operation of the reference, in its order (the package's rules):

* draws: the reference's layout of an iteration's uniforms, in its grouped draws (per coot flag,
  follow, chain and two scalars; two vectors per coot; per leader flag, sign and two scalars; two
  vectors per leader; then mCOOT's picks or ICOOT's two rows of U(0, 1)), as one take of a
  direct stream (uniforms only: the same numbers as the reference's several draws). Every
  branch gets its numbers whether it uses them or not, as in the reference;
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
from swarmpath.optimizers.compiled.coot_phases import (
    _clip,
    accelerate,
    accept_leaders,
    move_coots,
    offsets,
    propose_leaders,
    split,
    swap,
)
from swarmpath.optimizers.compiled.objectives import evaluate, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
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
def run(rng, objective, shifted, shift, lb, ub, N, T, params):
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
    stream = open_stream(rng, 2 * N * d + 6 * N, False)  # an iteration: see size
    mask = np.ones(2 * N, dtype=np.bool_)
    scratch = work_for(2 * N, d)
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
        evaluate(stream, objective, shifted, shift, lb, ub, X, F, mask, scratch)
        evals += 2 * N
        record_first_min(F, X, 2 * N, best, best_x)
        for i in range(N):
            if F[N + i] < F[i]:
                F[i] = F[N + i]
                X[i] = X[N + i]
    else:
        evaluate(stream, objective, shifted, shift, lb, ub, X[:N], F[:N], mask[:N], scratch)
        evals += N
        record_first_min(F, X, N, best, best_x)
    CP, CF, LP, LF, g, gf, leader_of = split(X, F, N, nl)
    o_extra = offsets(nc, nl, d)[5]
    size = o_extra
    if variant == MCOOT and jumpers:
        size += nc
    if variant == ICOOT:
        size += nc + nl
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
        # the iteration's draws (per coot, per leader, the variant's) are consecutive takes of
        # one kind: one take of them all gives the same numbers (a direct stream). A noisy
        # function's evaluations take their m <= N numbers into the front of the same buffer,
        # the per-coot flags (5 N_c numbers), which are used before the coots' evaluation
        o = take(stream, RANDOM, size)
        u = stream[1][RANDOM][o : o + size]
        if use_acc:
            accelerate(CP, cells, power_, omega, rest_min, call, u, acc_c, acc_l)
        move_coots(CP, LP, leader_of, u, randoms, A, acc_c, use_acc, variant == ICOOT, target, g,
                   lb, ub, span, mid)
        evaluate(stream, objective, shifted, shift, lb, ub, CP, CF, mask[:nc], scratch)
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
            evaluate(stream, objective, shifted, shift, lb, ub, opp[:jumpers], F[:jumpers],
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
        evaluate(stream, objective, shifted, shift, lb, ub, temp, TF, mask[:nl], scratch)
        evals += nl
        record_first_min(TF, temp, nl, best, best_x)
        gf = accept_leaders(LP, LF, temp, TF, g0, g, gf, leader_code)
        curve[t - 1] = best[0]
    return best[0], best_x, curve, evals


for _name in _VARIANTS:
    register_kernel(Kernel(_name, run, _packer(_name), check=_checker(_name)))
