"""The figures of a study as PNG files (matplotlib, Agg): an adapter used by ``swarmpath bench
--plot``, ``swarmpath plan --plot`` and ``swarmpath results JOB --plot`` alike.

Every function takes plain run dicts, the shape ``swarmpath plan --json`` and the service's run
records share:

* benchmark runs: ``algorithm``, ``function``, ``dim``, ``best_fitness`` and ``curve`` (best so
  far after each iteration; a thinned curve keeps its first and last iteration);
* map runs: ``planner``, ``map``, ``run``, ``success``, ``reason``, ``collisions``, ``length``,
  ``gap``, ``seconds`` and ``path`` (rows ``[x, y, t]``).

Files are named by cell: ``curves_<function>_d<dim>.png`` and ``box_<function>_d<dim>.png`` per
function and dimension, ``<planner>_<map>.png`` (paths on the map) and ``box_<map>.png`` (length,
gap, planning time) per map. One colour per algorithm or planner, the same in every figure.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

#: Colours of successful paths, failed paths and the marks on failed runs.
PATH_RGB = "#1f77b4"
FAILED_RGB = "#d32f2f"
STATIC_RGB = "#9e9e9e"
MOVING_RGB = "#f4b183"
UNKNOWN_RGB = "#cfcfcf"
OCCUPIED_RGB = "#424242"


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def slug(text: str) -> str:
    """A file-name-safe version of a name (``OMPL-RRT*`` -> ``OMPL-RRT``)."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", str(text)).strip("_") or "x"


def palette(names: Sequence[str]) -> dict[str, Any]:
    """One colour per name, in the given order (tab10, then tab20 for more than ten)."""
    plt = _pyplot()
    cmap = plt.get_cmap("tab10" if len(names) <= 10 else "tab20")
    return {n: cmap(i % cmap.N) for i, n in enumerate(names)}


