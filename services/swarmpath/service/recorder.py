"""One MCAP file per job, written while the job runs, finalized with summary and indexes at its end.

Files live in ``<data_dir>/mcap/``: ``<job>.mcap.part`` while the job runs, renamed (atomically) to
``<job>.mcap`` once :meth:`JobRecorder.finish` wrote the summary section. MCAP has no append mode.

Writing: chunked (1 MiB, zstd), message indexes and chunk indexes on, chunk CRCs and the data
section CRC on, statistics and summary offsets on. :meth:`JobRecorder.flush_if_due` closes the open
chunk when at least ``flush_interval`` (1 s) passed since the last flush; it runs after every
message and should also be called from a ~1 s timer (:meth:`Recorders.tick`) so that an idle job
is flushed too. A process kill therefore loses at most about a second of messages from the .part
file, and those are recoverable anyway, see below.

Recovery: the SQLite store is the source of truth; the MCAP is a view of it. When the coordinator
(re)opens a job's recorder it writes a fresh ``.part`` from the store's accepted results
(:meth:`Recorders.open`), then appends new results live. A recorder remembers which run ids it
wrote and skips repeats, so every accepted result is in the file exactly once, whether it came
from the rebuild, from the live path, or from both. :func:`salvage_messages` reads what a killed
process left in a ``.part`` (the flushed chunks) for inspection.

Layout (times in ns since the Unix epoch; ``base`` = the job's creation time):

=============================  ==============================  =================================
topic                          schema (jsonschema, JSON)       messages
=============================  ==============================  =================================
``/results``                   swarmpath.BenchmarkRunResult /  one per finished run, at its
                               swarmpath.MapRunResult          acceptance time
``/curves``                    swarmpath.ConvergenceCurve      benchmark: one per run, the whole
                                                               curve as ``best_fitness[]``
``/tf``                        foxglove.FrameTransform         map: once per map, at base:
                                                               frame ``map/<map>`` in ``world``
``/map/<map>/occupancy``       foxglove.Grid                   map: once per map, at base
                                                               (static obstacles only)
``/map/<map>/obstacles``       foxglove.SceneUpdate            map: once per map, at base
                                                               (static obstacles, start, goal)
``/scene/<planner>/<map>``     foxglove.SceneUpdate            map: per run, robot (and moving
                                                               goal and obstacles) at base + t,
                                                               the whole path at the end
``/paths/<planner>/<map>``     foxglove.PosesInFrame           map: one per run, at base + t_end
=============================  ==============================  =================================

Frames: each map has its own frame ``map/<map>`` (origin at the map's (0, 0)); ``/tf`` places the
job's maps side by side along x in frame ``world`` (spec order, ``MAP_GAP`` apart), so two maps
never overlap. Scene entities of a run are ``run-<run>/robot``, ``/goal``, ``/obstacles`` (moving
obstacles where they are at that time) and ``/path``, with the run's identity in their metadata.

Metadata records: ``swarmpath.job`` (job id, kind, spec JSON, swarmpath version, layout version)
first, one ``swarmpath.run`` per map run (run, run_id, cell, planner, map, success, reason,
collisions, length, its scene and path topics, entity prefix and frame), and
``swarmpath.summary`` (final state and the summary table JSON) at the end. The Foxglove layout
shipped beside this module (:data:`swarmpath.service.foxglove.LAYOUT_FILE`; ``swarmpath download
JOB --layout`` writes one with the file's topics) shows the scene in 3D and plots ``/curves``.
"""

from __future__ import annotations

import json
import logging
import math
import os
import re
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any, BinaryIO

import pydantic_core
from mcap.exceptions import McapError
from mcap.reader import NonSeekingReader
from mcap.writer import CompressionType, IndexType, Writer

from swarmpath.service import foxglove as fg
from swarmpath.service.protocol import PROTOCOL_VERSION

log = logging.getLogger(__name__)

