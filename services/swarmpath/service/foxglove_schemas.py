"""Foxglove's well-known message types as JSON Schemas (assembled from their building blocks, see
:mod:`swarmpath.service.foxglove`, which re-exports every name here) and the checks of Foxglove's
JSON-schema reader rules for schemas and messages."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

SCHEMAS_SOURCE = "github.com/foxglove/schemas schemas/jsonschema (SceneUpdate d41940ba, 16606139)"

# ----------------------------------------------------------------------------- schema blocks


def _num(desc: str) -> dict[str, Any]:
    return {"type": "number", "description": desc}


def _time(desc: str) -> dict[str, Any]:
    return {
        "type": "object",
        "title": "time",
        "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        },
        "description": desc,
    }


def _duration(desc: str) -> dict[str, Any]:
    return {
        "type": "object",
        "title": "duration",
        "properties": {
            "sec": {"type": "integer"},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        },
        "description": desc,
    }


def _components(title: str, desc: str, axes: str, what: str) -> dict[str, Any]:
    """A Foxglove struct of named float components (Vector3, Point3, Quaternion...)."""
    return {
        "title": f"foxglove.{title}",
        "description": desc,
        "type": "object",
        "properties": {a: _num(f"{a} {what}") for a in axes},
    }


def _vector3(desc: str) -> dict[str, Any]:
    return _components("Vector3", desc, "xyz", "coordinate length")


def _vector2(desc: str) -> dict[str, Any]:
    return _components("Vector2", desc, "xy", "coordinate length")


def _point3(desc: str) -> dict[str, Any]:
    return _components("Point3", desc, "xyz", "coordinate position")


def _quaternion(desc: str) -> dict[str, Any]:
    return _components("Quaternion", desc, "xyzw", "value")


def _pose(desc: str) -> dict[str, Any]:
    return {
        "title": "foxglove.Pose",
        "description": desc,
        "type": "object",
        "properties": {
            "position": _vector3("Point denoting position in 3D space"),
            "orientation": _quaternion("Quaternion denoting orientation in 3D space"),
        },
    }


def _color(desc: str) -> dict[str, Any]:
    names = {"r": "Red", "g": "Green", "b": "Blue", "a": "Alpha"}
    return {
        "title": "foxglove.Color",
        "description": desc,
        "type": "object",
        "properties": {c: _num(f"{n} value between 0 and 1") for c, n in names.items()},
    }


def _array(items: dict[str, Any], desc: str) -> dict[str, Any]:
    return {"type": "array", "items": items, "description": desc}


def _enum(title: str, desc: str, values: Sequence[tuple[str, int]]) -> dict[str, Any]:
    return {
        "title": title,
        "description": desc,
        "oneOf": [{"title": name, "const": value} for name, value in values],
    }


def _primitive(title: str, desc: str, props: dict[str, Any]) -> dict[str, Any]:
    return {"title": title, "description": desc, "type": "object", "properties": props}


def _scene_entity() -> dict[str, Any]:
    indices = {"type": "array", "items": {"type": "integer", "minimum": 0},
               "description": "Indices into points and colors"}
    colors = _array(_color("A color in RGBA format"), "Per-point colors")
    points = _array(_point3("A point representing a position in 3D space"), "Points")
    primitives = {
        "arrows": _primitive("foxglove.ArrowPrimitive", "A primitive representing an arrow", {
            "pose": _pose("Position of the arrow's tail and orientation of the arrow"),
            "shaft_length": _num("Length of the arrow shaft"),
            "shaft_diameter": _num("Diameter of the arrow shaft"),
            "head_length": _num("Length of the arrow head"),
            "head_diameter": _num("Diameter of the arrow head"),
            "color": _color("Color of the arrow"),
        }),
        "cubes": _primitive("foxglove.CubePrimitive", "A cube or rectangular prism", {
            "pose": _pose("Center and orientation of the cube"),
            "size": _vector3("Size of the cube along each axis"),
            "color": _color("Color of the cube"),
        }),
        "spheres": _primitive("foxglove.SpherePrimitive", "A sphere or ellipsoid", {
            "pose": _pose("Center and orientation of the sphere"),
            "size": _vector3("Size (diameter) of the sphere along each axis"),
            "color": _color("Color of the sphere"),
        }),
        "cylinders": _primitive("foxglove.CylinderPrimitive", "A cylinder or truncated cone", {
            "pose": _pose("Center and orientation of the cylinder (flat faces normal to z)"),
            "size": _vector3("Size of the cylinder's bounding box"),
            "bottom_scale": _num("0-1, bottom face diameter relative to the bounding box"),
            "top_scale": _num("0-1, top face diameter relative to the bounding box"),
            "color": _color("Color of the cylinder"),
        }),
        "lines": _primitive("foxglove.LinePrimitive", "Points connected by lines", {
            "type": _enum("foxglove.LineType", "Drawing primitive to use for lines",
                          [("LINE_STRIP", 0), ("LINE_LOOP", 1), ("LINE_LIST", 2)]),
            "pose": _pose("Origin of lines relative to reference frame"),
            "thickness": _num("Line thickness"),
            "scale_invariant": {"type": "boolean",
                                "description": "thickness in screen pixels (true) or metres"},
            "points": points,
            "color": _color("Solid color of the whole line"),
            "colors": colors,
            "indices": indices,
        }),
        "triangles": _primitive("foxglove.TriangleListPrimitive", "A set of triangles", {
            "pose": _pose("Origin of triangles relative to reference frame"),
            "points": points,
            "color": _color("Solid color of the whole shape"),
            "colors": colors,
            "indices": indices,
        }),
        "texts": _primitive("foxglove.TextPrimitive", "A text label", {
            "pose": _pose("Center of the text box and orientation of the text"),
            "billboard": {"type": "boolean", "description": "Always face the camera"},
            "font_size": _num("Font size (height of one line of text)"),
            "scale_invariant": {"type": "boolean",
                                "description": "font_size in screen pixels (true) or metres"},
            "color": _color("Color of the text"),
            "text": {"type": "string", "description": "Text"},
        }),
        "models": _primitive("foxglove.ModelPrimitive", "A 3D model file", {
            "pose": _pose("Origin of model relative to reference frame"),
            "scale": _vector3("Scale factor to apply to the model along each axis"),
            "color": _color("Solid color used if override_color is true"),
            "override_color": {"type": "boolean", "description": "Use color instead of materials"},
            "url": {"type": "string", "description": "URL pointing to model file"},
            "media_type": {"type": "string", "description": "Media type of embedded model"},
            "data": {"type": "string", "contentEncoding": "base64",
                     "description": "Embedded model"},
        }),
    }
    props: dict[str, Any] = {
        "timestamp": _time("Timestamp of the entity"),
        "frame_id": {"type": "string", "description": "Frame of reference"},
        "id": {"type": "string", "description": "Identifier; replaces a prior entity with it"},
        "lifetime": _duration("Time after which the entity is removed; zero = never"),
        "frame_locked": {"type": "boolean", "description": "Follow frame_id as it moves"},
        "metadata": _array(
            {
                "title": "foxglove.KeyValuePair",
                "description": "A key with its associated value",
                "type": "object",
                "properties": {
                    "key": {"type": "string", "description": "Key"},
                    "value": {"type": "string", "description": "Value"},
                },
            },
            "Additional user-provided metadata associated with the entity",
        ),
    }
    for name, item in primitives.items():
        props[name] = _array(item, f"{name.capitalize()} primitives")
    return _primitive(
        "foxglove.SceneEntity", "A visual element in a 3D scene, made of primitives", props
    )


def scene_update_schema() -> dict[str, Any]:
    return {
        "title": "foxglove.SceneUpdate",
        "description": "An update to the entities displayed in a 3D scene",
        "type": "object",
        "properties": {
            "deletions": _array(
                _primitive(
                    "foxglove.SceneEntityDeletion",
                    "Command to remove previously published entities",
                    {
                        "timestamp": _time("Only matching entities earlier than this are deleted"),
                        "type": _enum(
                            "foxglove.SceneEntityDeletionType",
                            "Type of deletion action to perform",
                            [("MATCHING_ID", 0), ("ALL", 1)],
                        ),
                        "id": {"type": "string", "description": "Id to match for MATCHING_ID"},
                    },
                ),
                "Scene entities to delete",
            ),
            "entities": _array(_scene_entity(), "Scene entities to add or replace"),
        },
    }


def poses_in_frame_schema() -> dict[str, Any]:
    return {
        "title": "foxglove.PosesInFrame",
        "description": "An array of timestamped poses for an object or reference frame in 3D space",
        "type": "object",
        "properties": {
            "timestamp": _time("Timestamp of pose"),
            "frame_id": {"type": "string", "description": "Frame of reference for the poses"},
            "poses": _array(_pose("A position and orientation in 3D space"), "Poses in 3D space"),
        },
    }


NUMERIC_TYPES = (
    ("UNKNOWN", 0), ("UINT8", 1), ("INT8", 2), ("UINT16", 3), ("INT16", 4), ("UINT32", 5),
    ("INT32", 6), ("FLOAT32", 7), ("FLOAT64", 8),
)
UINT8 = 1


def grid_schema() -> dict[str, Any]:
    return {
        "title": "foxglove.Grid",
        "description": "A 2D grid of data",
        "type": "object",
        "properties": {
            "timestamp": _time("Timestamp of grid"),
            "frame_id": {"type": "string", "description": "Frame of reference"},
            "pose": _pose("Origin of the grid's corner; the grid lies in its x-y plane"),
            "column_count": {"type": "integer", "minimum": 0,
                             "description": "Number of grid columns"},
            "cell_size": _vector2("Size of single grid cell along x and y axes"),
            "row_stride": {"type": "integer", "minimum": 0,
                           "description": "Number of bytes between rows in data"},
            "cell_stride": {"type": "integer", "minimum": 0,
                            "description": "Number of bytes between cells within a row in data"},
            "fields": _array(
                _primitive(
                    "foxglove.PackedElementField",
                    "A field present within each element in a byte array of packed elements.",
                    {
                        "name": {"type": "string", "description": "Name of the field"},
                        "offset": {"type": "integer", "minimum": 0,
                                   "description": "Byte offset from start of data buffer"},
                        "type": _enum("foxglove.NumericType", "Type of data in the field",
                                      NUMERIC_TYPES),
                    },
                ),
                "Fields in data",
            ),
            "data": {"type": "string", "contentEncoding": "base64",
                     "description": "Grid cell data, row-major (y-major)"},
        },
    }


def frame_transform_schema() -> dict[str, Any]:
    return {
        "title": "foxglove.FrameTransform",
        "description": "A transform between two reference frames in 3D space",
        "type": "object",
        "properties": {
            "timestamp": _time("Timestamp of transform"),
            "parent_frame_id": {"type": "string", "description": "Name of the parent frame"},
            "child_frame_id": {"type": "string", "description": "Name of the child frame"},
            "translation": _vector3("Translation component of the transform"),
            "rotation": _quaternion("Rotation component of the transform"),
        },
    }


SCHEMA_BUILDERS = {
    "foxglove.SceneUpdate": scene_update_schema,
    "foxglove.PosesInFrame": poses_in_frame_schema,
    "foxglove.Grid": grid_schema,
    "foxglove.FrameTransform": frame_transform_schema,
}


# ----------------------------------------------------------------------------------- checking
def check_foxglove_rules(schema: Any, where: str = "$") -> list[str]:
    """Problems Foxglove's JSON-schema reader would have: nested arrays, union types, null."""
    problems: list[str] = []
    if isinstance(schema, dict):
        t = schema.get("type")
        if isinstance(t, list):
            problems.append(f"{where}: union type {t}")
        if t == "null":
            problems.append(f"{where}: null type")
        if "anyOf" in schema:
            problems.append(f"{where}: anyOf")
        if t == "array":
            items = schema.get("items", {})
            if isinstance(items, dict) and items.get("type") == "array":
                problems.append(f"{where}: nested array")
        for key, value in schema.items():
            problems += check_foxglove_rules(value, f"{where}.{key}")
    elif isinstance(schema, list):
        for i, value in enumerate(schema):
            problems += check_foxglove_rules(value, f"{where}[{i}]")
    return problems


def check_message(message: Any, where: str = "$") -> list[str]:
    """Problems of a JSON message for Foxglove: nested arrays, nulls, non-finite numbers."""
    problems: list[str] = []
    if message is None:
        problems.append(f"{where}: null")
    elif isinstance(message, float) and not math.isfinite(message):
        problems.append(f"{where}: non-finite number")
    elif isinstance(message, dict):
        for k, v in message.items():
            problems += check_message(v, f"{where}.{k}")
    elif isinstance(message, list):
        for i, v in enumerate(message):
            if isinstance(v, list):
                problems.append(f"{where}[{i}]: nested array")
            problems += check_message(v, f"{where}[{i}]")
    return problems

