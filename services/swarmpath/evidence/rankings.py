"""Rankings of every optimizer on a suite, from a ``swarmpath bench --json`` document.

Pure functions, no I/O. Per dimension of the study, each function-instance cell is one block of
the Friedman test (:func:`swarmpath.evidence.friedman.friedman`) on the cell's mean error (what
bench's table compares; CEC errors below 1e-8 already count as 0): the optimizers' mean ranks
(1 = best, ties share), the test's statistic and p, and Nemenyi's critical difference. Beside
the mean rank each row counts the blocks where the optimizer has the lowest mean error (ties
count for each), the blocks it solved (mean error <= :data:`SOLVED`, CEC's floor) and its
median over the blocks of the mean error. The strong baselines
(:data:`swarmpath.optimizers.registry.BASELINES`) are marked, so a new algorithm's row reads
beside CMA-ES, L-SHADE, jSO and random search.

``scripts/evidence/rankings.py`` prints these tables as markdown (docs/rankings.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarmpath.evidence.friedman import Friedman, friedman
from swarmpath.optimizers.registry import BASELINES

#: a mean error at or below it counts as solved (the CEC competitions' 1e-8)
SOLVED = 1e-8


@dataclass(frozen=True)
class RankRow:
    algorithm: str
    mean_rank: float
    best_in: int  # blocks where its mean error is the lowest (ties count for each)
    solved: int  # blocks with mean error <= SOLVED
    median_error: float  # median over the blocks of the mean error
    within_cd: bool  # mean rank within Nemenyi's critical difference of the best mean rank


@dataclass(frozen=True)
class Ranking:
    dim: int
    blocks: int
    test: Friedman
    rows: tuple[RankRow, ...]  # best mean rank first


def rank_study(doc: Mapping[str, Any]) -> list[Ranking]:
    """One :class:`Ranking` per dimension of a bench ``--json`` document."""
    algorithms: Sequence[str] = doc["settings"]["algorithms"]
    out = []
    for dim in doc["settings"]["dims"]:
        means: dict[str, dict[str, float]] = {}
        for c in doc["cells"]:
            if c["dim"] == dim:
                means.setdefault(c["function"], {})[c["algorithm"]] = float(c["stats"]["avg"])
        blocks = {f: v for f, v in means.items() if len(v) == len(algorithms)}
        test = friedman(blocks, algorithms)
        best_rank = min(test.mean_ranks.values())
        rows = []
        for a in algorithms:
            errors = np.array([v[a] for v in blocks.values()])
            lowest = sum(v[a] <= min(v.values()) for v in blocks.values())
            within = test.cd is not None and test.mean_ranks[a] - best_rank <= test.cd
            rows.append(RankRow(a, test.mean_ranks[a], int(lowest),
                                int(np.sum(errors <= SOLVED)), float(np.median(errors)),
                                bool(within)))
        rows.sort(key=lambda r: (r.mean_rank, r.algorithm))
        out.append(Ranking(int(dim), len(blocks), test, tuple(rows)))
    return out


def ranking_markdown(ranking: Ranking) -> list[str]:
    """The ranking as a markdown table and a line on the test."""
    lines = ["| # | optimizer | mean rank | lowest mean error in | solved | median of mean "
             "errors |", "|---|---|---|---|---|---|"]
    for i, r in enumerate(ranking.rows, 1):
        name = f"**{r.algorithm}** (baseline)" if r.algorithm in BASELINES else r.algorithm
        rank = f"{r.mean_rank:.2f}" + (" ~" if r.within_cd else "")
        lines.append(f"| {i} | {name} | {rank} | {r.best_in} | {r.solved} | "
                     f"{r.median_error:.3g} |")
    t = ranking.test
    stat = ("not computed: " + t.note) if t.statistic is None or t.p is None else (
        f"chi2 = {t.statistic:.1f}, p = {t.p:.2g}")
    cd = "" if t.cd is None else (f"; Nemenyi critical difference {t.cd:.2f} (`~`: within it "
                                  "of the best mean rank)")
    lines += ["", f"Friedman over {ranking.blocks} function-instance cells: {stat}{cd}."]
    return lines
