"""The run tables ``swarmpath plan`` prints: one paper-style table per planner x map (Run /
Distance / Error / Elapsed time ..., with a Mean row), the caption and legend, and for several
planners the comparison from :mod:`swarmpath.cli.plan_stats`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from rich import box
from rich.console import Console
from rich.measure import Measurement
from rich.table import Table

from swarmpath.evidence.legend import legend_text

if TYPE_CHECKING:
    from swarmpath.cli.plan import CellResult, PlanSpec


def _num(v: Any, digits: int = 4) -> str:
    return "-" if v is None else f"{float(v):.{digits}f}"


def _causes(r: dict[str, Any]) -> str:
    """Collisions by cause, robot-driven / obstacle-driven (see metrics.contact_causes)."""
    return f"{r.get('robot_driven_contacts') or 0}/{r.get('obstacle_driven_contacts') or 0}"


def render_cell(cell: CellResult, row: dict[str, Any], reason: str | None = None,
                octile: float | None = None) -> Table:
    """The paper-style run table of one planner x map (``row``: its summary; ``reason``: why
    there is no exact optimum; ``octile``: the MovingAI .scen optimum as a reference)."""
    optimum = row["optimum"]
    title = f"{cell.planner} on {cell.scenario.name}"
    title += (f" (exact optimum {optimum:.4f} m" if optimum is not None
              else f" (no exact optimum: {reason or 'see the runs'}")
    title += f"; octile optimum {octile:.4f} m)" if octile is not None else ")"
    table = Table(title=title, box=box.SIMPLE_HEAD, pad_edge=False)
    for name in ("Run", "Distance (m)", "Error (m)", "Elapsed time (s)", "CPU time (s)", "Success",
                 "Collisions", "Robot/obstacle-driven", "Gap (%)", "Steps", "Iterations"):
        table.add_column(name, justify="left" if name == "Success" else "right", no_wrap=True)
    planned = any(r.get("planned_length") is not None for r in cell.runs)
    if planned:  # global planners: the length they planned beside the one driven
        table.add_column("Planned (m)", justify="right", no_wrap=True)
    failed = any(not r["success"] for r in cell.runs)
    if failed:
        table.add_column("Failure", no_wrap=True)
        table.add_column("Reason")
    for r in cell.runs:
        gap = None if r["gap"] is None else 100.0 * r["gap"]
        cols = [str(r["run"] + 1), _num(r["length"]), _num(r["error"]), _num(r["seconds"], 3),
                _num(r.get("cpu_seconds"), 3), "yes" if r["success"] else "no",
                str(r["collisions"]), _causes(r), _num(gap, 2), str(r["steps"]),
                str(r["iterations"])]
        if planned:
            cols.append(_num(r.get("planned_length")))
        if failed:
            cols.extend(("", "") if r["success"] else (str(r.get("failure_class") or ""),
                                                       _why(r)))
        table.add_row(*cols)
    gap_mean = None if row["gap_mean"] is None else 100.0 * row["gap_mean"]
    mean = ["Mean", _num(row["length_mean"]), _num(row["error_mean"]),
            _num(row["seconds_mean"], 3), _num(row["cpu_seconds_mean"], 3),
            f"{row['successes']}/{row['runs']}", str(row["collisions"]), _causes(row),
            _num(gap_mean, 2), f"{row['steps_mean']:.1f}", f"{row['iterations_mean']:.0f}"]
    if planned:
        mean.append("")
    if failed:
        mean.extend(("", ""))
    table.add_row(*mean, style="bold", end_section=True)
    return table


def _why(r: dict[str, Any]) -> str:
    """A failed run's reason and, when classified, where and for how long."""
    detail = r.get("failure_detail")
    reason = str(r["reason"])
    return f"{reason}: {detail}" if detail and detail != reason else reason


def render_failures(rows: Sequence[dict[str, Any]]) -> Table | None:
    """Why the runs failed, per planner x map: the count of each failure class
    (:mod:`swarmpath.planners.failures`); None when every run succeeded."""
    from swarmpath.failure_classes import FAILURE_CLASSES

    seen = {k for r in rows for k in (r.get("failure_classes") or {})}
    if not seen:
        return None
    kinds = [k for k in FAILURE_CLASSES if k in seen] + sorted(seen - set(FAILURE_CLASSES))
    table = Table(title="Why runs failed", box=box.SIMPLE_HEAD, pad_edge=False)
    for name in ("Map", "Planner", "Failed", *kinds):
        table.add_column(name, justify="left" if name in ("Map", "Planner") else "right",
                         no_wrap=True)
    for row in rows:
        counts = row.get("failure_classes") or {}
        table.add_row(str(row["map"]), str(row["planner"]), f"{row['runs'] - row['successes']}/"
                      f"{row['runs']}", *(str(counts.get(k, 0)) for k in kinds))
    return table


