"""One MCAP file per job, written while the job runs, finalized with summary and indexes at its end.

Files live in ``<data_dir>/mcap/``: ``<job>.mcap.part`` while the job runs, renamed (atomically) to
``<job>.mcap`` once :meth:`JobRecorder.finish` wrote the summary section. MCAP has no append mode.

Writing: chunked (1 MiB; lz4, or zstd/none with ``$SWARMPATH_MCAP_COMPRESSION``, see
:func:`~swarmpath.service.recorder.common.chunk_compression`), message indexes and chunk indexes
on, chunk CRCs and the data section CRC on, statistics and summary offsets on.
:meth:`JobRecorder.flush_if_due` closes the open chunk when at least ``flush_interval`` (1 s)
passed since the last flush; it runs after every message and should also be called from a ~1 s
timer (:meth:`Recorders.tick`) so that an idle job is flushed too. A process kill therefore loses
at most about a second of messages from the .part
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
first, one ``swarmpath.run`` per map run (run, run_id, cell, planner, map, its MovingAI bucket
when the map has one, success, reason, collisions, length, its scene and path topics, entity
prefix and frame), and
``swarmpath.summary`` (final state and the summary table JSON) at the end. The Foxglove layout
shipped beside this module (:data:`swarmpath.service.foxglove.LAYOUT_FILE`; ``swarmpath download
JOB --layout`` writes one with the file's topics) shows the scene in 3D and plots ``/curves``.

The package by concern: :mod:`.job` (the writer of one file), :mod:`.fastwriter` (the mcap
``Writer`` with cheaper messages, chunks and CRCs, same bytes), :mod:`.registry` (the
coordinator's recorders), :mod:`.scene` (how maps and runs are drawn), :mod:`.schemas` (the own
topics' JSON schemas), :mod:`.salvage` (reading an unfinished file), :mod:`.common` (paths and
encoding).
"""

from __future__ import annotations

from swarmpath.service.recorder.common import clamped, final_path, mcap_dir, part_path
from swarmpath.service.recorder.job import CHUNK_SIZE, FLUSH_INTERVAL, LAYOUT_VERSION, JobRecorder
from swarmpath.service.recorder.registry import Recorders
from swarmpath.service.recorder.salvage import salvage_messages
from swarmpath.service.recorder.scene import (
    GOAL_RGBA,
    GRID_MAX_CELLS,
    MAP_GAP,
    MAX_SCENE_FRAMES,
    OBSTACLE_HEIGHT,
    OBSTACLE_RGBA,
    ROBOT_HEIGHT,
    ROBOT_RGBA,
    START_RGBA,
    WORLD_FRAME,
    map_frame,
    occupancy,
    scenario_for,
    world_for,
)
from swarmpath.service.recorder.schemas import (
    BENCHMARK_RESULT_SCHEMA,
    CURVE_SCHEMA,
    MAP_RESULT_SCHEMA,
    OWN_SCHEMAS,
)

__all__ = [
    "BENCHMARK_RESULT_SCHEMA",
    "CHUNK_SIZE",
    "CURVE_SCHEMA",
    "FLUSH_INTERVAL",
    "GOAL_RGBA",
    "GRID_MAX_CELLS",
    "LAYOUT_VERSION",
    "MAP_GAP",
    "MAP_RESULT_SCHEMA",
    "MAX_SCENE_FRAMES",
    "OBSTACLE_HEIGHT",
    "OBSTACLE_RGBA",
    "OWN_SCHEMAS",
    "ROBOT_HEIGHT",
    "ROBOT_RGBA",
    "START_RGBA",
    "WORLD_FRAME",
    "JobRecorder",
    "Recorders",
    "clamped",
    "final_path",
    "map_frame",
    "mcap_dir",
    "occupancy",
    "part_path",
    "salvage_messages",
    "scenario_for",
    "world_for",
]
