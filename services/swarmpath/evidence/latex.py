"""Tables as LaTeX (``--format latex``): a booktabs ``table`` environment with a caption naming
the setting and the tests, ready for ``\\input`` in a paper (needs ``\\usepackage{booktabs}``).

:func:`grid_to_latex` draws a :class:`swarmpath.evidence.tables.Grid` (the benchmark table of
``bench`` and ``results``); :func:`rows_to_latex` any header and rows of text (``plan``,
``reproduce``). Numbers in the papers' notation (6.59E-28) become ``$6.59\\times10^{-28}$``;
bold cells (the best and those not significantly worse) use ``\\boldmath`` so that digits and
exponents are bold without another package; the +/=/- markers are superscripts; text is
escaped. Pure functions, no I/O.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from swarmpath.evidence.tables import NOTE_ROWS, Grid, TCell

PACKAGES = ("booktabs",)
_SPECIAL = {
    "\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_",
    "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}",
    "°": r"\textdegree{}", "≈": r"$\approx$",
}
_NUMBER = re.compile(r"(?<![\w.])(-?)(\d+(?:\.\d+)?)E([+-])(\d+)")
_INF = re.compile(r"(?<![\w\\])(-?)inf(?!\w)")
_MARKERS = {"+": "+", "=": "=", "-": "-"}


def escape(text: str) -> str:
    """``text`` with LaTeX's special characters escaped."""
    return "".join(_SPECIAL.get(ch, ch) for ch in text)


def _math_number(match: re.Match[str]) -> str:
    sign, mantissa, esign, exp = match.groups()
    power = int(exp) * (-1 if esign == "-" else 1)
    return f"${sign}{mantissa}\\times10^{{{power}}}$"


def cell_text(text: str) -> str:
    """Escaped text whose numbers in E notation are set as math."""
    out, last = [], 0
    for m in _NUMBER.finditer(text):
        out.append(escape(text[last:m.start()]))
        out.append(_math_number(m))
        last = m.end()
    out.append(escape(text[last:]))
    return _INF.sub(lambda m: f"${m.group(1)}\\infty$", "".join(out))


def _cell(c: TCell, markers: bool) -> str:
    s = cell_text(c.text)
    if c.bold and s:
        s = "{\\boldmath\\bfseries " + s + "}"
    if "°" in c.marks:
        s += r"$^{\circ}$"
    if markers and c.marker in _MARKERS:
        s += f"$^{{{_MARKERS[c.marker]}}}$"
    return s


def _environment(header: Sequence[str], align: str, body: list[str], caption: str,
                 label: str | None, size: str) -> str:
    lines = [r"\begin{table}[htbp]", r"\centering", f"\\caption{{{escape(caption)}}}"]
    if label:
        lines.append(f"\\label{{{label}}}")
    lines += [f"\\{size}", f"\\begin{{tabular}}{{{align}}}", r"\toprule",
              " & ".join(escape(h) for h in header) + r" \\", r"\midrule", *body,
              r"\bottomrule", r"\end{tabular}", r"\end{table}"]
    return "\n".join(lines) + "\n"


def grid_to_latex(grid: Grid, caption: str, label: str | None = None,
                  size: str = "footnotesize") -> str:
    """The grid as a booktabs table; a ``\\midrule`` between functions."""
    body = []
    last = len(grid.rows) - 1
    for i, row in enumerate(grid.rows):
        effect = grid.labels == 3 and row[2].text in NOTE_ROWS
        cells = [cell_text(c.text) for c in row[:grid.labels]]
        cells += [_cell(c, grid.markers and not effect) for c in row[grid.labels:]]
        body.append(" & ".join(cells) + r" \\")
        if i in grid.section_ends and i != last:
            body.append(r"\midrule")
    return _environment(grid.header, "".join(grid.align), body, caption, label, size)


def rows_to_latex(header: Sequence[str], rows: Sequence[Sequence[str]], caption: str,
                  label: str | None = None, align: str | None = None,
                  size: str = "footnotesize", section_ends: Sequence[int] = ()) -> str:
    """Any table of text cells (numbers in E notation set as math, markers after a value kept)."""
    body = []
    ends = set(section_ends)
    for i, row in enumerate(rows):
        body.append(" & ".join(cell_text(str(c)) for c in row) + r" \\")
        if i in ends and i != len(rows) - 1:
            body.append(r"\midrule")
    return _environment(header, align or "l" * len(header), body, caption, label, size)


def document(*tables: str) -> str:
    """A minimal standalone document around ``tables`` (what the tests compile)."""
    uses = "".join(f"\\usepackage{{{p}}}\n" for p in PACKAGES)
    return ("\\documentclass{article}\n" + uses + "\\begin{document}\n" + "\n".join(tables)
            + "\\end{document}\n")
