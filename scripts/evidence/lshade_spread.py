"""swarmpath's L-SHADE runs beside every run of the reference code, function by function.

The ``lshade-reference-cec2017-d10`` table keeps each of the reference's runs
(``reference_runs``, written by ``scripts/evidence/lshade_reference.py``). Given the runs a
``swarmpath reproduce lshade-reference-cec2017-d10 --json`` document holds (several documents,
e.g. one per function, are joined), this prints per function, with errors floored at the table's
1e-8: both means and medians, the log10 ratio of the means, the runs above the reference's max
and below its min (ours rounded to the 7 digits the reference's runs are kept at), the
two-sided rank-sum test of the two samples, and how far the mean of
``n`` reference runs moves with the seeds alone (the range of the means of its consecutive
blocks of ``n`` runs, ``n`` = the measured run count):

    .venv/bin/python scripts/evidence/lshade_spread.py F1.json F2.json ... [--functions 10,12]
"""

from __future__ import annotations

import argparse
import json
import math
from importlib import resources
from pathlib import Path

import numpy as np
import yaml
from scipy.stats import mannwhitneyu

TABLE = "lshade-reference-cec2017-d10"


def measured_runs(paths: list[Path]) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for path in paths:
        docs = json.loads(path.read_text())
        for doc in docs if isinstance(docs, list) else [docs]:
            if doc.get("table") != TABLE:
                raise SystemExit(f"{path}: not a {TABLE} document")
            for cell in doc["cells"]:
                out[cell["function"]] = np.array([float(v) for v in cell["runs"]])
    return out


def block_range(runs: np.ndarray, n: int) -> tuple[float, float] | None:
    blocks = [runs[i:i + n].mean() for i in range(0, len(runs) - n + 1, n)]
    return (min(blocks), max(blocks)) if len(blocks) > 1 else None


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("documents", nargs="+", type=Path)
    p.add_argument("--functions", default="", help="numbers, e.g. 10,12 (default: all measured)")
    args = p.parse_args(argv)
    text = resources.files("swarmpath.evidence.reference").joinpath(f"{TABLE}.yaml").read_text()
    doc = yaml.safe_load(text)
    floor = float(doc["setting"]["error_floor"])
    reference = {k: np.maximum(np.array(v, dtype=float), floor)
                 for k, v in doc["reference_runs"].items()}
    # ours at the precision the reference's runs are kept at (7 digits), so that a basin both
    # sides end in (e.g. F30's 394.5008) compares as a tie, not as a difference in the 8th digit
    ours = {k: np.maximum(np.array([float(f"{x:.6E}") for x in v]), floor)
            for k, v in measured_runs(args.documents).items()}
    wanted = {f"cec2017:F{n}" for n in args.functions.split(",") if n}
    print("function  n_ref n_ours  mean_ref  mean_ours  log10  median_ref median_ours  "
          ">max <min  rank-sum p  ref block means (n_ours runs)")
    for function in doc["cells"]:
        if function not in ours or (wanted and function not in wanted):
            continue
        ref, mine = reference[function], ours[function]
        ratio = math.log10(mine.mean() / ref.mean())
        same = np.all(ref == ref[0]) and np.all(mine == ref[0])
        p_value = 1.0 if same else float(mannwhitneyu(mine, ref).pvalue)
        blocks = block_range(ref, len(mine))
        spread = "-" if blocks is None else f"{blocks[0]:.3g} to {blocks[1]:.3g}"
        print(f"{function:<9} {len(ref):>5} {len(mine):>6}  {ref.mean():<9.3g} "
              f"{mine.mean():<10.3g} "
              f"{ratio:+.2f}  {np.median(ref):<10.3g} {np.median(mine):<11.3g} "
              f"{int(np.sum(mine > ref.max())):>4} {int(np.sum(mine < ref.min())):>4}  "
              f"{p_value:<10.3g}  {spread}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
