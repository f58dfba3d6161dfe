"""The Friedman test over blocks (functions or maps) with its post-hoc procedures: mean ranks,
Nemenyi's critical difference and Holm-adjusted z tests against the reference (Demsar, JMLR 7
(2006) 1-30; Derrac et al., Swarm Evol. Comput. 1 (2011) 3-18). See :mod:`.compare` for the
edge cases; pure numpy/scipy, no I/O."""

from __future__ import annotations

import math
from collections.abc import Hashable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

# scipy.stats (about 1 s to import) is imported by the functions that test: a coordinator
# imports this module at its start, for summaries it computes only when asked.
from swarmpath.evidence.markers import ALPHA, BETTER, SAME, WORSE, holm
from swarmpath.evidence.stats import resolve_reference

__all__ = ["Friedman", "cliques", "friedman", "nemenyi_cd"]

#: A block key: (function, dim), a map name, ...
K = TypeVar("K", bound=Hashable)


def nemenyi_cd(k: int, n: int, alpha: float = ALPHA) -> float:
    """Nemenyi's critical difference of mean ranks for k algorithms over n blocks."""
    from scipy import stats
    if k < 2 or n < 1:
        raise ValueError("the critical difference needs k >= 2 algorithms and n >= 1 blocks")
    q = float(stats.studentized_range.ppf(1.0 - alpha, k, np.inf)) / math.sqrt(2.0)
    return q * math.sqrt(k * (k + 1) / (6.0 * n))


@dataclass(frozen=True)
class Friedman:
    """The Friedman test over blocks (functions or maps) with its post-hoc procedures."""

    algorithms: tuple[str, ...]
    reference: str
    alpha: float
    blocks: tuple[Hashable, ...]  # the complete blocks used
    mean_ranks: dict[str, float]  # 1 = best
    statistic: float | None
    p: float | None
    cd: float | None  # Nemenyi critical difference (None with fewer than 2 algorithms)
    posthoc: dict[str, dict[str, Any]]  # algorithm -> z, p, p_holm, marker (vs the reference)
    note: str = ""

    @classmethod
    def from_json(cls, doc: Mapping[str, Any]) -> Friedman:
        """The test back from :meth:`to_json` (``blocks`` comes back as that many indexes;
        non-finite numbers may be the strings "nan", "inf")."""

        def num(v: Any) -> float | None:
            return None if v is None else float(v)

        ranks = {str(a): float(r) for a, r in doc["mean_ranks"].items()}
        return cls(
            tuple(ranks), str(doc["reference"]), float(doc["alpha"]),
            tuple(range(int(doc["blocks"]))), ranks, num(doc["statistic"]), num(doc["p"]),
            num(doc["nemenyi_cd"]), {a: dict(v) for a, v in doc["posthoc"].items()},
            str(doc.get("note", "")),
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "test": "friedman", "reference": self.reference, "alpha": self.alpha,
            "blocks": len(self.blocks), "mean_ranks": dict(self.mean_ranks),
            "statistic": self.statistic, "p": self.p, "nemenyi_cd": self.cd,
            "posthoc": {a: dict(v) for a, v in self.posthoc.items()}, "note": self.note,
        }


def friedman(
    values: Mapping[K, Mapping[str, float]],
    algorithms: Sequence[str],
    reference: str | None = None,
    alpha: float = ALPHA,
    lower_is_better: bool = True,
) -> Friedman:
    """Friedman test of ``algorithms`` over the blocks of ``values`` (block -> algorithm -> one
    value, e.g. the average best fitness of a function), with mean ranks and post-hoc tests."""
    from scipy import stats
    algos = tuple(algorithms)
    ref = resolve_reference(algos, reference) if algos else ""
    k = len(algos)
    blocks, rows = [], []
    for key, per_algo in values.items():
        row = [per_algo.get(a, math.nan) for a in algos]
        if k and not any(v is None or math.isnan(float(v)) for v in row):
            blocks.append(key)
            rows.append([float(v) for v in row])
    n = len(blocks)
    if k == 0 or n == 0:
        return Friedman(algos, ref, alpha, tuple(blocks), dict.fromkeys(algos, math.nan), None,
                        None, None, {}, "no complete block")
    table = np.array(rows) if lower_is_better else -np.array(rows)
    ranks = stats.rankdata(table, axis=1)  # ties share the average rank
    mean = ranks.mean(axis=0)
    mean_ranks = {a: float(r) for a, r in zip(algos, mean, strict=True)}
    statistic = p = None
    note = ""
    if k < 3:
        note = "the Friedman test needs at least 3 algorithms"
    elif n < 2:
        note = "the Friedman test needs at least 2 blocks"
    elif np.all(ranks == ranks[:, :1]):
        statistic, p, note = 0.0, 1.0, "every block is a complete tie"
    else:
        res = stats.friedmanchisquare(*table.T)
        statistic, p = float(res.statistic), float(res.pvalue)
    cd = nemenyi_cd(k, n, alpha) if k >= 2 else None
    posthoc: dict[str, dict[str, Any]] = {}
    if k >= 2:
        se = math.sqrt(k * (k + 1) / (6.0 * n))
        others = [a for a in algos if a != ref]
        z = [(mean_ranks[a] - mean_ranks[ref]) / se for a in others]
        raw = [float(2.0 * stats.norm.sf(abs(v))) for v in z]
        adjusted = holm(raw)
        for a, zi, pi, qi in zip(others, z, raw, adjusted, strict=True):
            marker = SAME if qi >= alpha else (BETTER if zi < 0 else WORSE)
            posthoc[a] = {"z": zi, "p": pi, "p_holm": float(qi), "marker": marker}
    return Friedman(algos, ref, alpha, tuple(blocks), mean_ranks, statistic, p, cd, posthoc, note)


def cliques(mean_ranks: Mapping[str, float], cd: float) -> list[tuple[str, ...]]:
    """Maximal groups of algorithms whose mean ranks all lie within ``cd`` of each other (the
    bars of a critical-difference diagram), ordered by rank; single algorithms are left out."""
    order = sorted(mean_ranks, key=lambda a: mean_ranks[a])
    groups: list[tuple[str, ...]] = []
    for i, a in enumerate(order):
        group = tuple(b for b in order[i:] if mean_ranks[b] - mean_ranks[a] <= cd)
        if len(group) > 1 and not any(set(group) <= set(g) for g in groups):
            groups.append(group)
    return groups