LAYOUT_VERSION = 2  # 2: a frame per map (/tf), static occupancy, swarmpath.run metadata
FLUSH_INTERVAL = 1.0
CHUNK_SIZE = 1024 * 1024
MAX_SCENE_FRAMES = 200  # per run: path samples drawn as robot positions
GRID_MAX_CELLS = 400  # per side of the occupancy raster
MAP_GAP = 2.0  # m between two maps laid side by side in the world frame
WORLD_FRAME = "world"
ROBOT_HEIGHT = 0.2
OBSTACLE_HEIGHT = 0.5
_BIG = 1.7976931348623157e308
OBSTACLE_RGBA = fg.color(0.45, 0.45, 0.5, 0.9)
ROBOT_RGBA = fg.color(0.95, 0.35, 0.1, 0.9)
START_RGBA = fg.color(0.1, 0.4, 1.0)
GOAL_RGBA = fg.color(0.1, 0.8, 0.2)


def map_frame(name: str) -> str:
    """The frame of one map (its origin at the map's (0, 0)); ``/tf`` places it in ``world``."""
    return f"map/{_topic_name(name)}"


def _run_about(record: dict[str, Any], planner: str, map_: str) -> dict[str, str]:
    """What identifies a map run, as strings (scene entity metadata, the run's metadata)."""
    metrics = record.get("metrics") or {}
    return {"run": str(int(record["run"])), "run_id": str(record["run_id"]), "planner": planner,
            "map": map_, "success": str(bool(metrics.get("success"))).lower(),
            "reason": str(metrics.get("reason") or record.get("failure") or "")}


def _marker(x: float, y: float, rgba: dict[str, float], size: float = 0.3) -> dict[str, Any]:
    return {"pose": fg.pose(x, y, size / 3), "size": fg.vec3(size, size, size), "color": rgba}

# -------------------------------------------------------------------------- own JSON schemas
_IDENTITY = {
    "job_id": {"type": "string"},
    "run_id": {"type": "integer", "description": "cell_index * runs_per_cell + run"},
    "cell": {"type": "string"},
    "run": {"type": "integer", "description": "run index within the cell"},
    "seed": {"type": "integer", "description": "job seed"},
}

# who ran the run and how it ended: the same fields on both kinds of result
_OUTCOME: dict[str, Any] = {
    "worker": {"type": "string"},
    "status": {"type": "string", "description": "ok or failed"},
    "failure": {"type": "string", "description": "exception text; empty unless failed"},
    "seconds": {"type": "number"},
}

BENCHMARK_RESULT_SCHEMA: dict[str, Any] = {
    "title": "swarmpath.BenchmarkRunResult",
    "description": "One finished benchmark run (non-finite metrics are left out)",
    "type": "object",
    "properties": {
        **_IDENTITY,
        "algorithm": {"type": "string"},
        "function": {"type": "string"},
        "dim": {"type": "integer"},
        **_OUTCOME,
        "best_fitness": {"type": "number"},
        "evaluations": {"type": "integer"},
    },
}

MAP_RESULT_SCHEMA: dict[str, Any] = {
    "title": "swarmpath.MapRunResult",
    "description": "One finished map run: the fields of `swarmpath plan --json` except the path",
    "type": "object",
    "properties": {
        **_IDENTITY,
        "planner": {"type": "string"},
        "map": {"type": "string"},
        **_OUTCOME,
        "success": {"type": "boolean"},
        "collisions": {"type": "integer"},
        "robot_driven_contacts": {"type": "integer", "description": "collisions: robot moved in"},
        "obstacle_driven_contacts": {"type": "integer",
                                     "description": "collisions: a moving obstacle reached it"},
        "planned_length": {"type": "number", "description": "a global planner's planned length"},
        "length": {"type": "number"},
        "error": {"type": "number", "description": "final distance to the goal"},
        "smoothness": {"type": "number"},
        "min_clearance": {"type": "number"},
        "steps": {"type": "integer"},
        "iterations": {"type": "integer"},
        "optimum": {"type": "number"},
        "gap": {"type": "number"},
    },
}

CURVE_SCHEMA: dict[str, Any] = {
    "title": "swarmpath.ConvergenceCurve",
    "description": "Best fitness after each iteration of one run (Plot: best_fitness[:] by index)",
    "type": "object",
    "properties": {
        **_IDENTITY,
        "algorithm": {"type": "string"},
        "function": {"type": "string"},
        "dim": {"type": "integer"},
        "iterations": {"type": "integer"},
        "best_fitness": {"type": "array", "items": {"type": "number"}},
    },
}

OWN_SCHEMAS = {
    s["title"]: s for s in (BENCHMARK_RESULT_SCHEMA, MAP_RESULT_SCHEMA, CURVE_SCHEMA)
}


