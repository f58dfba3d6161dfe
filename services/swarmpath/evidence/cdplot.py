"""Critical-difference diagrams (Demsar, JMLR 7 (2006) 1-30, Fig. 1) as PNG files.

The mean ranks of a Friedman test (:class:`swarmpath.evidence.compare.Friedman`) on an axis from 1
(best, left) to k; each algorithm hangs from its rank to a label on the left (the better half) or
the right; the Nemenyi critical difference is drawn above the axis, and a thick bar below it joins
every group of algorithms whose mean ranks differ by less than that (no significant difference).
Drawn on a bare :class:`matplotlib.figure.Figure` (no pyplot state).
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from swarmpath.evidence.compare import Friedman, cliques


def draw_cd(f: Friedman, path: Path, title: str = "") -> Path | None:
    """Write the diagram of ``f`` to ``path``; None (nothing written) with fewer than 2
    algorithms or no complete block."""
    ranks = {a: r for a, r in f.mean_ranks.items() if r == r}  # NaN: no block
    if f.cd is None or len(ranks) < 2:
        return None
    k = len(f.algorithms)
    order = sorted(ranks, key=lambda a: ranks[a])
    groups = cliques(ranks, f.cd)
    half = (len(order) + 1) // 2
    rows = max(half, len(order) - half)
    axis_y = 0.8
    first_label_y = axis_y + 0.35 + 0.12 * len(groups)
    height = first_label_y + 0.3 * rows
    fig = Figure(figsize=(7.5, height), dpi=100)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(-0.25 * k - 0.5, 1.25 * k + 1.5)
    ax.set_ylim(height, 0.0)  # y grows downwards, in inches
    ax.axis("off")
    ax.plot([1, k], [axis_y, axis_y], color="black", lw=1)
    for t in range(1, k + 1):
        ax.plot([t, t], [axis_y - 0.08, axis_y], color="black", lw=1)
        ax.text(t, axis_y - 0.12, str(t), ha="center", va="bottom", fontsize=9)
    # the critical difference, above the axis from rank 1
    cd_y = 0.25
    ax.plot([1, 1 + f.cd], [cd_y, cd_y], color="black", lw=1.5)
    for x in (1, 1 + f.cd):
        ax.plot([x, x], [cd_y - 0.05, cd_y + 0.05], color="black", lw=1.5)
    ax.text(1 + f.cd / 2, cd_y - 0.07, f"CD = {f.cd:.2f}", ha="center", va="bottom", fontsize=9)
    # the groups without significant difference
    for i, group in enumerate(groups):
        y = axis_y + 0.15 + 0.12 * i
        ax.plot([ranks[group[0]] - 0.03, ranks[group[-1]] + 0.03], [y, y], color="black", lw=3)
    for i, a in enumerate(order):
        left = i < half
        row = i if left else len(order) - 1 - i
        y = first_label_y + 0.3 * row
        x_end = 0.5 if left else k + 0.5
        ax.plot([ranks[a], ranks[a], x_end], [axis_y, y, y], color="black", lw=0.8)
        label = f"{a} ({ranks[a]:.2f})" if left else f"({ranks[a]:.2f}) {a}"
        ax.text(x_end + (-0.1 if left else 0.1), y, label, ha="right" if left else "left",
                va="center", fontsize=9, fontweight="bold" if a == f.reference else "normal")
    p = "" if f.p is None else f", Friedman p = {f.p:.3g}"
    ax.text(k + 1.4, 0.1, f"{title}{p}".strip(", "), ha="right", va="top", fontsize=9)
    fig.savefig(path)
    return path
