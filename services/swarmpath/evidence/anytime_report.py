"""The anytime statistics (:mod:`swarmpath.evidence.anytime`) as tables and figures: per function
and dimension a fixed-target table (ERT with its bootstrap interval and the runs that reached
each target), a fixed-budget table (median error after each budget) with the area under the
ECDF, and a figure of the runtime ECDF and ERT against the target (PNG, matplotlib Agg).
Used by ``swarmpath bench --anytime / --plot``, ``results --plot`` and ``reproduce --out``."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rich import box
from rich.table import Table
from rich.text import Text

from swarmpath.evidence.anytime import AnytimeGroup
from swarmpath.evidence.tables import format_value


def _ert(v: float) -> str:
    return "inf" if math.isinf(v) else ("-" if math.isnan(v) else f"{v:.0f}")


def fixed_target_table(title: str, group: AnytimeGroup, algorithms: Sequence[str]) -> Table:
    """Rows: the targets (f - f*, easiest first); per algorithm ERT [95 % interval] (hits/runs)."""
    table = Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("target f - f*", justify="right", no_wrap=True)
    names = [a for a in algorithms if a in group.cells]
    for a in names:
        table.add_column(f"{a} ERT [95% CI] (hits)", justify="right", no_wrap=True)
    for j, target in enumerate(group.targets):
        cols = [format_value(target)]
        for a in names:
            c = group.cells[a]
            cols.append(f"{_ert(c.ert[j])} [{_ert(c.ert_low[j])}, {_ert(c.ert_high[j])}] "
                        f"({c.hits[j]}/{c.runs})")
        table.add_row(*(Text(col) for col in cols))
    return table


def fixed_budget_table(title: str, group: AnytimeGroup, algorithms: Sequence[str]) -> Table:
    """Rows: the budgets (evaluations); per algorithm the median f - f* reached; last row the
    area under the ECDF."""
    table = Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("evaluations", justify="right", no_wrap=True)
    names = [a for a in algorithms if a in group.cells]
    for a in names:
        table.add_column(f"{a} median f - f*", justify="right", no_wrap=True)
    for k, budget in enumerate(group.fixed_budgets):
        table.add_row(str(budget), *(format_value(group.cells[a].budget_median[k]) for a in names),
                      end_section=k == len(group.fixed_budgets) - 1)
    table.add_row("ECDF AUC", *(f"{group.cells[a].auc:.3f}" for a in names))
    return table


LEGEND = (
    "Anytime: targets f - f* are IOHanalyzer's default (10 log-spaced between the smallest and "
    "largest error any run recorded, the smallest raised to 1e-12); ERT = evaluations spent by "
    "all runs until they reached the target or stopped, over the runs that reached it, with a "
    "95 % percentile bootstrap interval over the runs; ECDF AUC = area under the runtime ECDF "
    "over budgets 0..B divided by B (B: the largest budget of the function and dimension)."
)


def anytime_figure(title: str, group: AnytimeGroup, colours: Mapping[str, Any]) -> Any:
    """Two panels: the runtime ECDF against evaluations (log x), ERT against target (log-log)."""
    from swarmpath.evidence.plots import _pyplot

    plt = _pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.3), dpi=100)
    for a, c in group.cells.items():
        left.step(group.ecdf_budgets, c.ecdf, where="post", color=colours[a], lw=1.5,
                  label=f"{a} (AUC {c.auc:.3f})")
        pts = [(t, e) for t, e in zip(group.targets, c.ert, strict=True) if math.isfinite(e)]
        if pts:
            right.plot([t for t, _ in pts], [e for _, e in pts], marker="o", ms=3,
                       color=colours[a], lw=1.2, label=a)
    left.set_xscale("log")
    left.set_ylim(-0.02, 1.02)
    left.set_xlabel("function evaluations")
    left.set_ylabel("share of (run, target) pairs reached")
    left.set_title("runtime ECDF over the targets")
    left.grid(True, alpha=0.3)
    left.legend(fontsize=8)
    right.set_xscale("log")
    right.set_yscale("log")
    right.invert_xaxis()
    right.set_xlabel("target f - f*")
    right.set_ylabel("ERT (evaluations)")
    right.set_title("expected running time (targets reached)")
    right.grid(True, which="both", alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def write_anytime_plots(groups: Mapping[tuple[str, int], AnytimeGroup], directory: Path,
                        algorithms: Sequence[str] | None = None) -> list[Path]:
    """``anytime_<function>_d<dim>.png`` per function and dimension."""
    from swarmpath.evidence.plots import _save, palette, slug

    names = list(algorithms) if algorithms is not None else list(dict.fromkeys(
        a for g in groups.values() for a in g.cells))
    colours = palette(names)
    directory.mkdir(parents=True, exist_ok=True)
    out = []
    for (function, dim), group in groups.items():
        fig = anytime_figure(f"{function}, {dim} dimensions", group, colours)
        out.append(_save(fig, directory / f"anytime_{slug(function)}_d{dim}.png"))
    return out
