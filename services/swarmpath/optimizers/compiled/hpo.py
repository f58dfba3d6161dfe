"""Compiled kernels of HPO and IHPO: one run per call, the numpy reference's numbers.

The reference is :mod:`swarmpath.optimizers.hpo` (with ``ihpo``); its docstrings state the
algorithm. An iteration draws the reference's two arrays (per agent and component: u, then the
prey's angles unless ``prey_angle = "from_z"``, then IHPO's per-component betas; per agent: r2,
the hunter test, then IHPO's per-agent betas), computes C Z and the prey's factor S (the
cosine through numpy's own loop, on the whole slab as the reference), and then moves the agents:

* ``update = "sequential"`` (the authors' sweep, the default): agent by agent, each from the
  population as the agents before it left it (a hunter's mean and distance ranking recomputed)
  and toward the best point so far, then clipped and evaluated alone, which is what the
  reference's loop over agents does (one evaluation per agent: F7's noise too);
* ``update = "synchronous"``: every agent from the population and best point of the
  iteration's start, evaluated together.

Every floating-point operation is the reference's, in its order: the population mean added in
agent order (numpy's reduction over the agents' axis), the squared distances as ``einsum``
adds them (:func:`functions.dot`), C P + (1 - C) mu, IHPO's alpha = (2 u - 1) sin(C - t/T)
with ``math.sin`` (Python's, the C library's).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numba import njit

from swarmpath.optimizers.compiled.best import record_first_min
from swarmpath.optimizers.compiled.functions import dot
from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT
from swarmpath.optimizers.compiled.objectives import evaluate, evaluate_rows, work_for
from swarmpath.optimizers.compiled.registry import Kernel, register_kernel
from swarmpath.optimizers.compiled.streams import RANDOM, open_stream, take
from swarmpath.optimizers.compiled.ufuncs import cos_inplace
from swarmpath.optimizers.hpo import HPO
from swarmpath.optimizers.ihpo import IHPO
from swarmpath.registry import ParamValue

TWO_PI = 2.0 * math.pi
_HUNTER = HPO.choices["hunter"]
_ALPHA_ON = IHPO.choices["alpha_on"]  # step, displacement, literal, position
_BRANCHES = IHPO.choices["alpha_branches"]  # both, hunter, prey
_BETA_DRAW = IHPO.choices["beta_draw"]  # agent, iteration, dimension
STEP, DISPLACEMENT, LITERAL, POSITION = range(4)
BOTH, HUNTER_ONLY, PREY_ONLY = range(3)
PER_AGENT, PER_ITERATION, PER_DIMENSION = range(3)


def _packer(name: str):
    def pack(p: Mapping[str, ParamValue]) -> np.ndarray:
        return np.array([
            name == "IHPO", float(p["beta"]), p["prey_step"] == "2Z",
            p["prey_angle"] == "independent", _HUNTER.index(str(p["hunter"])),
            _ALPHA_ON.index(str(p.get("alpha_on", "literal"))),
            _BRANCHES.index(str(p.get("alpha_branches", "both"))),
            _BETA_DRAW.index(str(p.get("beta_draw", "agent"))), p.get("cp_c", "hpo") == "hpo",
            p["update"] == "sequential",
        ], dtype=np.float64)

    return pack


@njit(cache=True)
def matlab_round(x):
    """``hpo.matlab_round``: half away from zero."""
    a = abs(x)
    r = math.floor(a)
    if a - r >= 0.5:
        r += 1
    return int(math.copysign(r, x))


@njit(cache=True, **NO_REFCOUNT)
def anchor(X, kbest, P, mu, dist2):
    """``HPO._hunter_anchor``: mu the population mean (added in agent order) and P the agent of
    the kbest-th smallest squared distance to it (a stable order: ties by index)."""
    N, d = X.shape
    for j in range(d):
        s = 0.0  # numpy's reduction starts from its identity (-0.0 + -0.0 gives 0.0)
        for i in range(N):
            s = s + X[i, j]
        mu[j] = s / N
    for i in range(N):
        for j in range(d):
            P[j] = X[i, j] - mu[j]
        dist2[i] = dot(P, P, d)
    for i in range(N):  # the agent with kbest - 1 agents before it in the stable order
        below = 0
        for k in range(N):
            if dist2[k] < dist2[i] or (dist2[k] == dist2[i] and k < i):
                below += 1
        if below == kbest - 1:
            for j in range(d):
                P[j] = X[i, j]
            return


@njit(cache=True)
def hunter_move(hunter, z, x, target, centre):
    """``HPO._hunter_move`` for one coordinate: paper z target; centre, relative: base +
    z (target - base) from the box centre or the agent."""
    if hunter == 0:
        return z * target
    base = x if hunter == 2 else centre
    return (target - base) * z + base


@njit(cache=True, **NO_REFCOUNT)
def draw_terms(stream, N, d, C, t, T, params, CZ, S, alpha, hunters, call):
    """One iteration's numbers (``HPO._draw`` and IHPO's alpha): C Z, the prey's factor S (times
    alpha where eq 14b applies it), alpha (IHPO) and the hunters' test, in place."""
    ihpo, beta, two_z, independent = params[0] == 1.0, params[1], params[2] == 1.0, params[3] == 1.0
    on, branches, how, cp_hpo = int(params[5]), int(params[6]), int(params[7]), params[8] == 1.0
    slabs = (2 if independent else 1) + (1 if ihpo and how == PER_DIMENSION else 0)
    rows = 2 + (1 if ihpo and how != PER_DIMENSION else 0)
    n = N * d
    o = take(stream, RANDOM, slabs * n)
    U = stream[1][RANDOM]
    for i in range(N):  # the second draw follows: keep what the first gives before taking it
        for j in range(d):
            CZ[i, j] = U[o + i * d + j]
            if independent:
                S[i, j] = (U[o + n + i * d + j] - 0.5) * TWO_PI
            if ihpo and how == PER_DIMENSION:
                alpha[i, j] = U[o + (slabs - 1) * n + i * d + j]
    o = take(stream, RANDOM, rows * N)
    V = stream[1][RANDOM]
    for i in range(N):
        cr2 = V[o + i] * C
        hunters[i] = V[o + N + i] < beta
        for j in range(d):
            u = CZ[i, j]
            CZ[i, j] = (u - cr2) + cr2 if u < C else cr2  # the reference's arithmetic blend
            if not independent:
                s = CZ[i, j] * (2.0 / C) - 1.0
                S[i, j] = (s - np.rint(s)) * TWO_PI
    cos_inplace(S.reshape(n), call)
    for i in range(N):
        for j in range(d):
            s = S[i, j] * CZ[i, j]
            S[i, j] = s * (2.0 / C) if two_z else s
    if ihpo:
        cp = math.sin((C if cp_hpo else 1.0) - t / T)
        for i in range(N):
            for j in range(d):
                if how == PER_DIMENSION:
                    u = alpha[i, j]
                else:
                    u = V[o + 2 * N + (0 if how == PER_ITERATION else i)]
                alpha[i, j] = (2.0 * u - 1.0) * cp
                if branches != HUNTER_ONLY and (on == STEP or on == LITERAL):
                    S[i, j] = S[i, j] * alpha[i, j]  # eq 14b: T + alpha C Z cos(.) (T - x)


