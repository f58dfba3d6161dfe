"""How ``swarmpath reproduce`` prints a reproduction: a terminal table, markdown, CSV, plots."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.measure import Measurement
from rich.table import Table

from swarmpath.evidence import audit, reference, reproduction, reproduction_maps
from swarmpath.evidence.report import format_value
from swarmpath.evidence.reproduction import Row

Markers = Mapping[str, str | None]


def _num(v: float | None, digits: int = 2) -> str:
    return "n/a" if v is None else format_value(v, digits)


def _published(row: Row) -> tuple[str, str]:
    p = row.published
    spread = " / ".join(_num(p.get(s)) for s in ("min", "max", "std") if s in p)
    return _num(p.get("avg"), 4), spread


def _measured(row: Row, markers: Markers) -> list[str]:
    m = row.measured
    if m is None:
        return ["-"] * 5
    marker = markers.get(row.key) or ""
    odd = audit.ORIGIN_MARK if _origin_suspect(row) else ""
    return [f"{_num(m['avg'])}{odd} {marker}".strip(), _num(m["median"]), _num(m["min"]),
            _num(m["max"]), _num(m["std"])]


def _origin_suspect(row: Row) -> bool:
    """A benchmark cell that loses more than audit.SUSPECT_DECADES decades when shifted (the
    study ran the same runs shifted: ``extra['decades_lost_shift']``)."""
    return audit.shift_suspect(row.extra.get("decades_lost_shift"))


def _origin_note(rows: Sequence[Row]) -> list[str]:
    return [audit.SHIFT_FOOTNOTE] if any(_origin_suspect(r) for r in rows) else []


def _who(tab: reference.Table) -> tuple[str, str]:
    return ("algorithm", "F") if tab.kind == "benchmark" else ("planner", "map")


def _interval(row: Row) -> str:
    return "n/a" if row.interval is None else f"[{_num(row.interval[0])}, {_num(row.interval[1])}]"


def _beyond(row: Row) -> str:
    """Runs above the published max / below the min, and how likely that many are."""
    e = row.exceedance
    if e is None:
        return "n/a"
    sides = " / ".join("-" if n is None else str(n) for n in (e.above, e.below))
    return f"{sides} (p {e.p:.2g})"


def _reason_mark(row: Row, notes: list[str]) -> str:
    """The footnote number of the row's reason (one note for cells sharing a reason)."""
    if row.reason is None:
        return "UNEXPLAINED" if row.unexplained else ""
    text = row.reason + (f" (evidence: `{row.evidence}`)" if row.evidence else "")
    claim = row.claim
    if claim is not None and not row.holds:
        states = f"`{claim.direction}`" + (
            f" with exceedance `{claim.exceedance}`" if claim.exceedance else "")
        # a cell within the tolerance needs no reason: one written for another run count
        # (or a copied column) is shown as not needed, not as failing
        status = ("DOES NOT HOLD" if row.verdict in reproduction.DIFFERENT
                  else "not needed here")
        text = (f"{row.key}: {status} (it explains {states}; the cell is "
                f"`{row.verdict}`, beyond max / min {_beyond(row)}): {text}")
    if text not in notes:
        notes.append(text)
    return f"[{notes.index(text) + 1}]" + (" UNEXPLAINED" if row.unexplained else "")


def grid(tab: reference.Table, rows: Sequence[Row], markers: Markers
         ) -> tuple[list[str], list[list[str]], list[str]]:
    """Header, one line per cell (reason as a footnote number), and the footnotes."""
    who, where = _who(tab)
    header = [where, who, "published avg", "min / max / std", "measured avg", "median", "min",
              "max", "std"]
    if tab.kind == "map":
        header += ["success", "collisions", "exact optimum", "measured / published - 1"]
    else:
        header += ["log10 ratio"]
    header += ["95 % interval of the mean", "beyond max / min (p)", "verdict", "reason"]
    lines: list[list[str]] = []
    notes: list[str] = []
    for r in rows:
        pub_avg, spread = _published(r)
        line = [r.where, r.who, pub_avg, spread, *_measured(r, markers)]
        if tab.kind == "map":
            optimum = r.extra.get("optimum")
            line += [str(r.extra.get("success", "")), str(r.extra.get("collisions", "")),
                     "-" if optimum is None else f"{optimum:.3f}"]
        if r.log10_ratio is None:
            ratio = "n/a"
        elif tab.kind == "map":  # a few per cent: say it so
            ratio = f"{(10 ** r.log10_ratio - 1) * 100:+.1f} %"
        else:
            ratio = f"{r.log10_ratio:+.2f}"
        lines.append([*line, ratio, _interval(r), _beyond(r), r.verdict,
                      _reason_mark(r, notes)])
    return header, lines, notes


