"""The bat move of ``BatSwarms._bat_move`` (eqs 11-13), shared by the MFB and HPSO-MFB optimizer
kernels (:mod:`.bats`) and the planners' compiled decision (``planners/compiled_bats.py``)."""

from __future__ import annotations

from numba import njit

from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT


@njit(cache=True, **NO_REFCOUNT)
def move_bats(X, V, S, Zb, freq, per_dim, u, o, r, amean, G, shared, kb, sigma, toward,
              span_walk, lower, upper):
    """Every bat's velocity (in ``V``) and candidate point (clipped, into ``S``) in place.

    X, V, S (Nb, d): positions, velocities, candidates; Zb (G, d): each sub-swarm's best (bat i
    in sub-swarm i mod G, led by sub-swarm ``kb`` when ``shared``); freq: the frequencies, one
    per bat or per bat and dimension (``per_dim``); u[o:]: the iteration's uniforms as the
    reference lays them out, eps (Nb, d) then the walk test (Nb); r: the pulse rates; amean (G,):
    each sub-swarm's mean loudness. eq 11: V +- (z* - x) f (``toward``: +); eq 12: x + V; eq 13
    where the walk test exceeds r: z* + sigma eps <A> (ub - lb when ``span_walk``), as
    ``eps * sc + (z* - sc / 2)`` with sc = 2 sigma <A> (times the span), the reference's
    arithmetic. The candidate is clipped to [lower, upper] as ``np.minimum(np.maximum(.))``."""
    Nb, d = X.shape
    e = d if per_dim else 1
    o_walk = o + Nb * d
    for i in range(Nb):
        z = kb if shared else i % G
        scale = (2.0 * sigma) * amean[i % G]
        walk = u[o_walk + i] > r[i]
        for j in range(d):
            D = (Zb[z, j] - X[i, j]) * freq[i * e + (j if per_dim else 0)]
            V[i, j] = V[i, j] + D if toward else V[i, j] - D
            s = X[i, j] + V[i, j]
            if walk:
                sc = scale * (upper[j] - lower[j]) if span_walk else scale
                s = u[o + i * d + j] * sc + (Zb[z, j] - 0.5 * sc)
            S[i, j] = min(max(s, lower[j]), upper[j])