@njit(cache=True, **NO_REFCOUNT)
def move(X, i, C, kbest, params, CZ, S, alpha, hunters, T, lower, upper, centre, P, mu, dist2,
         out, k):
    """Agent i's new position (``HPO._moved`` / ``IHPO._moved`` of one row), clipped, into
    ``out[k]``: from the population X as it is and toward the best point T."""
    ihpo, hunter, on, branches = params[0] == 1.0, int(params[4]), int(params[5]), int(params[6])
    d = X.shape[1]
    plain = not ihpo or branches == HUNTER_ONLY or on == STEP or on == LITERAL
    for j in range(d):  # the prey's move (a hunter's row is replaced below)
        x = X[i, j]
        s = S[i, j]
        if plain:  # S already carries alpha where eq 14b applies
            v = (T[j] - x) * s + T[j]
        elif on == DISPLACEMENT:  # x + alpha (1 + S)(T - x)
            v = x + (T[j] - x) * ((s + 1.0) * alpha[i, j])
        else:  # position: alpha (T + S (T - x))
            v = ((T[j] - x) * s + T[j]) * alpha[i, j]
        out[k, j] = v
    if hunters[i]:
        anchor(X, kbest, P, mu, dist2)
        scaled = ihpo and branches != PREY_ONLY
        for j in range(d):
            z = CZ[i, j] / C
            x = X[i, j]
            a = alpha[i, j]
            o = centre[j]
            if scaled and on == LITERAL:  # eq 14a as printed: alpha scales the prey position
                if hunter == 1:
                    target = a * (C * (P[j] - o)) + (1.0 - C) * (mu[j] - o) + o
                else:
                    target = a * (C * P[j]) + (1.0 - C) * mu[j]
            else:
                target = C * P[j] + (1.0 - C) * mu[j]
            h = hunter_move(hunter, z, x, target, o)
            if scaled and on == POSITION:
                h = a * h
            elif scaled and (on == STEP or on == DISPLACEMENT):
                h = x + a * (h - x)
            out[k, j] = h
    for j in range(d):
        out[k, j] = min(max(out[k, j], lower[j]), upper[j])


