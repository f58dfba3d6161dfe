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
   random). The in-place sweep is reproduced exactly, with COOT.m's arithmetic and without a
   loop over agents, by ``chain_sweep``: every coot first makes its own (clipped) move, then the
   chaining coots are replaced by (y_{i-1} + CP_i) / 2, level by level of chain depth.
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

from swarmpath.functions.trig import cospi
from swarmpath.optimizers.base import Array, Optimizer, ParameterError, ParamValue
from swarmpath.optimizers.registry import register


def cos_angle(u: Array) -> Array:
    """cos(2 pi R) for R = 2u - 1 ~ U(-1, 1), as a new array.

    cos(2 pi (2u - 1)) = cos(4 pi u) = ``cospi(4u)`` (4u is exact): whole-array arithmetic, the
    same values as the C library's cos up to the last bit or two, several times faster
    (``swarmpath.functions.trig``); the cosine is the most expensive operation of an iteration.
    """
    return cospi(np.multiply(u, 4.0))


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


def chain_sweep(Y: Array, old: Array, chain: NDArray[np.bool_]) -> Array:
    """The in-place coot sweep of COOT.m for the chaining coots, in place on ``Y`` (R, n, d).

    Coot i ends at ``Y[:, i]`` unless ``chain[:, i]``, in which case it ends at
    (y_{i-1} + old_i) / 2 (eq 15, COOT.m's arithmetic), y_{i-1} being where coot i - 1 ended
    (already moved). Coot 0 never chains. Chaining coots are processed by depth, the number of
    chaining coots in a row ending at them: all depth-1 coots at once (their predecessor is
    final), then depth 2, and so on. A coot chains with probability 1/4, so the loop is short
    (depth <= 8 in practice even for 1000 runs) and touches only the chaining coots: no loop
    over agents, no whole-array scan. A mean of two in-box points is in the box (rounding is
    monotone), so no clipping is needed.
    """
    R, n, d = Y.shape
    flat = np.flatnonzero(chain)  # r * n + i
    if flat.size == 0:
        return Y
    count = np.cumsum(chain, axis=1)
    depth: np.ndarray = count - np.maximum.accumulate(np.where(chain, 0, count), axis=1)
    level: np.ndarray = depth.ravel()[flat]
    rows = Y.view()
    rows.shape = (R * n, d)  # a view (raises if Y is not contiguous)
    before = old.reshape(R * n, d)
    for k in range(1, int(level.max()) + 1):
        idx = flat[level == k]
        mean = rows[idx - 1]
        mean += before[idx]
        mean *= 0.5
        rows[idx] = mean
    return Y


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
        self._lb_coots, self._ub_coots = self.full_bounds(self.Nc)
        self._layout = self._draw_layout()
        self._plan = self._draw_plan()
        lower, upper = self.full_bounds(self.Nc)
        self._span_coots = upper - lower  # (R, N_c, d)

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
        """All uniforms of an iteration, in layout order, as named (R, *shape) arrays.

        Consecutive draws from the per-run streams: the same numbers as one draw of the whole
        layout split into named parts, drawn in groups of equal shape (fewer calls). Per-agent
        scalars are views of their group (small arrays); every per-component part is a
        contiguous array of its own (strided views are slow operands in numpy).
        """
        out: dict[str, Array] = {}
        for names, shape in self._plan:
            if len(names) == 1:
                out[names[0]] = self.rng.random(*shape)
            elif len(shape) == 1:
                block = self.rng.random(len(names), *shape)
                for i, name in enumerate(names):
                    out[name] = block[:, i]
            else:
                out.update(zip(names, self.rng.random_parts(len(names), *shape), strict=True))
        return out

    def _draw_plan(self) -> list[tuple[tuple[str, ...], tuple[int, ...]]]:
        """The layout with consecutive parts of equal shape grouped into one draw."""
        plan: list[tuple[tuple[str, ...], tuple[int, ...]]] = []
        for name, shape in self._layout:
            if plan and plan[-1][1] == shape:
                plan[-1] = ((*plan[-1][0], name), shape)
            else:
                plan.append(((name,), shape))
        return plan

    def _cosines(self, u: dict[str, Array]) -> None:
        """Every cos(2 pi R) of the iteration in one ``cospi`` call (fewer numpy calls).

        Coots: one per coot from its scalar R (used by scalar rows), one per component for the
        rows that follow their leader with vector randoms (computed compactly); leaders: one per
        component of R (a scalar repeated for scalar rows).
        """
        self._cosines_of = u
        self._follow = u["c_follow"] < 0.5
        self._vec = self._vector_rows(u["c_flag"])
        self._rows_fv = np.nonzero(self._follow & self._vec)
        vec_l = self._vector_rows(u["l_flag"])[..., None]
        angles = np.concatenate(
            (
                u["c_S1"].ravel(),
                u["c_V1"][self._rows_fv].ravel(),
                np.where(vec_l, u["l_V1"], u["l_S1"][..., None]).ravel(),
            )
        )
        cos = cos_angle(angles)
        a = self.R * self.Nc
        b = a + self._rows_fv[0].size * self.d
        self._cos_scalar = cos[:a].reshape(self.R, self.Nc)
        self._cos_rows = cos[a:b].reshape(-1, self.d)
        self._cos_leaders = cos[b:].reshape(self.R, self.NL, self.d)

    # ---------------------------------------------------------------------------------- hooks
    def _prepare(self, u: dict[str, Array]) -> None:
        """Called at the start of every iteration (ICOOT computes its acceleration here)."""

    def _acc(self, group: str) -> Array | None:
        """Per-agent factor (R, m) on the moves of group "c" (coots) or "l" (leaders); None = 1."""
        return None

    def _leader_gain(self) -> float:
        return 1.0

    def _random_target(self, Q: Array, X: Array) -> Array:
        """The point the random movement heads for (eq 13: Q itself).

        Q and X are (R, N_c, d), computed for every coot (only those moving at random use it).
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
        self._cosines(u)
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
        if getattr(self, "_cosines_of", None) is not u:  # called alone (tests)
            self._cosines(u)
        follow, vec = self._follow, self._vec
        chain = (~follow) & (u["c_chain"] < 0.5)
        chain[:, 0] = False  # COOT.m: the first coot cannot chain; it moves at random instead
        S1, S2, V1, V2 = u["c_S1"], u["c_S2"], u["c_V1"], u["c_V2"]
        acc = self._acc("c")
        fa: Array | float = 2.0 * acc if acc is not None else 2.0
        ra: Array | float = A * acc if acc is not None else A
        # y = X + W (T - X). Follow (eq 17): T = LP_k, W = 1 + 2 acc R1 cos(2 pi R), since
        # LP + w (LP - X) = X + (1 + w)(LP - X); R, R1 = V1, V2 (or S1, S2). Random (eq 13):
        # T = Q = lb + V2 (ub - lb), W = A acc R2 with R2 = V1 (or S1). Chain rows: see below
        # (their W and T are computed and discarded). W per coot first, for the scalar rows:
        w = self._cos_scalar.copy()
        w *= S2
        w *= fa
        w += 1.0
        np.multiply(S1, ra, out=w, where=~follow)
        # then the vector rows: A acc V1 (random), and the follow rows compactly (cos is costly)
        W = np.multiply(V1, ra[..., None] if isinstance(ra, np.ndarray) else ra)
        rows = np.nonzero(~vec)
        W[rows] = w[rows][:, None]
        rows = self._rows_fv
        c = self._cos_rows
        c *= V2[rows]
        c *= fa[rows][:, None] if isinstance(fa, np.ndarray) else fa
        c += 1.0
        W[rows] = c
        Q = np.multiply(V2, self._span_coots)
        Q += self._lb_coots  # eq 12, for every coot
        T = self._random_target(Q, X)
        rows = np.nonzero(follow)
        T[rows] = self.LP[rows[0], self.leader_of[rows[1]]]
        T -= X
        T *= W
        T += X
        self._clip_inplace(T)
        self.CP = chain_sweep(T, X, chain)  # eq 15 with the already moved predecessor

    def _clip_inplace(self, X: Array) -> None:
        self.clip_inplace(X)

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
        if getattr(self, "_cosines_of", None) is not u:  # called alone (tests)
            self._cosines(u)
        vec = self._vector_rows(u["l_flag"])[..., None]
        S = self._cos_leaders  # cos(2 pi R)
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
