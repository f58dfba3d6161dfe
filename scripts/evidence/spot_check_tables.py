"""Spot-check a transcribed benchmark table against its seed text (issue 21).

Reads the seed paper's text (../shared/seeds/ by default), finds the table by its caption, and
applies the reading rule written at the top of icoot-table4.yaml to every cell of every
statistic line: a field is read when it is one well-formed number -- a mantissa d.dddd (0.0000
is zero whatever its exponent) times 10 to a signed exponent of ``--digits`` digits ("-00"
excluded: the prints write a zero exponent "+00"), or a plain decimal -- and a line is used
only when it has one field per column. Prints every disagreement with the YAML:

- ``differs``: the text reads a value and the YAML holds another;
- ``readable``: the text reads a value the YAML marks illegible (allowed where the file's notes
  say why the line cannot be trusted as a whole, e.g. icoot-table4's F5 block);
- ``not read``: the YAML holds a value the rule does not read (allowed where the file's notes
  say how it was read, e.g. a value whose exponent stands on the next line).

    PYTHONPATH=services .venv/bin/python scripts/evidence/spot_check_tables.py icoot-table4
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from swarmpath.evidence import reference

LABELS = {"min": "min", "mın": "min", "mm": "min", "max": "max", "avg": "avg", "avo": "avg",
          "std": "std", "sta": "std", "siu": "std"}
SUPERSCRIPTS = str.maketrans("⁺⁻⁰¹²³⁴⁵⁶⁷⁸⁹−", "+-0123456789-")
NOISE = ("$", "\\scriptscriptstyle", "\\text", "{", "}", "<sup>", "</sup>", "<b>", "</b>", "^",
         " ")


def read_field(field: str, digits: int) -> float | None:
    """The value of one table field under the reading rule, or None."""
    s = field.translate(SUPERSCRIPTS)
    for token in NOISE:
        s = s.replace(token, "")
    s = s.replace("\\times", "x").replace("imes", "x").replace("×", "x").replace("\\cdot", "x")
    if re.fullmatch(r"-?\d+(\.\d+)?", s):
        return float(s)
    m = re.fullmatch(r"(-?\d\.\d{4})x10(\d+|[+-]\d+)", s)
    if m is None:
        return None
    mantissa, exponent = m.groups()
    if float(mantissa) == 0.0:
        return 0.0
    if mantissa.lstrip("-")[0] == "0" or exponent[0] not in "+-" or exponent == "-00":
        return None
    if not 1 <= len(exponent) - 1 <= digits:
        return None
    return float(f"{mantissa}e{exponent}")


def _word(field: str) -> str:
    return field.strip().strip("[]()|")


def check(name: str, seeds: Path, digits: int) -> int:
    table = reference.load(name)
    if not isinstance(table, reference.BenchmarkTable):
        raise SystemExit(f"{name} is not a benchmark table")
    lines = (seeds / table.source["seed"]).read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines)
                 if line.startswith(f"{table.source['table']}.")  # "Table 3." starts its caption
                 and str(table.source["caption"])[:30] in line)
    functions = iter(table.functions)
    function = None
    found = {"differs": 0, "readable": 0, "not read": 0, "checked": 0}
    for line in lines[start + 1:]:
        if function is not None and line.startswith("Table"):
            break
        fields = line.split("\t")
        label = next((LABELS[_word(f)] for f in fields[:3] if _word(f) in LABELS), None)
        if label is None:
            continue
        if label == "min":
            function = next(functions, None)
        if function is None:
            break
        at = next(i for i, f in enumerate(fields) if LABELS.get(_word(f)) == label)
        values = fields[at + 1:at + 1 + len(table.algorithms)]
        aligned = len(values) == len(table.algorithms)
        for algorithm, text in zip(table.algorithms, values if aligned else [], strict=False):
            read = read_field(text, digits)
            held = table.cells[(function, algorithm)][label]
            found["checked"] += 1
            kind = None
            if read is not None and held is None:
                kind = "readable"
            elif read is not None and held is not None and abs(read - held) > 1e-9 * abs(read):
                kind = "differs"
            elif read is None and held is not None:
                kind = "not read"
            if kind:
                found[kind] += 1
                print(f"{kind:9} {function}/{algorithm} {label}: text {text.strip()!r}, "
                      f"YAML {held!r}")
        if not aligned:
            print(f"unaligned {function} {label}: {len(values)} fields for "
                  f"{len(table.algorithms)} columns")
    print(f"{name}: {found['checked']} fields checked, {found['differs']} differ, "
          f"{found['readable']} readable but illegible in the YAML, {found['not read']} in the "
          "YAML but not read by the rule")
    return found["differs"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tables", nargs="+")
    ap.add_argument("--seeds", type=Path, default=Path(__file__).parents[3] / "shared" / "seeds")
    ap.add_argument("--digits", type=int, default=3,
                    help="exponent digits a value may have (2 for the ICOOT paper's tables)")
    args = ap.parse_args()
    bad = sum(check(t, args.seeds, args.digits) for t in args.tables)
    raise SystemExit(1 if bad else 0)


if __name__ == "__main__":
    main()