# --------------------------------------------------------------------------------- benchmark
def curve_matrix(curves: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
    """Curves of one cell as (iterations (m,), values (runs, m)).

    Curves of unequal length (thinned by the service to fit a message: evenly spaced samples,
    first and last kept) are put on the iterations of the longest by linear interpolation."""
    lengths = [len(c) for c in curves]
    m = max(lengths)
    x = np.arange(1, m + 1, dtype=float)
    rows = []
    for c in curves:
        arr = np.asarray(c, dtype=float)
        if len(arr) == m:
            rows.append(arr)
        else:
            rows.append(np.interp(x, np.linspace(1.0, m, len(arr)), arr))
    return x, np.vstack(rows)


def _y_scale(ax: Any, values: np.ndarray) -> str:
    """Log y when every finite value is positive, else linear (a map measure at 0)."""
    finite = values[np.isfinite(values)]
    if finite.size and finite.min() > 0:
        ax.set_yscale("log")
        return "log"
    return "linear"


def log_floor(values: np.ndarray) -> float:
    """Where a log axis draws the values at or below 0: the smallest positive finite value
    (as the dashboard does), or 1e-300 when there is none."""
    positive = values[np.isfinite(values) & (values > 0)]
    return float(positive.min()) if positive.size else 1e-300


def convergence_figure(title: str, curves: Mapping[str, Sequence[Sequence[float]]],
                       f_star: float = 0.0) -> Any:
    """Median best-so-far error f - f* against iteration with the interquartile band, one colour
    per algorithm, on a log y axis like the dashboard's: an error of 0 (the optimum reached) is
    drawn at the smallest positive error of the figure, so algorithms decades apart stay apart
    even when one of them reaches 0 (F9, F11)."""
    plt = _pyplot()
    colours = palette(list(curves))
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=100)
    bands = {}
    for name, runs in curves.items():
        if runs:
            x, values = curve_matrix(runs)
            bands[name] = (x, np.nanpercentile(np.maximum(values - f_star, 0.0), [25, 50, 75],
                                               axis=0))
    everything = [b.ravel() for _, b in bands.values()]
    floor = log_floor(np.concatenate(everything)) if everything else 1e-300
    reached = False
    for name, (x, (q1, med, q3)) in bands.items():
        reached = reached or bool(np.any(med <= 0))
        ax.fill_between(x, np.maximum(q1, floor), np.maximum(q3, floor), color=colours[name],
                        alpha=0.2, lw=0)
        ax.plot(x, np.maximum(med, floor), color=colours[name], lw=1.5,
                label=f"{name} (median of {len(curves[name])})")
    ax.set_yscale("log")
    ax.set_title(title)
    ax.set_xlabel("iteration")
    ax.set_ylabel("best-so-far f - f* (median, IQR band)"
                  + (f"\n0 drawn at {floor:.1e}" if reached else ""))
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def box_figure(title: str, panels: Sequence[tuple[str, Mapping[str, Sequence[float | None]]]],
               log: bool = False, empty: str | Sequence[str] = "no values") -> Any:
    """One box plot per panel (label, {name: values}): a box per name in its colour (None and
    non-finite values left out); names without values are labelled "(none)", a panel without any
    says ``empty`` (one text for every panel, or one per panel)."""
    says = [empty] * len(panels) if isinstance(empty, str) else list(empty)
    plt = _pyplot()
    names = list(dict.fromkeys(n for _, data in panels for n in data))
    colours = palette(names)
    fig, axes = plt.subplots(1, len(panels), figsize=(max(5.0, 0.6 * len(names) + 2) *
                                                      len(panels), 4.5), dpi=100, squeeze=False)
    for ax, (label, data), nothing in zip(axes[0], panels, says, strict=True):
        values = [np.asarray([v for v in data.get(n, ()) if v is not None and math.isfinite(v)],
                             dtype=float) for n in names]
        present = [i for i, v in enumerate(values) if v.size]
        if present:
            box = ax.boxplot([values[i] for i in present], positions=[i + 1 for i in present],
                             widths=0.6, patch_artist=True, showfliers=True,
                             medianprops={"color": "black"})
            for patch, i in zip(box["boxes"], present, strict=True):
                patch.set_facecolor(colours[names[i]])
                patch.set_alpha(0.6)
            if log:
                _y_scale(ax, np.concatenate([values[i] for i in present]))
        else:
            ax.text(0.5, 0.5, nothing, transform=ax.transAxes, ha="center", va="center",
                    wrap=True, color="#616161")
        ax.set_xlim(0.5, len(names) + 0.5)
        ax.set_xticks(range(1, len(names) + 1))
        ax.set_xticklabels([n if values[i].size else f"{n}\n(none)" for i, n in enumerate(names)],
                           rotation=30 if len(names) > 4 else 0, ha="right" if len(names) > 4
                           else "center", fontsize=8)
        ax.set_ylabel(label)
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def save_figure(fig: Any, path: Path) -> Path:
    """Write ``fig`` to ``path`` (PNG) and close it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fig.savefig(path)
    finally:
        _pyplot().close(fig)
    return path


_save = save_figure


def difficulty_figure(rows: Sequence[Mapping[str, Any]]) -> Any:
    """The difficulty curve of a MovingAI ``--scen`` study: per planner, the success rate and the
    median gap of its successful runs against the bucket
    (:func:`swarmpath.evidence.buckets.bucket_rows` rows)."""
    plt = _pyplot()
    planners = list(dict.fromkeys(str(r["planner"]) for r in rows))
    colours = palette(planners)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6.5), dpi=100, sharex=True)
    for p in planners:
        mine = [r for r in rows if r["planner"] == p]
        x = [int(r["bucket"]) for r in mine]
        top.plot(x, [100.0 * float(r["success_rate"]) for r in mine], marker="o",
                 color=colours[p], label=p)
        gaps = [(int(r["bucket"]), 100.0 * float(r["gap_median"])) for r in mine
                if r["gap_median"] is not None]
        if gaps:
            bottom.plot(*zip(*gaps, strict=True), marker="o", color=colours[p], label=p)
    top.set_ylabel("success (%)")
    top.set_ylim(-5, 105)
    top.set_title("Difficulty curve: MovingAI buckets (longer optimal paths to the right)")
    bottom.set_ylabel("median gap to the exact optimum (%)")
    bottom.set_xlabel("bucket (.scen column 1; octile optimum in [4 b, 4 b + 4) cells)")
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
    top.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _finite(v: Any) -> float | None:
    try:
        f = float(v)
    except (TypeError, ValueError):  # "inf"/"nan" strings of JSON exports parse; None does not
        return None
    return f if math.isfinite(f) else None


def write_benchmark_plots(runs: Iterable[Mapping[str, Any]], directory: Path) -> list[Path]:
    """Per function and dimension: the convergence curves and the box plot of the best error
    f - f* (log y where every error is positive)."""
    curves: dict[tuple[str, int], dict[str, list[Any]]] = {}
    best: dict[tuple[str, int], dict[str, list[float | None]]] = {}
    for r in runs:
        key = (str(r["function"]), int(r["dim"]))
        if r.get("curve"):
            curves.setdefault(key, {}).setdefault(str(r["algorithm"]), []).append(r["curve"])
        best.setdefault(key, {}).setdefault(str(r["algorithm"]), []).append(
            _finite(r.get("best_fitness")))
    directory.mkdir(parents=True, exist_ok=True)
    out = []
    from swarmpath.evidence.benchmark_stats import f_star

    for (function, dim), by_algo in best.items():
        name = f"{slug(function)}_d{dim}"
        fs = f_star(function, dim)
        if curves.get((function, dim)):
            fig = convergence_figure(f"{function}, {dim} dimensions", curves[(function, dim)], fs)
            out.append(_save(fig, directory / f"curves_{name}.png"))
        errors = {a: [None if v is None else v - fs for v in values]
                  for a, values in by_algo.items()}
        fig = box_figure(f"{function}, {dim} dimensions: best f - f* of each run",
                         [("best f - f*", errors)], log=True)
        out.append(_save(fig, directory / f"box_{name}.png"))
    return out


# -------------------------------------------------------------------------------------- maps
def map_box_figure(map_name: str, runs: Sequence[Mapping[str, Any]]) -> Any:
    """Length and gap of the successful runs, planning time of all runs, per planner."""
    length: dict[str, list[float | None]] = {}
    gap: dict[str, list[float | None]] = {}
    seconds: dict[str, list[float | None]] = {}
    for r in runs:
        p = str(r["planner"])
        for d in (length, gap, seconds):
            d.setdefault(p, [])
        if r.get("success"):
            length[p].append(_finite(r.get("length")))
            g = _finite(r.get("gap"))
            gap[p].append(None if g is None else 100.0 * g)
        seconds[p].append(_finite(r.get("seconds")))
    succeeded = any(r.get("success") for r in runs)
    no_success = "no successful run"
    return box_figure(f"{map_name}: runs per planner", [
        ("path length of successful runs (m)", length),
        ("gap to the exact optimum (%)", gap),
        ("planning time (s)", seconds),
    ], empty=[no_success, "no exact optimum:\nthe map moves" if succeeded else no_success,
              "no finished run"])


def collision_points(path: np.ndarray, world: Any, radius: float) -> np.ndarray:
    """The path rows that end a colliding step (the product's rule: clearance <= radius)."""
    from swarmpath.metrics import step_clearances
    from swarmpath.world.geometry import collides

    if len(path) < 2:
        return path[:0, :2]
    hit = collides(step_clearances(path, world.obstacles_at), radius)
    return path[1:][hit, :2]


def map_figure(planner: str, scenario: Any, runs: Sequence[Mapping[str, Any]],
               world_of: Callable[[int], Any]) -> Any:
    """The map, obstacles and their robot-radius-inflated outlines, moving obstacles at their
    initial positions with their tracks (run 1's world), start, goal, and every run's path:
    successful runs solid blue, failed runs dashed red with an x where they stopped and a dot on
    each colliding step. ``world_of(run)`` rebuilds the run's world (moving obstacles)."""
    plt = _pyplot()
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch, Polygon, Rectangle
    from shapely.geometry import Polygon as ShapelyPolygon

    s = scenario
    r = s.robot.radius
    w, h = s.size
    grid = getattr(s, "grid", None)
    # positions are drawn in the map's own frame (a nav2 map's YAML origin honoured)
    ox, oy = (float(v) for v in grid.origin) if grid is not None else (0.0, 0.0)
    fig, ax = plt.subplots(figsize=(7, 7.6), dpi=100)
    ax.add_patch(Rectangle((ox, oy), w, h, fill=False, ec="black", lw=1.0))
    if grid is not None:
        _grid_obstacles(ax, s, grid, (ox, oy))
    for ob in s.obstacles if grid is None else [o for o in s.obstacles if o.is_moving]:
        face = MOVING_RGB if ob.is_moving else STATIC_RGB
        if ob.shape == "circle":
            centre = (ob.center[0] + ox, ob.center[1] + oy)
            ax.add_patch(Circle(centre, ob.radius, fc=face, ec="none", alpha=0.9))
            ax.add_patch(Circle(centre, ob.radius + r, fill=False, ec="#616161", ls="--",
                                lw=0.8))
        else:
            pts = np.asarray(ob.points) + np.array([ox, oy])
            ax.add_patch(Polygon(pts, closed=True, fc=face, ec="none", alpha=0.9))
            xs, ys = ShapelyPolygon(pts).buffer(r, quad_segs=16).exterior.xy
            ax.plot(xs, ys, color="#616161", ls="--", lw=0.8)
    paths = {int(run.get("run", i)): np.asarray(run["path"], dtype=float).reshape(-1, 3)
             for i, run in enumerate(runs) if run.get("path")}
    shift = np.array([ox, oy, 0.0])
    t_end = max((p[-1, 2] for p in paths.values()), default=0.0)
    if s.is_dynamic and t_end > 0:
        world = world_of(min(paths) if paths else 0)
        times = np.linspace(0.0, t_end, 200)
        movers = [j for j, k in enumerate(world.set_order) if s.obstacles[k].is_moving]
        if movers:
            pos = np.array([world.obstacle_positions_at(float(t)) for t in times])
            for j in movers:
                ax.plot(pos[:, j, 0] + ox, pos[:, j, 1] + oy, color="#e07b39", alpha=0.35,
                        lw=1.0)
        if s.goal_motion is not None:
            g = np.array([world.goal_at(float(t)) for t in times])
            ax.plot(g[:, 0] + ox, g[:, 1] + oy, color="#2e7d32", alpha=0.5, lw=1.0, ls=":")
    any_collision = False
    for i, run in enumerate(runs):
        p = paths.get(int(run.get("run", i)))
        if p is None:
            continue
        scenario_frame = p
        p = p + shift
        if run.get("success"):
            ax.plot(p[:, 0], p[:, 1], lw=1.2, alpha=0.85, color=PATH_RGB)
            continue
        ax.plot(p[:, 0], p[:, 1], lw=1.2, ls="--", color=FAILED_RGB, alpha=0.85)
        ax.plot(p[-1, 0], p[-1, 1], marker="x", color=FAILED_RGB, ms=9, mew=2, ls="none")
        if int(run.get("collisions") or 0) > 0:
            hits = collision_points(scenario_frame, world_of(int(run.get("run", i))),
                                    r) + np.array([ox, oy])
            if len(hits):
                any_collision = True
                ax.plot(hits[:, 0], hits[:, 1], marker="o", color="black", mfc=FAILED_RGB,
                        ms=5, ls="none")
    ax.plot(s.start[0] + ox, s.start[1] + oy, marker="o", color="#1565c0", ms=8, ls="none")
    ax.plot(s.goal[0] + ox, s.goal[1] + oy, marker="*", color="#2e7d32", ms=13, ls="none")
    handles = [
        Line2D([], [], marker="o", color="#1565c0", ls="none", label="start"),
        Line2D([], [], marker="*", color="#2e7d32", ms=10, ls="none", label="goal (t=0)"),
        Patch(fc=STATIC_RGB if grid is None else OCCUPIED_RGB,
              label="static obstacle" if grid is None else "occupied (map)"),
        Line2D([], [], color="#616161", ls="--", lw=0.8, label=f"inflated by r={r:g} m"),
    ]
    if grid is not None and grid.unknown:
        handles.append(Patch(fc=UNKNOWN_RGB, label="unknown (an obstacle to the robot)"))
    if any(ob.is_moving for ob in s.obstacles):
        handles += [Patch(fc=MOVING_RGB, label="moving obstacle (t=0)"),
                    Line2D([], [], color="#e07b39", alpha=0.35, label="obstacle track (run 1)")]
    if s.goal_motion is not None:
        handles.append(Line2D([], [], color="#2e7d32", alpha=0.5, ls=":",
                              label="goal track (run 1)"))
    handles += [Line2D([], [], color=PATH_RGB, label="run (reached the goal)"),
                Line2D([], [], color=FAILED_RGB, ls="--", marker="x", mew=2,
                       label="run (failed; x: where it stopped)")]
    if any_collision:
        handles.append(Line2D([], [], marker="o", color="black", mfc=FAILED_RGB, ls="none",
                              label="colliding step"))
    ok = sum(1 for run in runs if run.get("success"))
    ax.set_title(f"{planner} on {s.name}: {ok}/{len(runs)} runs reached the goal")
    ax.set_xlim(ox - 0.02 * w, ox + 1.02 * w)
    ax.set_ylim(oy - 0.02 * h, oy + 1.02 * h)
    ax.set_aspect("equal")
    frame = f", {grid.frame} frame" if grid is not None else ""
    ax.set_xlabel(f"x (m{frame})")
    ax.set_ylabel(f"y (m{frame})")
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.subplots_adjust(bottom=0.16, top=0.94)
    return fig


def _grid_obstacles(ax: Any, scenario: Any, grid: Any, origin: tuple[float, float]) -> None:
    """An imported grid map's static obstacles as one shape (the importer's 64 x 64-cell tile
    cuts are no walls), their outline inflated by the robot radius, and the unknown cells grey
    on top (they are obstacles to the robot, but nobody mapped a wall there)."""
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path as MplPath
    from shapely import affinity
    from shapely.geometry import Polygon as ShapelyPolygon
    from shapely.ops import unary_union

    def patch(shape: Any, **style: Any) -> None:
        parts = getattr(shape, "geoms", [shape])
        verts: list[Any] = []
        codes: list[Any] = []
        for part in parts:
            if part.is_empty:
                continue
            for ring in (part.exterior, *part.interiors):
                xy = np.asarray(ring.coords)
                verts.extend(xy)
                codes.extend([MplPath.MOVETO] + [MplPath.LINETO] * (len(xy) - 2)
                             + [MplPath.CLOSEPOLY])
        if verts:
            ax.add_patch(PathPatch(MplPath(np.asarray(verts), codes), **style))

    def moved(shape: Any) -> Any:
        return affinity.translate(shape, *origin)

    static = [o for o in scenario.obstacles if not o.is_moving]
    shapes = [ShapelyPolygon(o.points) if o.shape == "polygon"
              else ShapelyPolygon(np.asarray(o.center) + o.radius * np.column_stack(
                  [np.cos(np.linspace(0, 2 * np.pi, 64)), np.sin(np.linspace(0, 2 * np.pi, 64))]))
              for o in static]
    union = unary_union(shapes) if shapes else None
    unknown = (unary_union([ShapelyPolygon(p) for p in grid.unknown_polygons()])
               if grid.unknown else None)
    if union is not None:
        mapped = union.difference(unknown) if unknown is not None else union
        patch(moved(mapped), fc=OCCUPIED_RGB, ec="none")
        outline = moved(union.buffer(scenario.robot.radius, quad_segs=8))
        for part in getattr(outline, "geoms", [outline]):
            for ring in (part.exterior, *part.interiors):
                xs, ys = ring.xy
                ax.plot(xs, ys, color="#616161", ls="--", lw=0.6)
    if unknown is not None:
        patch(moved(unknown), fc=UNKNOWN_RGB, ec="none")


def write_map_plots(
    runs: Iterable[Mapping[str, Any]],
    scenarios: Mapping[str, Any],
    world_of: Callable[[Any, int], Any],
    directory: Path,
) -> list[Path]:
    """Per planner x map the paths on the map, per map the box plots. ``scenarios``: map name
    -> Scenario; ``world_of(scenario, run)`` rebuilds a run's world."""
    cells: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for r in runs:
        cells.setdefault((str(r["planner"]), str(r["map"])), []).append(r)
    directory.mkdir(parents=True, exist_ok=True)
    out = []
    for (planner, name), cell_runs in cells.items():
        scenario = scenarios[name]
        fig = map_figure(planner, scenario, cell_runs, functools.partial(world_of, scenario))
        out.append(_save(fig, directory / f"{slug(planner)}_{slug(name)}.png"))
    by_map: dict[str, list[Mapping[str, Any]]] = {}
    for (_, name), cell_runs in cells.items():
        by_map.setdefault(name, []).extend(cell_runs)
    for name, map_runs in by_map.items():
        out.append(_save(map_box_figure(name, map_runs), directory / f"box_{slug(name)}.png"))
    return out