def count_lines(tab: reference.Table, rows: Sequence[Row], markers: Markers) -> list[list[str]]:
    order = tab.algorithms if isinstance(tab, reference.BenchmarkTable) else tab.planners
    counts = reproduction.counts(rows, order)
    out = []
    for who, per in counts.items():
        signs = [markers.get(r.key) for r in rows if r.who == who]
        tally = "/".join(str(sum(s == m for s in signs)) for m in ("+", "=", "-"))
        unexplained = sum(r.unexplained for r in rows if r.who == who)
        out.append([who, *(str(per[v]) for v in reproduction.VERDICTS), str(unexplained),
                    tally if any(signs) else "reference" if signs else "-"])
    return out


COUNT_HEADER = [*reproduction.VERDICTS, "unexplained", "+/=/- vs reference"]


def _setting_text(tab: reference.Table, setting: Mapping[str, Any]) -> str:
    paper = tab.setting
    if tab.kind != "benchmark":
        what = ", ".join(f"{k} {v}" for k, v in paper.items() if k not in ("maps", "runs"))
    elif paper.get("budget_evals"):  # a suite's table: the field's budget, its instances
        what = (f"{paper['budget_evals']} evaluations, {paper['dims'][0]} dims"
                + (f", instances {', '.join(map(str, paper['instances']))}"
                   if paper.get("instances") else ""))
    else:
        what = (f"{paper.get('agents')} agents, {paper.get('iterations')} iterations, "
                f"{paper['dims'][0]} dims")
    # a seed paper's table names its seed text; another paper's, its short citation
    where = tab.source.get("seed") or tab.source.get("cite") or tab.source["paper"]
    return (f"{tab.source['table']} of {where} ({paper['runs']} runs, {what}); "
            f"measured: {setting['runs']} runs per cell, seed {setting['seed']}")


def markdown(tab: reference.Table, setting: Mapping[str, Any], rows: Sequence[Row],
             markers: Markers, command: str) -> str:
    header, lines, notes = grid(tab, rows, markers)
    out = [f"## {tab.name}", "", f"`{command}`", "", _setting_text(tab, setting) + ".", ""]
    out += _md_table(header, lines)
    if notes:
        out += ["", "Reasons:", ""]
        out += [f"{i}. {n}" for i, n in enumerate(notes, 1)]
    for note in _origin_note(rows):
        out += ["", note]
    out += ["", "Verdicts per " + _who(tab)[0] + " (+/=/-: rank-sum test against the "
            "last one listed, Holm-corrected, alpha 0.05):", ""]
    out += _md_table([_who(tab)[0], *COUNT_HEADER], count_lines(tab, rows, markers))
    out += ["", reproduction.summary_line(rows), "", "Notes on the print:", ""]
    out += [f"- {' '.join(n.split())}" for n in tab.notes]
    return "\n".join(out) + "\n\n"


