"""Foxglove's well-known message types as JSON Schemas, and builders for their JSON messages.

Foxglove picks its built-in renderer by the *schema name* (``foxglove.SceneUpdate``,
``foxglove.PosesInFrame``, ``foxglove.Grid``) and decodes JSON-encoded messages against these
layouts. The field names, types and enum values below follow the published JSON Schemas of
github.com/foxglove/schemas (``schemas/jsonschema/SceneUpdate.json`` at d41940ba, and
``PosesInFrame.json`` / ``Grid.json`` at 16606139, MIT); the schemas are assembled here from their
building blocks (time, Vector3, Quaternion, Pose, Color, ...) rather than copied.

Foxglove's JSON-schema reader rejects nested arrays, union types and ``null``: every schema here
(and the message builders) uses arrays of objects and fills every field. Enums are integers,
binary fields (``Grid.data``) base64. :func:`check_foxglove_rules` verifies a schema.
"""

from __future__ import annotations

import base64
import json
import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from swarmpath.service.foxglove_schemas import (
    NUMERIC_TYPES,
    SCHEMA_BUILDERS,
    SCHEMAS_SOURCE,
    UINT8,
    check_foxglove_rules,
    check_message,
    frame_transform_schema,
    grid_schema,
    poses_in_frame_schema,
    scene_update_schema,
)

__all__ = [
    "LAYOUT_FILE",
    "NUMERIC_TYPES",
    "SCENE_TOPIC_PREFIXES",
    "SCHEMAS_SOURCE",
    "SCHEMA_BUILDERS",
    "UINT8",
    "check_foxglove_rules",
    "check_message",
    "color",
    "cylinder",
    "entity",
    "frame_transform",
    "frame_transform_schema",
    "ftime",
    "grid_schema",
    "grid_uint8",
    "layout",
    "line",
    "mcap_topics",
    "pose",
    "poses_in_frame",
    "poses_in_frame_schema",
    "quat_yaw",
    "scene_update",
    "scene_update_schema",
    "text",
    "vec3",
]


# ----------------------------------------------------------------------------------- messages
def ftime(ns: int) -> dict[str, int]:
    sec, nsec = divmod(max(0, int(ns)), 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def vec3(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> dict[str, float]:
    return {"x": float(x), "y": float(y), "z": float(z)}


def quat_yaw(yaw: float = 0.0) -> dict[str, float]:
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)}


def pose(x: float = 0.0, y: float = 0.0, z: float = 0.0, yaw: float = 0.0) -> dict[str, Any]:
    return {"position": vec3(x, y, z), "orientation": quat_yaw(yaw)}


def color(r: float, g: float, b: float, a: float = 1.0) -> dict[str, float]:
    return {"r": float(r), "g": float(g), "b": float(b), "a": float(a)}


def cylinder(x: float, y: float, radius: float, height: float, rgba: dict[str, float]) -> dict:
    return {
        "pose": pose(x, y, height / 2.0),
        "size": vec3(2 * radius, 2 * radius, height),
        "bottom_scale": 1.0,
        "top_scale": 1.0,
        "color": rgba,
    }


def line(
    points: Iterable[tuple[float, float]],
    rgba: dict[str, float],
    thickness: float = 0.05,
    loop: bool = False,
    z: float = 0.0,
) -> dict[str, Any]:
    return {
        "type": 1 if loop else 0,
        "pose": pose(),
        "thickness": float(thickness),
        "scale_invariant": False,
        "points": [vec3(x, y, z) for x, y in points],
        "color": rgba,
        "colors": [],
        "indices": [],
    }


def text(x: float, y: float, z: float, label: str, rgba: dict[str, float], size: float) -> dict:
    return {
        "pose": pose(x, y, z),
        "billboard": True,
        "font_size": float(size),
        "scale_invariant": False,
        "color": rgba,
        "text": label,
    }


def entity(
    ns: int,
    entity_id: str,
    frame_id: str = "map",
    *,
    cylinders: Sequence[dict] = (),
    lines: Sequence[dict] = (),
    spheres: Sequence[dict] = (),
    texts: Sequence[dict] = (),
    metadata: dict[str, str] | None = None,
) -> dict[str, Any]:
    """A foxglove.SceneEntity with every field present (unused primitive lists empty)."""
    return {
        "timestamp": ftime(ns),
        "frame_id": frame_id,
        "id": entity_id,
        "lifetime": {"sec": 0, "nsec": 0},
        "frame_locked": False,
        "metadata": [{"key": k, "value": v} for k, v in (metadata or {}).items()],
        "arrows": [],
        "cubes": [],
        "spheres": list(spheres),
        "cylinders": list(cylinders),
        "lines": list(lines),
        "triangles": [],
        "texts": list(texts),
        "models": [],
    }


