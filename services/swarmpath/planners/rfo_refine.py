"""Section 4.2 of the RFO family: the EA with the Erase mutation and the multiphase refinement.

Ketafa & Al-Darraji, Iraqi J. Science 65(2) (2024) 1070-1088, doi 10.24996/ijs.2024.65.2.38,
section 4.2. :class:`RfoRefine` is a base of :class:`~swarmpath.planners.rfo_gwo.RfoFamilyPlanner`,
whose plan calls it.

Phase B/C, section 4.2 (``RFO-GWO-EA`` only)
-------------------------------------------
Every path of the ``arrivals`` foxes is refined (side by side, independently) and the shortest
result is the plan. An EA with the Erase mutation as its only operator
(:meth:`RfoRefine._ea`: a population of ``ea_population`` copies of the path; Erase picks
two nodes V_i, V_j, j > i + 1, and if V_i V_j passes the safety rule removes the nodes between
them; (mu + lambda) selection on length, ``ea_generations`` = 50) runs on the path; then up to
``phases`` (4) rounds of the multiphase technique: cut every segment longer than the split length
into equal pieces, run the EA again, and (``node_opt = "gwo"``) optimise the nodes with GWO
(:meth:`RfoRefine._relax`: each interior node is a sub-problem, the point of a box around
it minimising the length of its two segments under the safety rule, odd and even nodes in turn,
``relax_sweeps`` = 2, box half-width ``relax_box`` = 0.5 times the longer adjacent segment; a node
moves only to a valid, shorter place). A path leaves the rounds once one shortens it by less than
``refine_tol`` (1e-4). Finally every node whose neighbours see each other under the safety rule is
erased (:meth:`RfoRefine._prune`). Erase and the node moves never lengthen a path and add
only checked segments; the split points lie on valid segments, so ``RFO-GWO-EA`` is never longer
than ``RFO-GWO`` with the same seed.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import NDArray

from swarmpath.optimizers import RunStreams
from swarmpath.planners.rfo_geometry import path_length
from swarmpath.planners.rfo_search import PENALTY, Array, RfoSearch
from swarmpath.world.geometry import collides


class RfoRefine(RfoSearch):
    """The refinement of the paths phase A found (:meth:`_refine`, :meth:`_prune`)."""

    _split_length: float


    # ------------------------------------------------ section 4.2: EA + multiphase
    def _refine(self, paths: list[Array]) -> list[Array]:
        """Section 4.2 on every path of ``paths`` (refined side by side, independently): the EA,
        then up to ``phases`` rounds of split, EA and (``node_opt = "gwo"``) the GWO optimisation
        of the path nodes (:meth:`_relax`). A path leaves the rounds once one shortens it by less
        than ``refine_tol`` (relative)."""
        paths = self._ea(paths)
        tol = float(self.p["refine_tol"])
        live = list(range(len(paths)))
        for _ in range(int(self.p["phases"])):
            if not live:
                break
            before = [path_length(paths[c]) for c in live]
            out = self._ea([self._split(paths[c], self._split_length) for c in live])
            if self.p["node_opt"] == "gwo":
                out = self._relax(out)
            for c, q in zip(live, out, strict=True):
                paths[c] = q
            live = [c for c, b in zip(live, before, strict=True)
                    if path_length(paths[c]) <= (1.0 - tol) * b]
        return paths

    def _relax(self, paths: list[Array]) -> list[Array]:
        """GWO optimisation of the path nodes: every interior node V_k is a sub-problem, the
        point x in a box around V_k that minimises |V_{k-1} x| + |x V_{k+1}| with both segments
        passing the safety rule (the neighbours fixed).

        Nodes of one parity do not share a segment, so the odd nodes of every path are optimised
        as one batch of independent GWO runs, then the even ones (``relax_sweeps`` times, fewer
        when a sweep moves nothing). The box of V_k has half-width ``relax_box`` times its longer
        adjacent segment (at most ``radius``), clipped to the world; a node moves only when the
        best wolf is valid and shortens the path, so no path gets longer and every new segment
        is checked.
        """
        paths = [q.copy() for q in paths]
        for _ in range(int(self.p["relax_sweeps"])):
            moved = False
            for first in (1, 2):
                ks = [np.arange(first, len(q) - 1, 2) for q in paths]
                if not sum(k.size for k in ks):
                    continue
                A = np.concatenate([q[k - 1] for q, k in zip(paths, ks, strict=True)])
                V = np.concatenate([q[k] for q, k in zip(paths, ks, strict=True)])
                B = np.concatenate([q[k + 1] for q, k in zip(paths, ks, strict=True)])
                best, better = self._gwo_nodes(A, V, B)
                at = 0
                for q, k in zip(paths, ks, strict=True):
                    sel = better[at:at + k.size]
                    q[k[sel]] = best[at:at + k.size][sel]
                    at += k.size
                moved |= bool(better.any())
            if not moved:
                break
        return paths

    def _gwo_nodes(self, A: Array, V: Array, B: Array) -> tuple[Array, NDArray[np.bool_]]:
        """One batch of node sub-problems (see :meth:`_relax`): the best point per node and
        whether it is valid and shortens the path by more than 1e-9 m."""
        K = V.shape[0]
        span = np.maximum(np.hypot(*(V - A).T), np.hypot(*(V - B).T))
        half = np.minimum(float(self.p["relax_box"]) * span, float(self.p["radius"]))
        lower = np.maximum(V - half[:, None], self._lo)
        upper = np.minimum(V + half[:, None], self._hi)
        # a node on the straight line between its neighbours is already optimal: skip it
        bend = np.hypot(*(V - A).T) + np.hypot(*(B - V).T) - np.hypot(*(B - A).T)
        live = np.all(upper - lower > 1e-9, axis=1) & (bend > 1e-9)
        out = V.copy()
        better = np.zeros(K, dtype=bool)
        if not live.any():
            return out, better
        A, V, B, lower, upper = A[live], V[live], B[live], lower[live], upper[live]
        m = int(self.p["wolves"])
        thr = self._thr_safe
        Am, Bm = np.repeat(A, m, axis=0), np.repeat(B, m, axis=0)

        def objective(X: Array, streams: RunStreams) -> Array:
            W = X.reshape(-1, 2)
            d = self._geo.segment(np.concatenate([Am, W]), np.concatenate([W, Bm]), thr)
            da, db = d[: len(W)], d[len(W):]
            length = np.hypot(*(W - Am).T) + np.hypot(*(Bm - W).T)
            valid = ~collides(da, thr) & ~collides(db, thr)
            viol = np.maximum(thr - da, 0.0) + np.maximum(thr - db, 0.0)
            return np.where(valid, length, PENALTY + viol).reshape(-1, m)

        opt = self._run_gwo(objective, lower, upper, m, int(live.sum()))
        now = np.hypot(*(V - A).T) + np.hypot(*(B - V).T)
        gain = opt.best_fitness < now - 1e-9
        idx = np.flatnonzero(live)[gain]
        out[idx] = opt.best_position[gain]
        better[idx] = True
        return out, better

    def _prune(self, path: Array) -> Array:
        """The nodes the path needs: in order, an interior node is erased when the segment from
        the last kept node to the next node passes the safety rule (the Erase mutation with
        j = i + 2, applied greedily; never longer). Also drops the repeated nodes that GWO can
        produce when a node lands on its neighbour."""
        keep = [0]
        for k in range(1, len(path) - 1):
            a, b = path[keep[-1]], path[k + 1]
            if not self._segments_ok(a[None, :], b[None, :])[0]:
                keep.append(k)
        keep.append(len(path) - 1)
        return path[keep]

    @staticmethod
    def _split(path: Array, length: float) -> Array:
        """Cut every segment longer than ``length`` into equal pieces (points on the segment)."""
        out = [path[:1]]
        for a, b in itertools.pairwise(path):
            n = max(1, math.ceil(math.dist(a, b) / length))
            s = np.arange(1, n + 1)[:, None] / n
            pts = a + s * (b - a)
            pts[-1] = b
            out.append(pts)
        return np.concatenate(out)

    def _ea(self, paths: list[Array]) -> list[Array]:
        """Evolutionary algorithm whose only variation is the Erase mutation (section 4.2), run
        on every path of ``paths`` side by side (independent populations, one random stream).

        Each population starts as ``ea_population`` copies of its reference path. Each
        generation every path V_0..V_n draws two node indices i <= j; if j > i + 1 and the
        segment V_i V_j passes the safety rule, its child erases V_{i+1}..V_{j-1} (never longer,
        by the triangle inequality, and valid: its only new segment was checked). Parents and
        children compete on length ((mu + lambda) selection, ties to fewer nodes, then to the
        older path). Returns the shortest path of each population.
        """
        C, P = len(paths), int(self.p["ea_population"])
        group = np.repeat(np.arange(C), P)
        pop = [q for q in paths for _ in range(P)]  # never modified in place: children are new
        cums = [c for q in paths for c in [_cumulative(q)] * P]
        lengths = np.array([c[-1] for c in cums])
        sizes = np.array([len(q) for q in pop])
        for _ in range(int(self.p["ea_generations"])):
            u = self.rng.random((C * P, 2))
            ij = np.minimum((u * sizes[:, None]).astype(np.intp), sizes[:, None] - 1)
            lo, hi = ij.min(axis=1), ij.max(axis=1)
            picks = np.flatnonzero(hi - lo >= 2)
            if not picks.size:
                continue
            A = np.array([pop[m][lo[m]] for m in picks])
            B = np.array([pop[m][hi[m]] for m in picks])
            ok = self._segments_ok(A, B)
            if not ok.any():
                continue
            picks, A, B = picks[ok], A[ok], B[ok]
            kids = [np.concatenate([pop[m][: lo[m] + 1], pop[m][hi[m]:]]) for m in picks]
            kid_lengths = lengths[picks] + np.hypot(*(B - A).T) - np.array(
                [cums[m][hi[m]] - cums[m][lo[m]] for m in picks])
            pool = pop + kids
            pool_group = np.concatenate([group, group[picks]])
            pool_lengths = np.concatenate([lengths, kid_lengths])
            pool_sizes = np.concatenate([sizes, [len(q) for q in kids]])
            order = np.lexsort((np.arange(len(pool)), pool_sizes, pool_lengths, pool_group))
            # each group has at least P members (its parents): keep the first P of each
            starts = np.searchsorted(pool_group[order], np.arange(C))
            keep = order[(starts[:, None] + np.arange(P)).ravel()]
            pop = [pool[k] for k in keep]
            cums = [cums[k] if k < len(cums) else _cumulative(pool[k]) for k in keep]
            lengths, sizes = pool_lengths[keep], pool_sizes[keep]
        return [pop[c * P] for c in range(C)]


def _cumulative(path: Array) -> Array:
    """Cumulative length along the path (first entry 0)."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
