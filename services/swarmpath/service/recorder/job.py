"""The writer of one job's MCAP file (layout: see :mod:`swarmpath.service.recorder`)."""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import orjson
from mcap.writer import CompressionType, IndexType, Writer

from swarmpath.service import foxglove as fg
from swarmpath.service.protocol import PROTOCOL_VERSION
from swarmpath.service.recorder.common import (
    _finite_scalar,
    _json,
    _ns,
    _topic_name,
    _version,
    chunk_compression,
    clamped,
)
from swarmpath.service.recorder.fastwriter import FastWriter, writer_class
from swarmpath.service.recorder.scene import (
    GOAL_RGBA,
    MAP_GAP,
    MAX_SCENE_FRAMES,
    ROBOT_HEIGHT,
    ROBOT_RGBA,
    START_RGBA,
    WORLD_FRAME,
    _marker,
    _obstacle_entity,
    _run_about,
    map_frame,
    occupancy,
    scenario_for,
    source_frame,
    world_for,
)
from swarmpath.service.recorder.schemas import OWN_SCHEMAS

MAX_PLATFORM_RECORDS = 1024  # swarmpath.platform metadata records per job
LAYOUT_VERSION = 2  # 2: a frame per map (/tf), static occupancy, swarmpath.run metadata
FLUSH_INTERVAL = 1.0
CHUNK_SIZE = 1024 * 1024
_FLOAT64 = np.dtype(np.float64)


