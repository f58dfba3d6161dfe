"""COOT bird optimizer, following the authors' equations and the semantics of their code.

Naruei & Keynia, "A new optimization method based on COOT bird natural life model", Expert Systems
with Applications 183 (2021) 115352, doi 10.1016/j.eswa.2021.115352. Equation numbers below are
those of its restatement as eqs 11-19 in Abdulsaheb & Kadhim, IJIES 15(5) 2022 (seed 000, whose
Table 2 has a COOT column).
Where the equations leave a point open we follow the authors' COOT.m (File Exchange 89102);
docs/algorithms.md lists every decision and its measured effect.

Population: N_L = ceil(0.1 N) leaders (parameter ``leaders`` overrides) and N_c = N - N_L coots.
Per iteration t = 1..T:

1. Coots move one by one (i = 1..N_c, in place), leader k = 1 + (i mod N_L) (eq 16, MATLAB
   1-based i). With probability 1/2 the coot follows its leader (eq 17):
   CP_i = LP_k + 2 R1 cos(2 pi R) (LP_k - CP_i); otherwise with probability 1/2 (and i > 1) the
   chain movement (eq 15) CP_i = (CP_{i-1} + CP_i) / 2 with the *already moved* CP_{i-1};
   otherwise the random movement (eqs 12-13) CP_i = CP_i + A R2 (Q - CP_i), Q ~ U(lb, ub).
   R ~ U(-1, 1), R1, R2 ~ U(0, 1). As in COOT.m, R and R1 are one scalar per coot with
   probability 1/2 and per-component vectors otherwise (``randoms``). COOT.m reuses R1 as R2;
   as R1 is fresh for every coot and iteration and only one branch uses it, that is the same
   as an independent R2 drawn by the same scalar-or-vector rule, which is what we draw (each
   coot draws two scalars and two vectors: (R, R1) when following, (R2, Q) when moving at
   random). The in-place sweep is reproduced exactly, without a loop over agents, by
   ``ops.linear_chain`` (chain: y_i = y_{i-1}/2 + CP_i/2; other moves: y_i = their clipped move).
2. All coots are evaluated. Sweeping coots in order, a coot better than its leader k (strictly)
   swaps position and fitness with it (COOT.m); replayed exactly with running minima per leader.
3. Leaders (eq 18): Temp = B R3 cos(2 pi R) (gBest - LP_j) + gBest if R4 < 0.5, and
   ... - gBest otherwise (the mirrored branch of paper and code; ``mirror = "plus"`` drops it).
   B = 2 - l/T (eq 19). Temp is clipped and evaluated; a Temp better than gBest (strictly)
   becomes gBest and its leader takes the old gBest's position and fitness; other leaders do not
   move (COOT.m; ``leader_update = "paper"``: every leader moves to its Temp, eq 18 as written).
   gBest is updated *only* here (``gbest = "any"`` also lets leaders that got a better point
   from a coot update it). Leaders are swept in order as in COOT.m, with one difference: every
   Temp of an iteration is built from the gBest at the start of the leader phase (Jacobi); the
   acceptance sweep and the hand-over of the old gBest are replayed exactly. The measured effect
   of building each Temp from the updated gBest instead is nil within noise (docs).

Schedules: COOT.m runs l = 2..Max_iter with A = 1 - l/Max_iter, B = 2 - l/Max_iter, i.e. Max_iter
- 1 moves. ``counter = "code"`` (default) maps our step t to l = t + 1 with Max_iter = T + 1, so
our T steps are exactly the T moves of COOT.m called with Max_iter = T + 1 (A ends at 0, B at 1);
``counter = "paper"`` uses l = t, Max_iter = T (eq 14 with L = 1..T).

Bounds: every moved point is clipped to the box before it is evaluated (COOT.m does the same).
Evaluations: N at initialization, then N_c coots + N_L leader proposals = N per iteration, all
through ``evaluate``: N (T + 1) in all (COOT.m with Max_iter = T + 1 also makes N (T + 1)).
The reported best is the best point ever evaluated, which can be better than COOT's own gBest.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.ops import linear_chain
from swarmpath.optimizers.registry import register

TWO_PI = 2.0 * math.pi


def cos_angle(u: Array) -> Array:
    """cos(2 pi R) for R = 2u - 1 ~ U(-1, 1), as a new array.

    cos(2 pi R) = cos(2 pi v) with v = 2u - round(2u) in [-1/2, 1/2] (period 1), and
    cos(2 pi v) = sin(2 pi (1/4 - |v|)) with an argument in [-pi/2, pi/2]: the same values up to
    rounding, computed faster (float64 libm cos on large arguments dominates an iteration).
    """
    v = np.multiply(u, 2.0)
    v -= np.rint(v)
    np.abs(v, out=v)
    np.subtract(0.25, v, out=v)
    v *= TWO_PI
    return np.sin(v, out=v)


def record_holders(vals: Array) -> NDArray[np.int64]:
    """Strict-< record sweep along the last axis.

    Position 0 is the incumbent; position j > 0 takes the record if vals[j] is strictly below the
    record before it. Returns, for every position, the index of the record holder after it.
    """
    n = vals.shape[-1]
    run = np.minimum.accumulate(vals, axis=-1)
    new = np.empty(vals.shape, dtype=bool)
    new[..., 0] = True
    np.less(vals[..., 1:], run[..., :-1], out=new[..., 1:])
    idx = np.where(new, np.arange(n), 0)
    return np.maximum.accumulate(idx, axis=-1)


def chain_sweep(moved: Array, old: Array, chain: NDArray[np.bool_]) -> Array:
    """The in-place coot sweep of COOT.m, vectorized with ``ops.linear_chain``.

    Coot i ends at ``moved[:, i]`` unless ``chain[:, i]``, in which case it ends at
    (y_{i-1} + old_i) / 2, y_{i-1} being where coot i - 1 ended (already moved): the affine
    recursion y_i = a_i y_{i-1} + b_i with a_i = 1/2, b_i = old_i / 2 for chaining coots and
    a_i = 0, b_i = moved_i for the others. ``moved`` is used as scratch space.
    """
    r, j = np.nonzero(chain)
    moved[r, j] = 0.5 * old[r, j]
    return linear_chain(np.where(chain, 0.5, 0.0), moved)


@register
class COOT(Optimizer):
    name = "COOT"
    summary = "COOT bird optimizer (Naruei & Keynia 2021), authors' code semantics"
    reference = (
        "Naruei & Keynia, Expert Syst. Appl. 183 (2021) 115352, as restated in "
        "Abdulsaheb & Kadhim, IJIES 15(5) 2022, eqs 11-19"
    )
    defaults: ClassVar[dict[str, Any]] = {
        "leaders": 0,
        "leader_fraction": 0.1,
        "randoms": "mixed",
        "gbest": "leader_phase",
        "mirror": "minus",
        "leader_update": "code",
        "counter": "code",
    }
    choices: ClassVar[dict[str, tuple[str, ...]]] = {
        "randoms": ("mixed", "vector", "scalar"),
        "gbest": ("leader_phase", "any"),
        "mirror": ("minus", "plus"),
        "leader_update": ("code", "paper"),
        "counter": ("code", "paper"),
    }
    min_agents = 2

    @classmethod
    def check_params(cls, p: Mapping[str, ParamValue]) -> None:
        if int(p["leaders"]) < 0:
            raise ParameterError(f"{cls.name}.leaders must be >= 0 (0: ceil(leader_fraction N))")
        if not 0.0 < float(p["leader_fraction"]) < 1.0:
            raise ParameterError(f"{cls.name}.leader_fraction must be in (0, 1)")

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        nl = int(self.p["leaders"]) or math.ceil(float(self.p["leader_fraction"]) * self.N)
        if not 1 <= nl < self.N:
            raise ParameterError(
                f"{self.name}.leaders must leave at least one coot: got {nl} of {self.N} agents"
            )
        self.NL = nl
        self.Nc = self.N - nl
        coots = np.arange(self.Nc)
        self.leader_of = (coots + 1) % nl  # eq 16 with MATLAB's 1-based coot index
        # coots of each leader, in sweep order, padded with -1: (N_L, M)
        m = max(int(np.sum(self.leader_of == k)) for k in range(nl))
        groups = np.full((nl, m), -1, dtype=np.int64)
        for k in range(nl):
            members = coots[self.leader_of == k]
            groups[k, : members.size] = members
        # sweep table over [coots, leaders, +inf pad]: (N_L, M + 1), column 0 the leader itself
        index = np.concatenate([self.Nc + np.arange(nl)[:, None], groups], axis=1)
        index[index < 0] = self.N
        self._sweep_index = index
        self._sweep_flat = index.ravel()
        self._sweep_offset = (np.arange(nl) * (m + 1))[:, None]
        self._own = np.arange(1, m + 1)
        self._leader_rank = np.arange(1, nl + 1)
        self.span = self.ub - self.lb  # (R, 1, d)
        # bounds spelled out for the coots: contiguous operands take numpy's fast path
        shape = (self.R, self.Nc, self.d)
        self._lb_coots = np.ascontiguousarray(np.broadcast_to(self.lb, shape))
        self._ub_coots = np.ascontiguousarray(np.broadcast_to(self.ub, shape))
        self._layout = self._draw_layout()
        self._width = sum(math.prod(shape) for _, shape in self._layout)

    # ------------------------------------------------------------------------------- randomness
    def _draw_layout(self) -> list[tuple[str, tuple[int, ...]]]:
        """Names and per-run shapes of every uniform drawn in one iteration (fixed shapes)."""
        nc, nl, d = self.Nc, self.NL, self.d
        layout = [
            ("c_flag", (nc,)),
            ("c_follow", (nc,)),
            ("c_chain", (nc,)),
            ("c_S1", (nc,)),
            ("c_S2", (nc,)),
            ("c_V1", (nc, d)),
            ("c_V2", (nc, d)),
            ("l_flag", (nl,)),
            ("l_sign", (nl,)),
            ("l_S1", (nl,)),
            ("l_S2", (nl,)),
            ("l_V1", (nl, d)),
            ("l_V2", (nl, d)),
        ]
        return layout + self._extra_layout()

    def _extra_layout(self) -> list[tuple[str, tuple[int, ...]]]:
        """Further per-iteration uniforms of a subclass."""
        return []

    def _draw(self) -> dict[str, Array]:
        """All uniforms of an iteration in one rng call, as named views shaped (R, *shape)."""
        U = self.rng.random(self._width)
        out: dict[str, Array] = {}
        start = 0
        for name, shape in self._layout:
            size = math.prod(shape)
            out[name] = U[:, start : start + size].reshape(self.R, *shape)
            start += size
        return out

    # ---------------------------------------------------------------------------------- hooks
    def _prepare(self, u: dict[str, Array]) -> None:
        """Called at the start of every iteration (ICOOT computes its acceleration here)."""

    def _acc(self, group: str) -> Array | None:
        """Per-agent factor (R, m) on the moves of group "c" (coots) or "l" (leaders); None = 1."""
        return None

    def _leader_gain(self) -> float:
        return 1.0

    def _random_target(self, Q: Array, X: Array, runs: NDArray[np.int64]) -> Array:
        """The point the random movement heads for (eq 13: Q itself), for the moving coots only.

        Q and X are (n, d) rows of the coots making a random move, ``runs`` their run indices.
        May work in Q's buffer.
        """
        return Q

    def _after_coot_evaluation(self, u: dict[str, Array]) -> None:
        """Called after the coots were moved and evaluated, before the leader swap."""

    # ------------------------------------------------------------------------------ algorithm
    def _initialize(self) -> None:
        X = self.random_population()  # coots first, then leaders, as COOT.m draws them
        self._adopt(X, self.evaluate(X))

    def _adopt(self, X: Array, F: Array) -> None:
        """Split an evaluated population into coots and leaders; gBest = first best (COOT.m)."""
        nc = self.Nc
        self.CP, self.CF = X[:, :nc].copy(), F[:, :nc].copy()
        self.LP, self.LF = X[:, nc:].copy(), F[:, nc:].copy()
        rows = np.arange(self.R)
        idx = np.argmin(F, axis=1)
        self.g = X[rows, idx].copy()
        self.gf = F[rows, idx].copy()

    def schedule(self, t: int | None = None) -> tuple[float, float]:
        """(A, B) of eqs 14 and 19 for iteration t (default: the current one)."""
        t = self.t if t is None else t
        if self.p["counter"] == "code":
            l, T = t + 1, self.T + 1
        else:
            l, T = t, self.T
        return 1.0 - l * (1.0 / T), 2.0 - l * (1.0 / T)

    def _iterate(self) -> None:
        A, B = self.schedule()
        u = self._draw()
        self._prepare(u)
        self._move_coots(A, u)
        self.CF = self.evaluate(self.CP)
        self._after_coot_evaluation(u)
        self._swap_with_leaders()
        if self.p["gbest"] == "any":
            self._leaders_update_gbest()
        self._move_leaders(B, u)

    def _vector_rows(self, flag: Array) -> NDArray[np.bool_]:
        """Agents whose R and R1 (R3) are per-component vectors; the others use one scalar each."""
        mode = self.p["randoms"]
        if mode == "mixed":
            return flag >= 0.5  # COOT.m: ``if rand < 0.5`` -> scalars
        return np.full(flag.shape, mode == "vector")

    def _move_coots(self, A: float, u: dict[str, Array]) -> None:
        """Eqs 12-17 for every coot, as COOT.m's in-place sweep (see the module docstring)."""
        X = self.CP
        R, nc, d = X.shape
        follow = u["c_follow"] < 0.5
        chain = (~follow) & (u["c_chain"] < 0.5)
        chain[:, 0] = False  # COOT.m: the first coot cannot chain; it moves at random instead
        rand = ~(follow | chain)
        vec = self._vector_rows(u["c_flag"])
        S1, S2, V1, V2 = u["c_S1"], u["c_S2"], u["c_V1"], u["c_V2"]
        acc = self._acc("c")
        fa = 2.0 * acc if acc is not None else np.full((R, nc), 2.0)
        ra = A * acc if acc is not None else np.full((R, nc), A)
        # y = X + W (T - X). Follow (eq 17): T = LP_k, W = 1 + 2 acc R1 cos(2 pi R), since
        # LP + w (LP - X) = X + (1 + w)(LP - X); R, R1 = V1, V2 (or S1, S2). Random (eq 13):
        # T = Q = lb + V2 (ub - lb), W = A acc R2 with R2 = V1 (or S1). Chain rows: see below.
        # Rows are handled compactly: cos is the most expensive operation of an iteration.
        W = np.zeros((R, nc, d))
        rows = follow & vec
        w = cos_angle(V1[rows])
        w *= V2[rows]
        w *= fa[rows][:, None]
        w += 1.0
        W[rows] = w
        rows = follow & ~vec
        W[rows] = (1.0 + fa * cos_angle(S1) * S2)[rows][:, None]
        rows = rand & vec
        W[rows] = V1[rows] * ra[rows][:, None]
        rows = rand & ~vec
        W[rows] = (ra * S1)[rows][:, None]
        T = X.copy()
        rf, jf = np.nonzero(follow)
        T[rf, jf] = self.LP[rf, self.leader_of[jf]]
        rr, jr = np.nonzero(rand)
        Q = V2[rr, jr]
        Q *= self.span[rr, 0]
        Q += self.lb[rr, 0]  # eq 12
        T[rr, jr] = self._random_target(Q, X[rr, jr], rr)
        T -= X
        T *= W
        T += X
        self._clip_inplace(T)
        Y = chain_sweep(T, X, chain)  # eq 15 with the already moved predecessor
        self._clip_inplace(Y)  # a mean of in-box points: guards rounding only
        self.CP = Y

    def _clip_inplace(self, X: Array) -> None:
        if X.shape == self._ub_coots.shape:
            np.minimum(X, self._ub_coots, out=X)
            np.maximum(X, self._lb_coots, out=X)
        else:
            np.minimum(X, self.ub, out=X)
            np.maximum(X, self.lb, out=X)

    def _swap_with_leaders(self) -> None:
        """COOT.m's sweep: coot i swaps with leader k when strictly better, in coot order.

        Per leader, the sequence (leader, its coots in order) is a strict-< record sweep: a coot
        that takes the record becomes the leader and receives the record it beat (the previous
        holder, an original position); the leader ends as the final holder. Only the agents
        that change are gathered and written.
        """
        R, nl = self.R, self.NL
        allF = np.concatenate([self.CF, self.LF, np.full((R, 1), np.inf)], axis=1)
        vals = allF[:, self._sweep_index]  # (R, N_L, M + 1)
        holder = record_holders(vals)
        gh = self._sweep_flat[holder + self._sweep_offset]  # global index of each holder
        r, k, j = np.nonzero(holder[..., 1:] == self._own)  # coots that took the record
        coots = self._sweep_index[k, j + 1]
        beaten = gh[r, k, j]  # the record each of them beat (held before it)
        last = gh[..., -1]  # (R, N_L): the final holders, the new leaders
        lr = np.repeat(np.arange(R), nl)
        coot_pos, coot_fit = self._agents(r, beaten), allF[r, beaten]
        lead_pos, lead_fit = self._agents(lr, last.ravel()), allF[lr, last.ravel()]
        self.CP[r, coots] = coot_pos
        self.CF[r, coots] = coot_fit
        self.LP = lead_pos.reshape(R, nl, self.d)
        self.LF = lead_fit.reshape(R, nl)

    def _agents(self, runs: NDArray[np.int64], index: NDArray[np.int64]) -> Array:
        """Positions of agents given by index into [coots, leaders], one per run in ``runs``."""
        out = np.empty((runs.size, self.d))
        coot = index < self.Nc
        out[coot] = self.CP[runs[coot], index[coot]]
        out[~coot] = self.LP[runs[~coot], index[~coot] - self.Nc]
        return out

    def _leaders_update_gbest(self) -> None:
        rows = np.arange(self.R)
        idx = np.argmin(self.LF, axis=1)
        better = self.LF[rows, idx] < self.gf
        self.gf = np.where(better, self.LF[rows, idx], self.gf)
        self.g = np.where(better[:, None], self.LP[rows, idx], self.g)

    def _move_leaders(self, B: float, u: dict[str, Array]) -> None:
        """Eq 18 for every leader, then COOT.m's acceptance sweep against gBest."""
        vec = self._vector_rows(u["l_flag"])[..., None]
        S = cos_angle(np.where(vec, u["l_V1"], u["l_S1"][..., None]))  # cos(2 pi R)
        S *= np.where(vec, u["l_V2"], u["l_S2"][..., None])  # R3
        gain = B * self._leader_gain()
        acc = self._acc("l")
        S *= (gain * acc)[..., None] if acc is not None else gain
        g = self.g[:, None, :]
        temp = g - self.LP
        temp *= S
        if self.p["mirror"] == "minus":  # R4 < 0.5: + gBest, otherwise - gBest
            temp += np.where(u["l_sign"] < 0.5, 1.0, -1.0)[..., None] * g
        else:
            temp += g
        self._clip_inplace(temp)
        TF = self.evaluate(temp)
        # a proposal better than gBest (strictly) becomes gBest; its leader gets the old gBest
        vals = np.concatenate([self.gf[:, None], TF], axis=1)  # (R, N_L + 1)
        pool = np.concatenate([g, temp], axis=1)
        holder = record_holders(vals)
        rows = np.arange(self.R)[:, None]
        if self.p["leader_update"] == "code":
            took = holder[:, 1:] == self._leader_rank
            before = holder[:, :-1]
            self.LP = np.where(took[..., None], pool[rows, before], self.LP)
            self.LF = np.where(took, vals[rows, before], self.LF)
        else:  # eq 18 as written: every leader moves to its proposal
            self.LP, self.LF = temp, TF
        last = holder[:, -1:]
        self.g = pool[rows, last][:, 0]
        self.gf = vals[rows, last][:, 0]
