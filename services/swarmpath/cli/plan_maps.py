"""Maps for ``swarmpath plan``: presets, scenario files, nav2 / MovingAI imports, start / goal
overrides, MovingAI scenario pairs, and the exact optimum of each map (with progress and the
reason when it is not available).

Plain functions raising :class:`~swarmpath.cli.core.InputError` (exit 2, naming the option);
the command in :mod:`swarmpath.cli.plan` only wires them.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmpath.cli.core import InputError, InputErrors

MAP_SUFFIXES = (".json", ".yaml", ".yml", ".map")
MAX_SCEN_PAIRS = 50  # pairs taken from a .scen without --scen-ids
SLOW = 1.0  # s: an import or optimum taking longer reports progress on stderr


@dataclass(frozen=True)
class MapOptions:
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None
    resolution: float | None = None  # MovingAI cell size (m)
    scen: Path | None = None
    scen_ids: tuple[int, ...] | None = None
    max_cells: int | None = None
    max_obstacles: int | None = None
    #: the frame of --start/--goal: "map" (a nav2 map's own frame, its YAML origin honoured; the
    #: scenario frame for every other map) or "scenario" (metres from the lower-left corner)
    frame: str = "map"


FRAMES = ("map", "scenario")


def parse_point(text: str | None, option: str) -> tuple[float, float] | None:
    """'X,Y' -> (x, y) in metres (the scenario frame: from the map's lower-left corner)."""
    if text is None:
        return None
    parts = [p.strip() for p in text.split(",")]
    try:
        x, y = (float(p) for p in parts)
    except ValueError:
        raise InputError(option, f"{text!r} is not X,Y (two numbers in metres)") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise InputError(option, f"{text!r}: coordinates must be finite")
    return (x, y)


def parse_ids(text: str | None) -> tuple[int, ...] | None:
    if text is None:
        return None
    try:
        ids = tuple(int(p) for p in text.split(","))  # an empty item ('0,,1') is an error too
    except ValueError:
        raise InputError("--scen-ids",
                         f"{text!r} is not a comma-separated list of integers") from None
    if not ids or min(ids) < 0:
        raise InputError("--scen-ids", f"{text!r}: give row numbers >= 0 (0 = first pair)")
    return ids


def make_options(start: str | None = None, goal: str | None = None,
                 resolution: float | None = None, scen: Path | None = None,
                 scen_ids: str | None = None, max_cells: int | None = None,
                 max_obstacles: int | None = None, frame: str = "map") -> MapOptions:
    if resolution is not None and not (math.isfinite(resolution) and resolution > 0):
        raise InputError("--resolution", f"{resolution} is not a positive cell size in metres")
    for option, value in (("--max-cells", max_cells), ("--max-obstacles", max_obstacles)):
        if value is not None and value < 1:
            raise InputError(option, f"{value} is not >= 1")
    if scen_ids is not None and scen is None:
        raise InputError("--scen-ids", "needs --scen FILE")
    if scen is not None and (start is not None or goal is not None):
        raise InputError("--scen", "takes start and goal from the file: drop --start/--goal")
    if frame not in FRAMES:
        raise InputError("--frame", f"must be one of {', '.join(FRAMES)}, got {frame!r}")
    return MapOptions(parse_point(start, "--start"), parse_point(goal, "--goal"), resolution,
                      scen, parse_ids(scen_ids), max_cells, max_obstacles, frame)


# ------------------------------------------------------------------------------------ loading
def _limits(opts: MapOptions) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if opts.max_cells is not None:
        out["max_cells"] = opts.max_cells
    if opts.max_obstacles is not None:
        out["max_obstacles"] = opts.max_obstacles
    return out


def _option_of(exc: Exception) -> str:
    text = str(exc)
    for option, words in (("--max-cells", "max_cells="), ("--max-obstacles", "max_obstacles="),
                          ("--resolution", "resolution=")):
        if words in text:
            return option
    return "--maps"


def _problem_option(field_: str, opts: MapOptions) -> str:
    """A scenario problem's option: --start / --goal when the user gave that point."""
    if field_ == "start" and opts.start is not None:
        return "--start"
    if field_ == "goal" and opts.goal is not None:
        return "--goal"
    return "--maps"


def _load_file(path: Path, opts: MapOptions,
               progress: Callable[[float], None] | None = None) -> tuple[Any, bool]:
    """The scenario, and whether it was imported (start / goal then went to the importer)."""
    import yaml

    from swarmpath.world.importers import load_movingai_map, load_ros_map
    from swarmpath.world.safe_yaml import load_yaml
    from swarmpath.world.scenario_io import load_scenario, scenario_from_dict

    ends = {"start": opts.start, "goal": opts.goal}
    suffix = path.suffix.lower()
    if suffix == ".map":
        return load_movingai_map(path, resolution=opts.resolution or 1.0, **ends,
                                 progress=progress, **_limits(opts)).scenario, True
    if suffix in (".yaml", ".yml"):
        try:
            doc = load_yaml(path.read_text(encoding="utf-8"))
        except yaml.YAMLError as exc:
            raise InputError("--maps", f"{path}: not valid YAML ({exc})") from None
        if isinstance(doc, dict) and "image" in doc:
            return load_ros_map(path, **ends, progress=progress, endpoints_frame=opts.frame,
                                **_limits(opts)).scenario, True
        if not isinstance(doc, dict):
            raise InputError("--maps", f"{path}: expected a YAML mapping")
        return scenario_from_dict(doc, str(path)), False
    return load_scenario(path), False


def _with_endpoints(scenario: Any, opts: MapOptions) -> Any:
    """A preset or scenario file with --start / --goal applied (and validated)."""
    from swarmpath.world.scenario import scenario_problems

    if opts.start is None and opts.goal is None:
        return scenario
    start, goal = opts.start, opts.goal
    if opts.frame == "map" and scenario.grid is not None:  # a scenario saved from a nav2 map
        start, goal = (None if p is None else tuple(scenario.grid.to_scenario_frame(p).tolist())
                       for p in (start, goal))
    s = dataclasses.replace(scenario, start=start or scenario.start,
                            goal=goal or scenario.goal)
    for field_, message in scenario_problems(s):
        if field_ in ("start", "goal"):
            raise InputError(f"--{field_}", f"on {scenario.name}: {message}")
    return s


def _frame_hint(field_: str, opts: MapOptions, nav2: bool) -> str:
    """On a nav2 map the user's map-frame --start/--goal is reported in the scenario frame."""
    if nav2 and _problem_option(field_, opts) in ("--start", "--goal"):
        return (" (scenario-frame coordinates: the map-frame point given minus the YAML "
                "origin)")
    return ""


def load_map(item: str, opts: MapOptions | None = None,
             note: Callable[[str], None] | None = None) -> Any:
    """A preset by name, or a scenario / nav2 / MovingAI file; raises InputError naming the
    option at fault (--maps, --start, --goal, --max-cells, --max-obstacles)."""
    from swarmpath.world import get_map, list_maps

    opts = opts or MapOptions()
    presets = list_maps()
    by_lower = {m.lower(): m for m in presets}
    if item in presets or item.lower() in by_lower:
        return _with_endpoints(get_map(item if item in presets else by_lower[item.lower()]), opts)
    path = Path(item)
    if not path.is_file():
        hint = "no such file" if path.suffix.lower() in MAP_SUFFIXES else "unknown map"
        raise InputError(
            "--maps",
            f"{hint} {item!r}; presets: {', '.join(presets)}; or a path to a scenario "
            "JSON/YAML, nav2 map YAML or MovingAI .map file",
        )
    started = time.perf_counter()
    last = [started]

    def progress(fraction: float) -> None:
        now = time.perf_counter()
        if note is not None and now - started > SLOW and now - last[0] > SLOW:
            last[0] = now
            note(f"importing {item}: {100 * fraction:.0f}% of the grid turned into polygons, "
                 f"{now - started:.1f} s")

    try:
        scenario, imported = _load_file(path, opts, progress)
    except InputError:
        raise
    except (ValueError, KeyError, OSError) as exc:  # ScenarioError, MapImportError, ...
        problems = getattr(exc, "problems", None)
        if problems:  # a scenario: one line per problem
            nav2 = path.suffix.lower() in (".yaml", ".yml") and opts.frame == "map"
            raise InputErrors([(_problem_option(p, opts), (f"{item}: {p}: {m}" if p
                                else f"{item}: {m}") + _frame_hint(p, opts, nav2))
                               for p, m in problems]) from None
        text = str(exc)  # the importers' messages start with the file already
        raise InputError(_option_of(exc), text if text.startswith(item) else f"{item}: {text}"
                         ) from None
    if note is not None and time.perf_counter() - started > SLOW:
        note(f"imported {item} in {time.perf_counter() - started:.1f} s "
             f"({len(scenario.obstacles)} obstacles)")
    return scenario if imported else _with_endpoints(scenario, opts)


def scen_pairs(path: Path, ids: Sequence[int] | None,
               shape: tuple[int, int] | None = None) -> list[tuple[int, tuple[int, int],
                                                              tuple[int, int], float, int]]:
    """(row, start cell, goal cell, octile length, bucket) of the chosen rows of a MovingAI
    .scen (:mod:`swarmpath.world.movingai_scen`); with ``shape`` (the map's width, height in
    cells) a row stated for another size is refused."""
    from swarmpath.world.movingai_scen import ScenChoiceError, ScenError, choose_rows, parse_scen

    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError("--scen", f"cannot read {path}: {exc}") from None
    try:
        rows = parse_scen(text, str(path), shape)
    except ScenError as exc:
        raise InputError("--scen", str(exc)) from None
    if ids is None and len(rows) > MAX_SCEN_PAIRS:
        raise InputError("--scen-ids", f"{path} has {len(rows)} pairs; choose some with "
                         f"--scen-ids (0 = first), at most {MAX_SCEN_PAIRS} are taken "
                         "without it")
    try:
        chosen = choose_rows(rows, ids)
    except ScenChoiceError as exc:
        raise InputError("--scen-ids", f"{exc} ({path})") from None
    return [(r.row, r.start, r.goal, r.octile, r.bucket) for r in chosen]


@dataclass
class ResolvedMaps:
    """The maps of --maps (one scenario per --scen pair), with distinct names; for the maps made
    from --scen pairs their octile optimum (m) and MovingAI bucket, by name."""

    maps: list[Any]
    octile: dict[str, float]
    buckets: dict[str, int]


def resolve_maps(spec: str, opts: MapOptions | None = None,
                 note: Callable[[str], None] | None = None) -> ResolvedMaps:
    """Every map of --maps (expanded into one scenario per --scen pair): :class:`ResolvedMaps`."""
    from swarmpath.world.importers import movingai_cell_center

    opts = opts or MapOptions()
    items = [p.strip() for p in spec.split(",") if p.strip()]
    if opts.resolution is not None and not any(i.lower().endswith(".map") for i in items):
        raise InputError("--resolution", "applies to MovingAI .map files only (nav2 maps give "
                         "theirs in the YAML)")
    maps: list[Any] = []
    octile: dict[str, float] = {}
    buckets: dict[str, int] = {}
    if opts.scen is not None:
        grids = [i for i in items if i.lower().endswith(".map")]
        if len(grids) != 1:
            raise InputError("--scen", "needs exactly one MovingAI .map in --maps")
        base = load_map(grids[0], opts, note)
        res = opts.resolution or 1.0
        height = round(base.size[1] / res)
        pairs = scen_pairs(opts.scen, opts.scen_ids, (round(base.size[0] / res), height))
        for i, s_cell, g_cell, length, bucket in pairs:
            s = dataclasses.replace(
                base, name=f"{base.name}#{i}",
                start=movingai_cell_center(*s_cell, height, res),
                goal=movingai_cell_center(*g_cell, height, res),
            )
            problems = [m for f, m in s.problems() if f in ("start", "goal")]
            if problems:
                raise InputError("--scen", f"pair {i}: {'; '.join(problems)}")
            maps.append(s)
            octile[s.name] = length * res
            buckets[s.name] = bucket
        items = [i for i in items if i != grids[0]]
    for item in items:
        maps.append(load_map(item, opts, note))
    if note is not None:
        from swarmpath.world.trajectories import trajectory_warnings

        for scenario in maps:
            for field_, message in trajectory_warnings(scenario):
                note(f"warning: {scenario.name}: {field_}: {message}")
    names: set[str] = set()
    out = []
    for scenario in maps:
        name, k = scenario.name, 2
        while name in names:  # two files with the same scenario name: keep them apart
            name, k = f"{scenario.name}#{k}", k + 1
        if name != scenario.name:
            for by_name in (octile, buckets):
                if scenario.name in by_name:
                    by_name[name] = by_name[scenario.name]  # type: ignore[index]
            scenario = dataclasses.replace(scenario, name=name)
        names.add(name)
        out.append(scenario)
    if not out:
        raise InputError("--maps", "no map given")
    return ResolvedMaps(out, octile, buckets)


# ------------------------------------------------------------------------------------ optimum
def compute_optima(maps: Sequence[Any], budget: float | None,
                   note: Callable[[str], None]) -> dict[str, tuple[float | None, str | None]]:
    """The exact optimum of every map (cached for the episodes of this process), with progress
    through ``note`` once a map takes over a second, and the reason when there is none."""
    from swarmpath.planners.episode import optimum_of

    out: dict[str, tuple[float | None, str | None]] = {}
    for s in maps:
        started = time.perf_counter()
        last = [started]

        def progress(fraction: float, name: str = s.name, t0: float = started,
                     last: list[float] = last) -> None:
            now = time.perf_counter()
            if now - t0 > SLOW and now - last[0] > SLOW:
                last[0] = now
                note(f"exact optimum of {name}: {100 * fraction:.0f}% of the disk pairs, "
                     f"{now - t0:.1f} s")

        value, reason = optimum_of(s, budget, progress)
        took = time.perf_counter() - started
        if reason is not None and not s.is_dynamic:
            hint = " (--optimum-budget S)" if "time budget" in reason else ""
            note(f"no exact optimum on {s.name}: {reason}{hint}")
        elif took > SLOW:
            note(f"exact optimum of {s.name}: {value:.4f} m in {took:.1f} s")
        out[s.name] = (value, reason)
    return out