# ------------------------------------------------------------------------------------ helpers
def mcap_dir(data_dir: Path | str) -> Path:
    return Path(data_dir) / "mcap"


def final_path(data_dir: Path | str, job_id: str) -> Path:
    return mcap_dir(data_dir) / f"{job_id}.mcap"


def part_path(data_dir: Path | str, job_id: str) -> Path:
    return mcap_dir(data_dir) / f"{job_id}.mcap.part"


def _ns(seconds: float) -> int:
    return max(0, round(seconds * 1e9))


def _topic_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


def _finite_scalar(v: Any) -> bool:
    if isinstance(v, bool | str | int):
        return True
    return isinstance(v, float) and math.isfinite(v)


def _clamp(v: float) -> float:
    """Curve values for Foxglove's JSON parser (no Infinity/NaN): clamp to the float range."""
    if math.isfinite(v):
        return v
    return -_BIG if v < 0 else _BIG


def clamped(values: Any) -> list[float]:
    """A curve as a list of finite floats (non-finite values clamped, see :func:`_clamp`);
    vectorized: a 500-value curve costs microseconds, not a Python loop per value."""
    import numpy as np

    arr = np.asarray(values, dtype=float)
    bad = ~np.isfinite(arr)
    if bad.any():
        arr = np.where(bad, np.where(arr < 0, -_BIG, _BIG), arr)
    return arr.tolist()  # type: ignore[no-any-return]


def _json(obj: Any) -> bytes:
    return json.dumps(obj, separators=(",", ":"), allow_nan=False).encode()


def _version() -> str:
    try:
        from swarmpath import __version__
    except ImportError:  # pragma: no cover
        return "unknown"
    return __version__


# ------------------------------------------------------------------------------ scenario shapes
def scenario_for(cell_spec: dict[str, Any]) -> Any | None:
    """The :class:`swarmpath.world.scenario.Scenario` of a map cell (inline JSON object or preset
    name); None when the world layer is unavailable or the scenario is invalid (the scene topics
    are then left out, /results is still written)."""
    try:
        from swarmpath.world.presets import get_map
        from swarmpath.world.scenario_io import scenario_from_dict
    except ImportError as exc:
        log.warning("no scenario geometry (world layer unavailable): %s", exc)
        return None
    inline = cell_spec.get("scenario")
    try:
        if isinstance(inline, dict):
            return scenario_from_dict(inline)
        return get_map(str(cell_spec.get("map")))
    except (KeyError, ValueError, TypeError) as exc:
        log.warning("no scenario geometry for map %r: %s", cell_spec.get("map"), exc)
        return None


def world_for(scenario: Any, seed: int, run: int) -> Any:
    """The world of run ``run``: the same moving obstacles and goal the simulator saw (the world
    draws from stream (seed, run, SIMULATION), see swarmpath.planners.episode)."""
    from swarmpath.optimizers.streams import SIMULATION, run_generator

    return scenario.instantiate(run_generator(seed, run, SIMULATION))


def occupancy(scenario: Any) -> tuple[bytes, int, float]:
    """The scenario's static obstacles rasterized by the world layer (moving ones are drawn per
    run where they are, never baked into the grid): uint8 0 free / 100 occupied, row-major from
    y = 0 up. Returns (data, columns, resolution)."""
    import dataclasses

    import numpy as np

    from swarmpath.world.raster import rasterize_scenario

    width, height = (float(v) for v in scenario.size)
    static = dataclasses.replace(
        scenario, obstacles=tuple(o for o in scenario.obstacles if not o.is_moving))
    grid = rasterize_scenario(static, max(width, height) / GRID_MAX_CELLS)
    data = np.where(grid.data < 0, 50, grid.data).astype(np.uint8)  # unknown -> 50
    return data.tobytes(), grid.shape[1], grid.resolution


def _obstacle_entity(ns: int, entity_id: str, obstacles: Any, frame: str) -> dict[str, Any]:
    """An ObstacleSet as one entity: cylinders for circles, line loops for polygons."""
    return fg.entity(
        ns, entity_id, frame,
        cylinders=[fg.cylinder(cx, cy, r, OBSTACLE_HEIGHT, OBSTACLE_RGBA)
                   for cx, cy, r in obstacles.circles],
        lines=[fg.line([(float(x), float(y)) for x, y in poly], OBSTACLE_RGBA, 0.04, loop=True)
               for poly in obstacles.polygons],
    )