def markdown_header(command: str, version: str, judged_from: str | None = None) -> str:
    """The top of a generated reproduction document: what made it and how to read it."""
    made = (f"Generated by `{command}` (swarmpath {version}). Do not edit by hand: run the "
            "command again.")
    if judged_from is not None:
        made = (f"Generated by `swarmpath reproduce --from {judged_from} --format markdown` "
                f"(swarmpath {version}): the runs measured by the command named in each "
                "section, saved with `--json`, judged with the current reasons. Do not edit by "
                "hand: run the commands again.")
    return "\n".join([
        "# Reproduction of the seed papers' tables", "",
        made, "",
        "Each cell sets the published value beside the measured one at the paper's setting "
        "(agents, iterations, dims, maps; fewer runs than the paper where stated). Benchmark "
        "cells compare means on f - f_min (so F8 compares gaps to its optimum), every value "
        "raised to the function's floating-point floor; map cells compare the mean executed "
        "length of the successful runs with the published mean distance. Verdicts "
        "(`services/swarmpath/evidence/verdicts.py`): `consistent` when the published mean "
        "lies in the 95 % bootstrap interval of the measured mean (BCa, 9999 resamples seeded "
        "from the cell's key) and the measured runs do not depart from the published range "
        "(the exceedance test: how many runs lie above the published max or below its min, "
        "and the probability of that many if the paper's n runs and ours came from one "
        "distribution, P(K >= k) = C(m, k) / C(n + m, k), both sides Bonferroni-combined, "
        "departing below 0.05); otherwise `matches` when the log10 ratio of the means is "
        "within the tolerance (one decade; F8 and the maps: 10 %), else `better` or `worse`. "
        "`not comparable`: the published value is illegible, contradicts itself, is not a "
        "measurement (a derived column), is in other units, or cannot be a path length. A "
        "`better` or `worse` cell is explained only by a reviewed reason "
        "(`services/swarmpath/evidence/reference/reasons.yaml`) that states this direction "
        "(and, for a tail, the exceedance it explains) and carries the command showing its "
        "cause; a reason whose direction the cell leaves does not hold, and the cell counts as "
        "unexplained. ° origin-suspect: the cell's mean gap grows by more than "
        f"{audit.SUSPECT_DECADES:g} decades when the function is shifted (the same runs and "
        "seeds, `--transform shift`, as `swarmpath audit` computes). +/=/- beside a measured "
        "mean: "
        "Wilcoxon rank-sum test against the last algorithm or planner listed (the paper's "
        "proposed one), Holm-corrected over the table, alpha 0.05 (docs/statistics.md). The "
        "published tables and the notes on their prints are in "
        "`services/swarmpath/evidence/reference/*.yaml`.", "", "",
    ])


def _md_table(header: Sequence[str], lines: Sequence[Sequence[str]]) -> list[str]:
    def esc(s: str) -> str:
        return s.replace("|", "\\|")

    out = ["| " + " | ".join(header) + " |", "|" + " --- |" * len(header)]
    out += ["| " + " | ".join(esc(c) for c in line) + " |" for line in lines]
    return out


def csv_text(tab: reference.Table, rows: Sequence[Row], markers: Markers) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    who, where = _who(tab)
    w.writerow(["table", where, "dim", who, "published_avg", "published_min", "published_max",
                "published_std", "measured_avg", "measured_median", "measured_min",
                "measured_max", "measured_std", "marker", "log10_ratio", "interval_low",
                "interval_high", "above_max", "below_min", "exceedance_p", "verdict",
                "unexplained", "reason", "evidence"])
    for r in rows:
        m = r.measured or {}
        w.writerow([tab.name, r.where, "" if r.dim is None else r.dim, r.who,
                    *(_raw(r.published.get(s)) for s in ("avg", "min", "max", "std")),
                    *(_raw(m.get(s)) for s in ("avg", "median", "min", "max", "std")),
                    markers.get(r.key) or "", _raw(r.log10_ratio),
                    *(_raw(v) for v in (r.interval or (None, None))),
                    *(("" if n is None else n) for n in _sides(r)),
                    "" if r.exceedance is None else _raw(r.exceedance.p), r.verdict,
                    str(r.unexplained).lower(), r.reason or "", r.evidence or ""])
    return buf.getvalue()


def _sides(r: Row) -> tuple[int | None, int | None]:
    e = r.exceedance
    return (None, None) if e is None else (e.above, e.below)


def _raw(v: float | None) -> str:
    return "" if v is None else repr(float(v))