def scene_update(entities: Sequence[dict[str, Any]]) -> dict[str, Any]:
    return {"deletions": [], "entities": list(entities)}


def poses_in_frame(ns: int, poses: Sequence[dict[str, Any]], frame_id: str = "map") -> dict:
    return {"timestamp": ftime(ns), "frame_id": frame_id, "poses": list(poses)}


def grid_uint8(
    ns: int,
    cells: bytes,
    columns: int,
    resolution: float,
    origin: tuple[float, float] = (0.0, 0.0),
    frame_id: str = "map",
    field: str = "occupancy",
) -> dict[str, Any]:
    """A foxglove.Grid of one uint8 field (row-major, row 0 at the origin's y)."""
    return {
        "timestamp": ftime(ns),
        "frame_id": frame_id,
        "pose": pose(origin[0], origin[1], 0.0),
        "column_count": int(columns),
        "cell_size": {"x": float(resolution), "y": float(resolution)},
        "row_stride": int(columns),
        "cell_stride": 1,
        "fields": [{"name": field, "offset": 0, "type": UINT8}],
        "data": base64.b64encode(cells).decode("ascii"),
    }


def frame_transform(ns: int, parent: str, child: str, x: float = 0.0, y: float = 0.0
                    ) -> dict[str, Any]:
    """A foxglove.FrameTransform: ``child`` is ``parent`` moved by (x, y), not rotated."""
    return {"timestamp": ftime(ns), "parent_frame_id": parent, "child_frame_id": child,
            "translation": vec3(x, y, 0.0), "rotation": quat_yaw(0.0)}


# ------------------------------------------------------------------------------------- layout
#: The Foxglove layout shipped with swarmpath: a 3D panel following frame ``world`` (the maps
#: side by side), a Plot of ``/curves.best_fitness[:]`` against the value index (the
#: iteration) and the ``/results`` message of the current time. Import it in Foxglove with
#: Layouts > Import from file.
LAYOUT_FILE = Path(__file__).with_name("foxglove_layout.json")
#: Topics the layout shows in its 3D panel when a file has them (``/map/...``, ``/scene/...``,
#: ``/paths/...`` and ``/tf``).
SCENE_TOPIC_PREFIXES = ("/tf", "/map/", "/scene/", "/paths/")


#: The topic each panel of the shipped layout shows; a file without it does not get the panel
#: (a benchmark file has no scene, a map file no curves: issue 25).
PANEL_TOPICS = {"3D!swarmpath": SCENE_TOPIC_PREFIXES, "Plot!swarmpath": ("/curves",),
                "RawMessages!swarmpath": ("/results",)}


def layout(topics: Sequence[str] | None = None) -> dict[str, Any]:
    """The shipped layout (``topics`` None), or the one for a file with these ``topics``: its
    scene topics visible in 3D, and only the panels whose topics the file has."""
    doc: dict[str, Any] = json.loads(LAYOUT_FILE.read_text(encoding="utf-8"))
    if topics is None:
        return doc
    panel = doc["configById"]["3D!swarmpath"]
    panel["topics"] = {t: {"visible": True} for t in topics if t.startswith(SCENE_TOPIC_PREFIXES)}
    gone = {name for name, prefixes in PANEL_TOPICS.items()
            if not any(t.startswith(prefixes) for t in topics)}
    if len(gone) < len(PANEL_TOPICS):  # a file with none of them keeps the whole layout
        for name in gone:
            del doc["configById"][name]
        doc["layout"] = _without(doc["layout"], gone)
    return doc


def _without(node: Any, gone: set[str]) -> Any:
    """A mosaic layout tree without the panels ``gone`` (a split losing a side is its other)."""
    if isinstance(node, str):
        return None if node in gone else node
    first, second = _without(node["first"], gone), _without(node["second"], gone)
    if first is None or second is None:
        return second if first is None else first
    return {**node, "first": first, "second": second}


def mcap_topics(path: Path) -> list[str]:
    """The channel topics of a finished MCAP file (from its summary section)."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    return sorted({c.topic for c in summary.channels.values()}) if summary else []