# --------------------------------------------------------------------------------- recorder
class JobRecorder:
    """Writes one job's MCAP (see the module docstring). Not thread-safe by itself: use
    :class:`Recorders`, which serializes access."""

    def __init__(
        self,
        path: Path | str,
        job_id: str,
        kind: str,
        spec: dict[str, Any],
        created: float,
        *,
        flush_interval: float = FLUSH_INTERVAL,
        chunk_size: int = CHUNK_SIZE,
        compression: CompressionType = CompressionType.ZSTD,
        clock: Callable[[], float] = time.monotonic,
    ):
        self.final = Path(path)
        self.part = self.final.with_name(self.final.name + ".part")
        self.job_id = job_id
        self.kind = kind
        self.spec = spec
        self.base_ns = _ns(created)
        self.flush_interval = flush_interval
        self.clock = clock
        self.written: set[int] = set()
        self._scenarios: dict[str, Any] = {}  # map name -> Scenario (None: no geometry)
        self._offsets: dict[str, float] | None = None  # map name -> x of its frame in "world"
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._dirty = False
        self._last_flush = clock()
        self.final.parent.mkdir(parents=True, exist_ok=True)
        self._file: BinaryIO = open(self.part, "wb")  # closed by finish/close
        self._writer = Writer(
            self._file,
            chunk_size=chunk_size,
            compression=compression,
            index_types=IndexType.ALL,
            repeat_channels=True,
            repeat_schemas=True,
            use_chunking=True,
            use_statistics=True,
            use_summary_offsets=True,
            enable_crcs=True,
            enable_data_crcs=True,
        )
        self._writer.start(profile="", library=f"swarmpath {_version()} (mcap-python)")
        self._writer.add_metadata(
            "swarmpath.job",
            {
                "job_id": job_id,
                "kind": kind,
                "spec": json.dumps(spec, separators=(",", ":")),
                "swarmpath_version": _version(),
                "protocol_version": str(PROTOCOL_VERSION),
                "layout_version": str(LAYOUT_VERSION),
                "created_ns": str(self.base_ns),
            },
        )
        self._file.flush()
        self.closed = False

    # ----------------------------------------------------------------------------- channels
    def _channel(self, topic: str, schema_name: str) -> int:
        cid = self._channels.get(topic)
        if cid is None:
            sid = self._schemas.get(schema_name)
            if sid is None:
                builder = fg.SCHEMA_BUILDERS.get(schema_name)
                body = builder() if builder is not None else OWN_SCHEMAS[schema_name]
                sid = self._writer.register_schema(
                    name=schema_name, encoding="jsonschema", data=_json(body)
                )
                self._schemas[schema_name] = sid
            cid = self._writer.register_channel(
                topic=topic, message_encoding="json", schema_id=sid
            )
            self._channels[topic] = cid
        return cid

    def _put(
        self, topic: str, schema_name: str, log_ns: int, message: dict[str, Any] | bytes
    ) -> None:
        self._writer.add_message(
            self._channel(topic, schema_name), log_time=log_ns, publish_time=log_ns,
            data=message if isinstance(message, bytes) else _json(message),
        )
        self._dirty = True

    # ---------------------------------------------------------------------------------- runs
    def add(self, record: dict[str, Any]) -> bool:
        """Write one finished run (a record from :meth:`Store.run_record`/``iter_run_records``).
        Returns False when that run id was already written (nothing is written twice)."""
        if self.closed:
            raise RuntimeError(f"recorder of job {self.job_id} is closed")
        run_id = int(record["run_id"])
        if run_id in self.written:
            return False
        self.written.add(run_id)
        if record.get("kind", self.kind) == "benchmark":
            self._benchmark_run(record)
        else:
            self._map_run(record)
        self.flush_if_due()
        return True

    def _result_message(self, record: dict[str, Any], identity: dict[str, Any]) -> dict[str, Any]:
        msg: dict[str, Any] = {
            "job_id": record["job_id"],
            "run_id": int(record["run_id"]),
            "cell": record["cell"],
            "run": int(record["run"]),
            "seed": int(record["seed"]),
            **identity,
            "worker": record.get("worker") or "",
            "status": record.get("status") or "ok",
            "failure": record.get("failure") or "",
            "seconds": float(record.get("seconds") or 0.0),
        }
        for key, value in (record.get("metrics") or {}).items():
            if key not in msg and _finite_scalar(value):
                msg[key] = value
        return msg

    def _benchmark_run(self, record: dict[str, Any]) -> None:
        spec = record["spec"]
        identity = {"algorithm": spec["algorithm"], "function": spec["function"],
                    "dim": int(spec["dim"])}
        ns = _ns(record["created"])
        self._put("/results", "swarmpath.BenchmarkRunResult", ns,
                  self._result_message(record, identity))
        curve = record.get("curve")
        if curve is not None and len(curve):
            self._put("/curves", "swarmpath.ConvergenceCurve", ns, pydantic_core.to_json({
                "job_id": record["job_id"], "run_id": int(record["run_id"]),
                "cell": record["cell"], "run": int(record["run"]), "seed": int(record["seed"]),
                **identity, "iterations": len(curve), "best_fitness": clamped(curve),
            }))

    def _map_run(self, record: dict[str, Any]) -> None:
        spec = record["spec"]
        planner, map_ = spec["planner"], spec["map"]
        self._put("/results", "swarmpath.MapRunResult", _ns(record["created"]),
                  self._result_message(record, {"planner": planner, "map": map_}))
        if map_ not in self._scenarios:
            self._scenarios[map_] = scenario = scenario_for(spec)
            if scenario is not None:
                self._draw_map(map_, scenario)
        scenario = self._scenarios[map_]
        topic = f"{_topic_name(planner)}/{_topic_name(map_)}"
        metrics = record.get("metrics") or {}
        self._writer.add_metadata("swarmpath.run", {
            **_run_about(record, planner, map_), "cell": str(record["cell"]),
            "seed": str(record["seed"]), "scene_topic": f"/scene/{topic}",
            "path_topic": f"/paths/{topic}", "entity_prefix": f"run-{int(record['run'])}/",
            "frame_id": map_frame(map_), "collisions": str(metrics.get("collisions", "")),
            "length": str(metrics.get("length", "")),
        })
        path = record.get("path") or []
        if path:
            self._draw_run(record, planner, map_, path, scenario)

    def _map_offset(self, name: str, width: float) -> float:
        """x of map ``name``'s frame in ``world``: the job's maps side by side in the spec's
        order with a gap, so that they never overlap (a map not in the spec goes last)."""
        if self._offsets is None:
            self._offsets, x = {}, 0.0
            for entry in self.spec.get("maps") or []:
                inline = entry if isinstance(entry, dict) else None
                key = str(inline.get("name")) if inline else str(entry)
                sc = self._scenarios.get(key) or scenario_for({"map": key, "scenario": inline})
                self._offsets[key] = x
                x += (float(sc.size[0]) if sc is not None else 0.0) + MAP_GAP
            self._offsets[""] = x  # where the next unknown map goes
        if name not in self._offsets:
            self._offsets[name] = self._offsets[""]
            self._offsets[""] += width + MAP_GAP
        return self._offsets[name]

    def _draw_map(self, name: str, scenario: Any) -> None:
        ns = self.base_ns
        topic = _topic_name(name)
        frame = map_frame(name)
        w, h = (float(v) for v in scenario.size)
        self._put("/tf", "foxglove.FrameTransform", ns,
                  fg.frame_transform(ns, WORLD_FRAME, frame, self._map_offset(name, w)))
        data, cols, res = occupancy(scenario)
        grid = fg.grid_uint8(ns, data, cols, res, frame_id=frame)
        self._put(f"/map/{topic}/occupancy", "foxglove.Grid", ns, grid)
        entities = [
            _obstacle_entity(ns, "obstacles", scenario.static_obstacles(), frame),
            fg.entity(ns, "world", frame, lines=[fg.line(
                [(0, 0), (w, 0), (w, h), (0, h)], fg.color(0.2, 0.2, 0.2, 1), 0.03, loop=True)]),
        ]
        for label, point, rgba in (("start", scenario.start, START_RGBA),
                                   ("goal", scenario.goal, GOAL_RGBA)):
            x, y = float(point[0]), float(point[1])
            entities.append(fg.entity(ns, label, frame, spheres=[_marker(x, y, rgba)],
                                      texts=[fg.text(x, y, 0.5, label, rgba, 0.3)]))
        self._put(f"/map/{topic}/obstacles", "foxglove.SceneUpdate", ns, fg.scene_update(entities))

    def _draw_run(
        self,
        record: dict[str, Any],
        planner: str,
        map_: str,
        path: list[list[float]],
        scenario: Any | None,
    ) -> None:
        run = int(record["run"])
        topic = f"{_topic_name(planner)}/{_topic_name(map_)}"
        prefix = f"run-{run}"
        frame = map_frame(map_)
        about = _run_about(record, planner, map_)
        radius = float(scenario.robot.radius) if scenario is not None else 0.1
        world = None
        if scenario is not None and scenario.is_dynamic:
            world = world_for(scenario, int(record["seed"]), run)
        n = len(path)
        k = min(n, MAX_SCENE_FRAMES)
        picks = sorted({round(i * (n - 1) / max(1, k - 1)) for i in range(k)})
        for i in picks:
            x, y, t = (float(v) for v in path[i][:3])
            ns = self.base_ns + _ns(t)
            robot = fg.cylinder(x, y, radius, ROBOT_HEIGHT, ROBOT_RGBA)
            robot["pose"] = fg.pose(x, y, ROBOT_HEIGHT / 2, self._heading(path, i))
            ents = [fg.entity(ns, f"{prefix}/robot", frame, cylinders=[robot], metadata=about)]
            if world is not None:
                gx, gy = (float(v) for v in world.goal_at(max(t, 0.0)))
                ents.append(fg.entity(ns, f"{prefix}/goal", frame,
                                      spheres=[_marker(gx, gy, GOAL_RGBA)], metadata=about))
                movers = world.obstacles_at(max(t, 0.0))
                ents.append(_obstacle_entity(ns, f"{prefix}/obstacles", movers, frame))
            self._put(f"/scene/{topic}", "foxglove.SceneUpdate", ns, fg.scene_update(ents))
        end_ns = self.base_ns + _ns(float(path[-1][2]))
        xy = [(float(p[0]), float(p[1])) for p in path]
        self._put(f"/scene/{topic}", "foxglove.SceneUpdate", end_ns, fg.scene_update([
            fg.entity(end_ns, f"{prefix}/path", frame,
                      lines=[fg.line(xy, ROBOT_RGBA, 0.03, z=0.02)], metadata=about)]))
        poses = [fg.pose(float(p[0]), float(p[1]), 0.0, self._heading(path, i))
                 for i, p in enumerate(path)]
        self._put(f"/paths/{topic}", "foxglove.PosesInFrame", end_ns,
                  fg.poses_in_frame(end_ns, poses, frame_id=frame))

    @staticmethod
    def _heading(path: list[list[float]], i: int) -> float:
        j, k = (i, i + 1) if i + 1 < len(path) else (i - 1, i)
        if j < 0:
            return 0.0
        dx, dy = path[k][0] - path[j][0], path[k][1] - path[j][1]
        return math.atan2(dy, dx) if (dx or dy) else 0.0

    # ------------------------------------------------------------------------------ flushing
    def flush(self) -> None:
        """Close the open chunk and push everything to the OS (a process kill keeps it)."""
        if not self.closed:
            self._writer.flush()
            self._dirty = False
            self._last_flush = self.clock()

    def flush_if_due(self) -> bool:
        if self._dirty and self.clock() - self._last_flush >= self.flush_interval:
            self.flush()
            return True
        return False

    def finish(self, summary: dict[str, Any] | None = None, state: str = "done") -> Path:
        """Write the summary metadata, the summary section and indexes; rename to the final
        name (atomic). Returns the final path."""
        if self.closed:
            raise RuntimeError(f"recorder of job {self.job_id} is closed")
        self._writer.add_metadata(
            "swarmpath.summary",
            {
                "state": state,
                "runs_written": str(len(self.written)),
                "summary": json.dumps(summary, separators=(",", ":")) if summary else "",
            },
        )
        self._writer.finish()
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()
        self.closed = True
        os.replace(self.part, self.final)
        return self.final

    def close(self) -> None:
        """Stop without finalizing (coordinator shutdown): flush and leave the .part file."""
        if not self.closed:
            self._writer.flush()
            self._file.close()
            self.closed = True