def print_rich(tab: reference.Table, setting: Mapping[str, Any], rows: Sequence[Row],
               markers: Markers) -> None:
    header, lines, notes = grid(tab, rows, markers)
    table = Table(title=f"{tab.name}: {_setting_text(tab, setting)}")
    for h in header:
        table.add_column(h, overflow="fold")
    for line in lines:
        table.add_row(*line)
    counts = Table(title="verdicts")
    for h in [_who(tab)[0], *COUNT_HEADER]:
        counts.add_column(h)
    for line in count_lines(tab, rows, markers):
        counts.add_row(*line)
    console = Console()
    if not console.is_terminal:  # pipes and files: never squeeze the numbers
        width = Measurement.get(console, console.options.update(width=100_000), table).maximum
        console = Console(width=max(80, width))
    console.print(table)
    for i, n in enumerate(notes, 1):
        console.print(f"[{i}] {n}", highlight=False, markup=False)
    for n in _origin_note(rows):
        console.print(n, highlight=False, markup=False)
    console.print(counts)
    console.print(reproduction.summary_line(rows), highlight=False)


def plot(tab: reference.Table, rows: Sequence[Row], path: Path) -> Path:
    """log10(measured / published) per cell, one series per algorithm or planner, the
    tolerance shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    places = list(dict.fromkeys(r.where for r in rows))
    who = list(dict.fromkeys(r.who for r in rows))
    lo, hi = ((-reproduction.DECADE, reproduction.DECADE) if tab.kind == "benchmark" else
              (math.log10(1 - reproduction_maps.MAP_TOLERANCE),
               math.log10(1 + reproduction_maps.MAP_TOLERANCE)))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.6 * len(places) + 2), 4.5))
    ax.axhspan(lo, hi, color="0.9", label="matches" if tab.kind == "map" else "matches (F8: 10 %)")
    for i, name in enumerate(who):
        pts = [(places.index(r.where) + (i - len(who) / 2) * 0.08, r.log10_ratio)
               for r in rows if r.who == name and r.log10_ratio is not None]
        if pts:
            ax.scatter([x for x, _ in pts], [y for _, y in pts], s=18, label=name)
    ax.set_xticks(range(len(places)), places, rotation=45 if tab.kind == "map" else 0)
    ax.set_ylabel("log10(measured / published)")
    ax.set_title(tab.name)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_outputs(directory: Path, tab: reference.Table, setting: Mapping[str, Any],
                  rows: Sequence[Row], markers: Markers, command: str,
                  statistics: Mapping[str, Any] | None = None) -> list[Path]:
    """DIR/<table>.md and .png, and for a benchmark table run here its anytime figures
    (DIR/<table>-anytime/anytime_<function>_d<dim>.png: runtime ECDF and ERT per function)."""
    directory.mkdir(parents=True, exist_ok=True)
    from swarmpath.cli.reproduce_added import markdown_added

    (directory / f"{tab.name}.md").write_text(
        markdown(tab, setting, rows, markers, command) + markdown_added(statistics),
        encoding="utf-8")
    out = [directory / f"{tab.name}.md", plot(tab, rows, directory / f"{tab.name}.png")]
    groups = (statistics or {}).get("anytime")
    if groups:
        from swarmpath.evidence.anytime import AnytimeGroup
        from swarmpath.evidence.anytime_report import write_anytime_plots

        parsed = {(g["function"], int(g["dim"])): AnytimeGroup.from_json(g) for g in groups}
        order = tab.algorithms if isinstance(tab, reference.BenchmarkTable) else None
        out += write_anytime_plots(parsed, directory / f"{tab.name}-anytime", order)
    return out


def latex_table(tab: reference.Table, setting: Mapping[str, Any], rows: Sequence[Row],
                markers: Markers) -> str:
    """The reproduction as a booktabs table: published beside measured, markers, verdicts; the
    reasons and the caption naming the setting and the tests."""
    from swarmpath.evidence import latex

    header, lines, notes = grid(tab, rows, markers)
    caption = (f"{tab.name}: {_setting_text(tab, setting)}. +/=/- beside a measured mean: "
               "two-sided Wilcoxon rank-sum test against the last one listed, Holm-corrected, "
               "alpha 0.05. " + reproduction.summary_line(rows))
    ends = [i for i in range(len(rows) - 1) if rows[i].where != rows[i + 1].where]
    text = latex.rows_to_latex(header, lines, caption, f"tab:{tab.name}",
                               "l" * 2 + "r" * (len(header) - 2), section_ends=ends)
    if notes:
        text += "\\begin{enumerate}\n" + "".join(
            f"\\item {latex.cell_text(n)}\n" for n in notes) + "\\end{enumerate}\n"
    return text
