"""``swarmpath audit --maps``: the invariance certificate of path planners.

Every planner runs on every map of ``--maps`` and on its symmetric copies
(:mod:`swarmpath.world.symmetry`), the same runs and seeds, through ``swarmpath plan``'s runner;
:func:`swarmpath.evidence.map_audit.certify` tests per copy whether success and gap moved. The
table lists each copy against the original, then one verdict per planner and map.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Sequence
from typing import Any

from rich import box
from rich.console import Console
from rich.table import Table

from swarmpath import __version__
from swarmpath.cli.core import InputError
from swarmpath.evidence.map_audit import (
    ALPHA,
    GAP_TOLERANCE,
    SUCCESS_TOLERANCE,
    MapCertificate,
    certify,
)

__all__ = ["map_audit"]


def _num(v: Any, digits: int, scale: float = 1.0) -> str:
    return "-" if v is None else f"{scale * float(v):.{digits}f}"


def _p(v: float | None) -> str:
    return "-" if v is None else (f"{v:.3g}" if v >= 1e-3 else f"{v:.1e}")


def render(certificates: Sequence[MapCertificate]) -> Table:
    table = Table(title="Invariance certificate: each copy against the original map",
                  box=box.SIMPLE_HEAD, pad_edge=False)
    for name in ("Planner", "Map", "Copy", "Success", "Gap median (%)", "Length median (m)",
                 "Optimum (m)", "p success (Holm)", "p gap (Holm)", "Moved"):
        table.add_column(name, justify="left" if name in ("Planner", "Map", "Copy", "Moved")
                         else "right", no_wrap=True)
    for cert in certificates:
        for i, t in enumerate([cert.original, *cert.copies]):
            table.add_row(cert.planner if i == 0 else "", cert.map if i == 0 else "",
                          t.transform, f"{t.successes}/{t.runs}", _num(t.gap_median, 2, 100.0),
                          _num(t.length_median, 4), _num(t.optimum, 4), _p(t.p_success_holm),
                          _p(t.p_gap_holm), t.why or ("" if i == 0 else "no"),
                          end_section=i == len(cert.copies))
    return table


def map_audit(planners: str, maps: str, runs: int, seed: int, params: str | None, jobs: int,
              as_json: bool, map_options: Any = None) -> None:
    """Run the planners on the maps and their copies; print the certificate (or ``--json``)."""
    from swarmpath.cli import parallel
    from swarmpath.cli.plan import make_spec, run_plan
    from swarmpath.cli.plan_maps import compute_optima
    from swarmpath.world.symmetry import TRANSFORMS, symmetric_copy

    stderr = Console(stderr=True)

    def note(text: str) -> None:
        stderr.print(f"swarmpath audit: {text}", highlight=False, markup=False, soft_wrap=True)

    spec = make_spec(planners, maps, runs, seed, params, map_options=map_options, note=note)
    originals = list(spec.maps)
    copies = []
    for s in originals:
        try:
            copies += [symmetric_copy(s, t) for t in TRANSFORMS]
        except ValueError as exc:
            raise InputError("--maps", str(exc)) from None
    spec.maps = originals + copies
    spec.optima = compute_optima(spec.maps, spec.optimum_budget, note)
    total = len(spec.cells()) * spec.runs
    cells = run_plan(spec, jobs=jobs or min(parallel.usable_cpus(), total))
    by_cell = {(c.planner, c.scenario.name): c.runs for c in cells}
    certificates = [
        certify(p, s.name, by_cell[(p, s.name)],
                {t: by_cell[(p, f"{s.name}@{t}")] for t in TRANSFORMS})
        for p in spec.planners for s in originals
    ]
    if as_json:
        doc = {"swarmpath": __version__,
               "settings": {"planners": spec.planners, "maps": [s.name for s in originals],
                            "runs": spec.runs, "seed": spec.seed, "params": spec.params,
                            "transforms": list(TRANSFORMS), "alpha": ALPHA,
                            "gap_tolerance": GAP_TOLERANCE,
                            "success_tolerance": SUCCESS_TOLERANCE},
               "certificates": [_finite(c.to_json()) for c in certificates]}
        sys.stdout.write(json.dumps(doc, allow_nan=False) + "\n")
        return
    console = Console()
    if not console.is_terminal:
        console = Console(width=200)
    console.print(render(certificates))
    for c in certificates:
        text = f"{c.planner} on {c.map}: {c.verdict}"
        if c.moved:
            text += " (moved by " + ", ".join(c.moved) + ")"
        if c.note:
            text += f"; {c.note}"
        console.print(text, highlight=False)
    console.print(
        f"{spec.runs} runs per planner x map x copy, seed {spec.seed}; copies: rotated by 90, "
        "180 and 270 degrees, mirrored, translated by half the map inside a world 1.5 times "
        "as large, start and goal swapped (swarmpath.world.symmetry); a copy moves the planner "
        f"when Fisher's test (success) or the rank-sum test (gap), Holm-adjusted, is below "
        f"{ALPHA:g} and the success rate changes by >= {SUCCESS_TOLERANCE:g} or the median gap "
        f"by >= {100 * GAP_TOLERANCE:g} percentage points", highlight=False)


def _finite(v: Any) -> Any:
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_finite(x) for x in v]
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v