# ------------------------------------------------------------------------------ job recorders
class Recorders:
    """The recorders of a coordinator: opened on demand from the store, thread-safe."""

    def __init__(
        self, store: Any, *, flush_interval: float = FLUSH_INTERVAL,
        compression: CompressionType = CompressionType.ZSTD,
    ):
        self.store = store
        self.data_dir = Path(store.data_dir)
        self.flush_interval = flush_interval
        self.compression = compression
        self._open: dict[str, JobRecorder] = {}
        self._lock = threading.RLock()

    def path(self, job_id: str) -> Path:
        return final_path(self.data_dir, job_id)

    def ready(self, job_id: str) -> bool:
        """True when the job's finalized MCAP exists."""
        return self.path(job_id).exists()

    def open(self, job_id: str) -> JobRecorder:
        """The job's recorder; a new one starts a fresh .part from the store's results."""
        with self._lock:
            rec = self._open.get(job_id)
            if rec is not None:
                return rec
            status = self.store.job_status(job_id)
            if status is None:
                raise KeyError(f"unknown job {job_id!r}")
            spec = self.store.job_spec(job_id)
            rec = JobRecorder(
                self.path(job_id), job_id, status.kind, spec.model_dump(mode="json"),
                status.created, flush_interval=self.flush_interval, compression=self.compression,
            )
            for record in self.store.iter_run_records(job_id):
                rec.add(record)
            rec.flush()
            self._open[job_id] = rec
            return rec

    def add(self, job_id: str, record: dict[str, Any]) -> bool:
        with self._lock:
            return self.open(job_id).add(record)

    def record_run(self, job_id: str, run_id: int) -> bool:
        """Write an accepted run, reading it back from the store."""
        record = self.store.run_record(job_id, run_id)
        if record is None:
            return False
        return self.add(job_id, record)

    def finish(self, job_id: str) -> Path:
        """Finalize the job's file (rebuilding it from the store if no recorder is open)."""
        with self._lock:
            rec = self.open(job_id)
            status = self.store.job_status(job_id)
            stored = status.runs_done + status.runs_failed if status else 0
            if len(rec.written) < stored:
                # A concurrent batch stored its results but has not handed them to the recorder
                # yet (it will find the file finalized): take them from the store now.
                for record in self.store.iter_run_records(job_id):
                    rec.add(record)
            summary = self.store.summary(job_id)
            path = rec.finish(summary, status.state if status else "done")
            del self._open[job_id]
            return path

    def tick(self) -> int:
        """Flush every recorder whose interval elapsed (call about once a second)."""
        with self._lock:
            return sum(rec.flush_if_due() for rec in self._open.values())

    def recover(self) -> list[str]:
        """After a restart: reopen (rebuild) unfinished jobs' files and finalize finished jobs
        whose file is missing. Returns the job ids touched."""
        touched = []
        for job_id in self.store.unfinished_jobs():
            self.open(job_id)
            touched.append(job_id)
        for status in self._final_jobs_without_file():
            self.finish(status.id)
            touched.append(status.id)
        return touched

    def _final_jobs_without_file(self) -> Iterator[Any]:
        for state in ("done", "failed", "cancelled"):
            offset = 0
            while True:
                page = self.store.list_jobs(state, limit=500, offset=offset)
                if not page:
                    break
                for status in page:
                    if not self.ready(status.id):
                        yield status
                offset += len(page)

    def close(self) -> None:
        """Shutdown: flush and close every open recorder without finalizing."""
        with self._lock:
            for rec in self._open.values():
                rec.close()
            self._open.clear()


# ------------------------------------------------------------------------------------ reading
def salvage_messages(
    path: Path | str, topics: Iterable[str] | None = None
) -> list[tuple[str, Any]]:
    """(topic, decoded JSON) of every message readable from a possibly unfinished MCAP file,
    in file order: streams records until the cut (make_reader's seeking reader needs a footer)."""
    out: list[tuple[str, Any]] = []
    with open(path, "rb") as f:
        reader = NonSeekingReader(f, validate_crcs=True)
        try:
            for _schema, channel, message in reader.iter_messages(
                topics=list(topics) if topics is not None else None, log_time_order=False
            ):
                out.append((channel.topic, json.loads(message.data)))
        except (McapError, EOFError, ValueError, OSError) as exc:
            log.info("stopped reading %s at the cut: %s", path, exc)
    return out