@njit(cache=True)
def run(rng, objective, shifted, shift, lower, upper, agents, iterations, params):
    """One HPO or IHPO run (the package's kernel signature)."""
    N, d, T = agents, lower.size, iterations
    sequential = params[9] == 1.0
    stream = open_stream(rng, 3 * N * d + 3 * N, False)
    work = work_for(N, d)
    everyone = np.ones(N, dtype=np.bool_)
    centre = 0.5 * (lower + upper)
    X = np.empty((N, d))
    o = take(stream, RANDOM, N * d)
    buf = stream[1][RANDOM]
    for i in range(N):
        for j in range(d):
            X[i, j] = lower[j] + (upper[j] - lower[j]) * buf[o + i * d + j]
    F = np.empty(N)
    best = np.full(1, np.inf)
    best_x = np.zeros(d)
    curve = np.empty(T)
    evaluate(stream, objective, shifted, shift, lower, upper, X, F, everyone, work)
    record_first_min(F, X, N, best, best_x)
    CZ = np.empty((N, d))
    S = np.empty((N, d))
    alpha = np.empty((N, d))
    hunters = np.empty(N, dtype=np.bool_)
    call = np.empty(5, dtype=np.int64)
    P = np.empty(d)
    mu = np.empty(d)
    dist2 = np.empty(N)
    B = np.empty((N, d))  # the moved agents (one row at a time when sequential)
    start = np.empty(d)
    for t in range(1, T + 1):
        C = 1.0 - t * (0.98 / T)
        kbest = max(1, matlab_round(N * C))
        draw_terms(stream, N, d, C, t, T, params, CZ, S, alpha, hunters, call)
        for j in range(d):
            start[j] = best_x[j]
        for i in range(N):
            if sequential:  # the authors' sweep: moved, clipped and evaluated in turn
                move(X, i, C, kbest, params, CZ, S, alpha, hunters, best_x, lower, upper,
                     centre, P, mu, dist2, B, 0)
                for j in range(d):
                    X[i, j] = B[0, j]
                evaluate_rows(stream, objective, shifted, shift, lower, upper, X, i, i + 1, F,
                              everyone, work)
                if F[i] < best[0]:
                    best[0] = F[i]
                    for j in range(d):
                        best_x[j] = X[i, j]
            else:
                move(X, i, C, kbest, params, CZ, S, alpha, hunters, start, lower, upper,
                     centre, P, mu, dist2, B, i)
        if not sequential:
            for i in range(N):
                for j in range(d):
                    X[i, j] = B[i, j]
            evaluate(stream, objective, shifted, shift, lower, upper, X, F, everyone, work)
            record_first_min(F, X, N, best, best_x)
        curve[t - 1] = best[0]
    return best[0], best_x, curve, N * (T + 1)


for _name in ("HPO", "IHPO"):
    register_kernel(Kernel(_name, run, _packer(_name)))