#: The path-quality table: (header, summary key, digits, scale).
QUALITY_COLUMNS = (
    ("Clearance min (m)", "min_clearance", 3, 1.0),
    ("Clearance mean (m)", "clearance_mean", 3, 1.0),
    ("Curvature max (1/m)", "curvature_max", 2, 1.0),
    ("Curvature mean (1/m)", "curvature_mean", 3, 1.0),
    ("Cusps", "cusps", 1, 1.0),
    ("In danger (%)", "danger_share", 1, 100.0),
    ("Travel time (s)", "travel_time_mean", 1, 1.0),
    ("Velocity smoothness (m/s2)", "velocity_smoothness", 3, 1.0),
    ("Angular smoothness (rad/s2)", "angular_smoothness", 2, 1.0),
    ("Jerk (m/s3)", "jerk", 2, 1.0),
    ("Cost mean (nav2)", "costmap_cost_mean", 1, 1.0),
    ("Cost max (nav2)", "costmap_cost_max", 1, 1.0),
)


def render_quality(rows: Sequence[dict[str, Any]]) -> Table:
    """The field's path metrics per planner x map (summary rows: means over successful runs;
    the least clearance over all runs)."""
    table = Table(title="Path quality (means over the successful runs)", box=box.SIMPLE_HEAD,
                  pad_edge=False)
    for name in ("Map", "Planner", *(c[0] for c in QUALITY_COLUMNS)):
        table.add_column(name, justify="left" if name in ("Map", "Planner") else "right",
                         no_wrap=True)
    for row in rows:
        cells = []
        for _, key, digits, scale in QUALITY_COLUMNS:
            v = row.get(key)
            cells.append(_num(None if v is None else scale * float(v), digits))
        table.add_row(str(row["map"]), str(row["planner"]), *cells)
    return table


def render_buckets(rows: Sequence[dict[str, Any]]) -> Table:
    """Success and gap per MovingAI bucket and planner (the difficulty curve as a table)."""
    table = Table(title="Per MovingAI bucket (difficulty: longer optimal paths in higher "
                  "buckets)", box=box.SIMPLE_HEAD, pad_edge=False)
    for name in ("Bucket", "Planner", "Pairs", "Success", "Gap median (%)", "Gap mean (%)"):
        table.add_column(name, justify="left" if name == "Planner" else "right", no_wrap=True)
    for r in sorted(rows, key=lambda r: (r["bucket"], str(r["planner"]))):
        gm, ga = r["gap_median"], r["gap_mean"]
        table.add_row(str(r["bucket"]), str(r["planner"]), str(r["pairs"]),
                      f"{r['successes']}/{r['runs']}", _num(None if gm is None else 100 * gm, 2),
                      _num(None if ga is None else 100 * ga, 2))
    return table


def print_tables(cells: Sequence[CellResult], spec: PlanSpec, seconds: float) -> None:
    from swarmpath.planners.summary import summarize

    console = Console()
    tables = []
    for cell in cells:
        reason = spec.optima.get(cell.scenario.name, (None, None))[1]
        tables.append(render_cell(cell, summarize(cell.runs)[0], reason,
                                  spec.octile.get(cell.scenario.name)))
    quality = render_quality(summarize([r for c in cells for r in c.runs]))
    if not console.is_terminal:  # pipes and files: never squeeze the numbers
        widest = max(Measurement.get(console, console.options.update(width=100_000), t).maximum
                     for t in [*tables, quality])
        console = Console(width=max(80, widest))
    for t in tables:
        console.print(t)
    console.print(
        f"{spec.runs} runs per planner x map, seed {spec.seed}; Distance = executed path length "
        "(Planned: the global planner's plan), Robot/obstacle-driven = colliding steps where the "
        "robot moved into the obstacle / a moving obstacle reached a still or retreating robot, "
        "Error = final distance to the goal, Elapsed time = planning wall time, CPU time = the "
        "planner's CPU time (other processes' load inflates wall time, not CPU time); the Mean "
        "row averages Distance and Gap over successful runs; "
        f"{seconds:.1f} s",
        highlight=False,
    )
    console.print(quality)
    why = render_failures(summarize([r for c in cells for r in c.runs]))
    if why is not None:
        console.print(why)
    if spec.buckets:
        from swarmpath.evidence.buckets import bucket_rows

        console.print(render_buckets(bucket_rows([r for c in cells for r in c.runs],
                                                 spec.buckets)))
    console.print(legend_text(["Collisions", "Gap (%)", "CPU time (s)",
                               *(["failure_classes"] if why is not None else []),
                               "clearance_mean",
                               "curvature_max", "cusps", "danger_share", "velocity_smoothness",
                               "angular_smoothness", "jerk", "costmap_cost_mean"]),
                  markup=False, highlight=False)
    if len(spec.planners) > 1:
        from swarmpath.cli import plan_stats
        from swarmpath.evidence.compare_maps import map_statistics

        runs = [r for c in cells for r in c.runs]
        tests = map_statistics(runs, spec.planners, spec.reference)
        console.print(plan_stats.render_comparison(tests, summarize(runs), spec.planners))
        console.print(plan_stats.render_counts(tests, spec.planners))
        for line in plan_stats.lines(tests):
            console.print(line, highlight=False)
