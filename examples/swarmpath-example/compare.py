"""The README's tables, measured with swarmpath: ``python compare.py`` (from this directory, with
swarmpath and this package installed, or ``--plugin swarmpath_example`` reachable).

1. F1-F13 at D = 30 (30 agents, 500 iterations, 30 runs: the GWO paper's setting) for GWO and
   mGWO, beside the GWO column of the GWO paper's Tables 5 and 6;
2. the spring design problem (30 agents, 500 iterations, 30 runs) for GWO, mGWO and PSO, against
   its known best value.
"""

from __future__ import annotations

import json
import subprocess
import sys

#: GWO, average over 30 runs: Mirjalili et al., Adv. Eng. Softw. 69 (2014), Tables 5 and 6
GWO_PAPER = {
    "F1": 6.59e-28, "F2": 7.18e-17, "F3": 3.29e-06, "F4": 5.61e-07, "F5": 26.81258,
    "F6": 0.816579, "F7": 0.002213, "F8": -6123.1, "F9": 0.310521, "F10": 1.06e-13,
    "F11": 0.004485, "F12": 0.053438, "F13": 0.654464,
}


def bench(*args: str) -> dict:
    out = subprocess.run([sys.executable, "-m", "swarmpath.cli", "bench", "--json",
                          "--plugin", "swarmpath_example", *args],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def cells(doc: dict) -> dict[tuple[str, str], dict]:
    return {(c["algorithm"], c["function"]): c for c in doc["cells"]}


def main() -> None:
    doc = bench("-a", "GWO,mGWO", "-f", "F1-F13", "-d", "30", "--runs", "30", "--agents", "30",
                "--iterations", "500", "--reference", "GWO", "-j", "0")
    got = cells(doc)
    print("| function | GWO paper avg | GWO avg (swarmpath) | mGWO avg (swarmpath) | mGWO vs GWO |")
    print("| --- | --- | --- | --- | --- |")
    for f, paper in GWO_PAPER.items():
        g, m = got[("GWO", f)], got[("mGWO", f)]
        marker = m["test"]["marker"] or "="
        print(f"| {f} | {paper:.4g} | {g['stats']['avg']:.4g} | {m['stats']['avg']:.4g} | "
              f"{marker} (p_holm {m['test']['p_holm']:.2g}) |")
    doc = bench("-a", "GWO,mGWO,PSO", "-f", "spring-design", "-d", "3", "--runs", "30",
                "--agents", "30", "--iterations", "500")
    from swarmpath_example.spring import F_BEST

    print("\n| algorithm | best | median | worst | best / f* |")
    print("| --- | --- | --- | --- | --- |")
    for (a, _f), c in cells(doc).items():
        s = c["stats"]
        print(f"| {a} | {s['min']:.7f} | {s['median']:.7f} | {s['max']:.7f} | "
              f"{s['min'] / F_BEST:.5f} |")


if __name__ == "__main__":
    main()