def _without_nulls(value: Any) -> Any:
    """``value`` with every null field left out (Foxglove's readers take no nulls)."""
    if isinstance(value, dict):
        return {k: _without_nulls(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [_without_nulls(v) for v in value]
    return value


def _fast_json(message: dict[str, Any]) -> bytes:
    """``message`` as compact JSON, numpy arrays included (orjson; the general encoder for what
    orjson refuses, e.g. an integer beyond 64 bits)."""
    try:
        return orjson.dumps(message, option=orjson.OPT_SERIALIZE_NUMPY)
    except TypeError:
        return _json({k: v.tolist() if isinstance(v, np.ndarray) else v
                      for k, v in message.items()})


def _curve_json(record: dict[str, Any], identity: dict[str, Any], curve: Any) -> tuple[bytes, ...]:
    """The /curves message of a benchmark run: ``best_fitness`` (its last field) holds the
    curve's values, non-finite ones clamped (:func:`clamped`). A C-contiguous float64 array (a
    store record holds one over the stored bytes) is written by orjson straight from its
    buffer (the shortest round-trip decimals: the same text as for a list of the same floats)
    after the other fields' JSON; orjson writes a non-finite float as ``null`` and a number
    never holds an ``n``, so the clamped values are only made when the array's text has one.
    The message is returned in parts, to be written one after the other (not joined first)."""
    head = {
        "job_id": record["job_id"], "run_id": int(record["run_id"]), "cell": record["cell"],
        "run": int(record["run"]), "seed": int(record["seed"]), **identity,
        "iterations": len(curve),
    }
    if (isinstance(curve, np.ndarray) and curve.dtype == _FLOAT64
            and curve.flags.c_contiguous):
        try:
            values = orjson.dumps(curve, option=orjson.OPT_SERIALIZE_NUMPY)
            fields = orjson.dumps(head)
        except TypeError:  # what orjson refuses (e.g. an integer beyond 64 bits)
            pass
        else:
            if b"n" not in values:  # (memchr: a fraction of a microsecond)
                return fields[:-1], b',"best_fitness":', values, b"}"
    return (_fast_json({**head, "best_fitness": np.ascontiguousarray(clamped(curve,
                                                                             as_array=True))}),)


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
        compression: CompressionType | None = None,
        clock: Callable[[], float] = time.monotonic,
        fast: bool = True,
        pins: dict[str, dict[str, str]] | None = None,
    ):
        """``fast=False``: the plain mcap ``Writer`` instead of :class:`FastWriter` (the same
        bytes, slower; for the test that compares them)."""
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
        self._identities: dict[str, tuple[dict[str, Any], dict[str, Any]]] = {}  # by cell
        self._channels: dict[str, int] = {}
        self._platforms: set[tuple[str, str]] = set()  # (worker, fingerprint) written
        self._dirty = False
        self._last_flush = clock()
        self.final.parent.mkdir(parents=True, exist_ok=True)
        self._file: BinaryIO = open(self.part, "wb")  # closed by finish/close
        settings: dict[str, Any] = dict(
            chunk_size=chunk_size,
            compression=chunk_compression() if compression is None else compression,
            index_types=IndexType.ALL,
            repeat_channels=True,
            repeat_schemas=True,
            use_chunking=True,
            use_statistics=True,
            use_summary_offsets=True,
            enable_crcs=True,
            enable_data_crcs=True,
        )
        writer = writer_class()(self._file, **settings) if fast else None
        self._fast: FastWriter | None = (
            writer if isinstance(writer, FastWriter) and writer.checked else None)
        self._writer: Writer = self._fast or Writer(self._file, **settings)
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
        if pins:  # the code the job was pinned to: each extension's origin, version, digest
            self._writer.add_metadata("swarmpath.extensions", {
                key: json.dumps(pin, sort_keys=True, separators=(",", ":"))
                for key, pin in sorted(pins.items())})
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

    def _put(self, topic: str, schema_name: str, log_ns: int,
             message: dict[str, Any] | bytes) -> None:
        """One message on ``topic``: a dict (its JSON made here) or its JSON."""
        self._put_parts(topic, schema_name, log_ns,
                        (message if isinstance(message, bytes) else _json(message),))

    def _put_parts(self, topic: str, schema_name: str, log_ns: int,
                   parts: tuple[bytes, ...]) -> None:
        """One message on ``topic`` whose JSON is ``parts`` one after the other."""
        cid = self._channels.get(topic)
        if cid is None:
            cid = self._channel(topic, schema_name)
        if self._fast is not None:
            self._fast.add_parts(cid, log_ns, parts)
        else:
            self._writer.add_message(cid, log_time=log_ns, publish_time=log_ns,
                                     data=b"".join(parts))
        self._dirty = True

    # ---------------------------------------------------------------------------------- runs
    def add(self, record: dict[str, Any]) -> bool:
        """Write one finished run (a record from :meth:`Store.run_record`/``iter_run_records``).
        Returns False when that run id was already written (nothing is written twice)."""
        if self.closed:
            raise RuntimeError(f"recorder of job {self.job_id} is closed")
        platform = record.get("platform")
        if platform:  # also when the run came from the store first
            self.note_platform(str(record.get("worker") or ""), platform)
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

    def note_platform(self, worker: str, platform: dict[str, str]) -> None:
        """One ``swarmpath.platform`` metadata record per (worker, platform fingerprint) seen in
        this job (from the coordinator's worker table: the platform is not stored, so a file
        rebuilt from the store has none). Bounded by MAX_PLATFORM_RECORDS."""
        if self.closed or not platform or len(self._platforms) >= MAX_PLATFORM_RECORDS:
            return
        key = (worker, str(platform.get("fingerprint", "")))
        if key in self._platforms:
            return
        self._platforms.add(key)
        self._writer.add_metadata("swarmpath.platform", {
            **{str(k): str(v) for k, v in platform.items()}, "worker": key[0]})

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
        cpu = record.get("cpu_seconds")
        if cpu is not None:  # None: stored before CPU times were measured (left out, not 0)
            msg["cpu_seconds"] = float(cpu)
        for key, value in (record.get("metrics") or {}).items():
            if key not in msg and _finite_scalar(value):
                msg[key] = value
        return msg

    def _benchmark_run(self, record: dict[str, Any]) -> None:
        cell = record["cell"]
        known = self._identities.get(cell)
        if known is None:  # per cell, not per run
            spec = record["spec"]
            identity = {"algorithm": spec["algorithm"], "function": spec["function"],
                        "dim": int(spec["dim"])}
            known = self._identities[cell] = (
                identity, {**identity, "backend": spec.get("backend") or "numpy"})
        identity, with_backend = known
        ns = _ns(record["created"])
        self._put_parts("/results", "swarmpath.BenchmarkRunResult", ns,
                        (_fast_json(self._result_message(record, with_backend)),))
        curve = record.get("curve")
        if curve is not None and len(curve):
            self._put_parts("/curves", "swarmpath.ConvergenceCurve", ns,
                            _curve_json(record, identity, curve))

    def _bucket(self, map_: str) -> int | None:
        """The MovingAI bucket of map ``map_`` (a ``.scen`` pair's, or one the spec gave it:
        the spec's ``buckets``); None when it has none (every map of an older job)."""
        bucket = (self.spec.get("buckets") or {}).get(map_)
        return int(bucket) if isinstance(bucket, int) and not isinstance(bucket, bool) else None

    def _map_run(self, record: dict[str, Any]) -> None:
        spec = record["spec"]
        planner, map_ = spec["planner"], spec["map"]
        bucket = self._bucket(map_)
        identity: dict[str, Any] = {"planner": planner, "map": map_}
        if bucket is not None:  # left out, not null, when the map has none
            identity["bucket"] = bucket
        self._put("/results", "swarmpath.MapRunResult", _ns(record["created"]),
                  self._result_message(record, identity))
        if map_ not in self._scenarios:
            self._scenarios[map_] = scenario = scenario_for(spec)
            if scenario is not None:
                self._draw_map(map_, scenario)
        scenario = self._scenarios[map_]
        topic = f"{_topic_name(planner)}/{_topic_name(map_)}"
        metrics = record.get("metrics") or {}
        self._writer.add_metadata("swarmpath.run", {
            **_run_about(record, planner, map_, bucket), "cell": str(record["cell"]),
            "seed": str(record["seed"]), "scene_topic": f"/scene/{topic}",
            "path_topic": f"/paths/{topic}", "entity_prefix": f"run-{int(record['run'])}/",
            "frame_id": map_frame(map_), "collisions": str(metrics.get("collisions", "")),
            "length": str(metrics.get("length", "")),
        })
        path = record.get("path")  # a list, or an array (in-process records): no truthiness
        if path is not None and len(path):
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
        offset = self._map_offset(name, w)
        grid = getattr(scenario, "grid", None)
        if grid is None:
            self._put("/tf", "foxglove.FrameTransform", ns,
                      fg.frame_transform(ns, WORLD_FRAME, frame, offset))
        else:  # world -> the map's own frame -> its scenario frame, at the same place
            ox, oy = (float(v) for v in grid.origin)
            own = source_frame(name, grid.frame)
            self._put("/tf", "foxglove.FrameTransform", ns,
                      fg.frame_transform(ns, WORLD_FRAME, own, offset - ox, -oy))
            self._put("/tf", "foxglove.FrameTransform", ns,
                      fg.frame_transform(ns, own, frame, ox, oy))
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
        about = _run_about(record, planner, map_, self._bucket(map_))
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
        race = ((summary or {}).get("statistics") or {}).get("race")
        if race:  # a raced job: its decisions, on /race (one message per block) and as metadata
            ns = _ns(time.time())
            for block in race["blocks"]:
                self._put("/race", "swarmpath.RaceBlock", ns,
                          _without_nulls({"job_id": self.job_id, **block}))
            self._writer.add_metadata("swarmpath.race", {
                "settings": json.dumps(race["settings"], separators=(",", ":")),
                "comparisons": str(race["comparisons"])})
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

    def abandon(self) -> None:
        """Stop after a write failed (disk full): close the file without writing more; the
        .part is rewritten from the store by the job's next recorder."""
        if not self.closed:
            self.closed = True
            try:
                self._file.close()
            except OSError:
                pass

    def close(self) -> None:
        """Stop without finalizing (coordinator shutdown): flush and leave the .part file."""
        if not self.closed:
            self._writer.flush()
            self._file.close()
            self.closed = True
