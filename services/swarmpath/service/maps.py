"""Uploaded maps: import a nav2 YAML + image or a MovingAI .map sent to ``POST /maps``, and put
the stored scenario in place of ``{"map": id, "start"?, "goal"?}`` entries of a map job.

Plain functions (no HTTP): the ``/maps`` router and the ``/jobs`` router call them. Errors are
:class:`MapUploadError` with the body field and an HTTP status: 413 for a size limit (the message
names the limit), 422 for anything else.
"""

from __future__ import annotations

import base64
import binascii
import json
import tempfile
from collections.abc import Callable
from pathlib import Path, PurePath
from typing import Any, Literal

import yaml
from pydantic import Field

from swarmpath.service.protocol import (
    ID_PATTERN,
    MAX_SCENARIO_BYTES,
    FieldProblems,
    MapJobSpec,
    MapRef,
    Model,
)


class MapUpload(Model):
    """``POST /maps`` body. nav2: ``yaml`` (the map_server YAML text) and ``image`` (the image
    file, base64); MovingAI: ``map`` (the .map text) and ``resolution`` (metres per cell)."""

    name: str = Field(pattern=ID_PATTERN, max_length=64)
    format: Literal["nav2", "movingai"]
    yaml: str | None = None
    image: str | None = Field(default=None, description="base64 of the PGM/PNG/BMP file")
    map: str | None = None
    resolution: float = Field(default=1.0, gt=0, description="MovingAI: metres per cell")


class MapUploadError(ValueError):
    def __init__(self, status: int, field: str, message: str):
        super().__init__(message)
        self.status = status
        self.field = field


def import_upload(up: MapUpload, max_cells: int | None = None,
                  max_obstacles: int | None = None) -> dict[str, Any]:
    """The scenario (JSON object) of an upload; raises :class:`MapUploadError`. The grid limits
    default to the importer's (the coordinator's ``max_map_cells`` / ``max_map_obstacles``)."""
    from swarmpath.world.importers import (  # the grid limits are the CLI's
        MAX_CELLS,
        MAX_OBSTACLES,
        MapImportError,
        MapLimitError,
        load_movingai_map,
        load_ros_map,
    )
    from swarmpath.world.scenario_io import ScenarioError, scenario_to_dict

    limits = {"max_cells": max_cells or MAX_CELLS, "max_obstacles": max_obstacles or MAX_OBSTACLES}
    with tempfile.TemporaryDirectory(prefix="swarmpath-map-") as tmp:
        d = Path(tmp)
        try:
            if up.format == "movingai":
                if not up.map:
                    raise MapUploadError(422, "map", "required for format 'movingai'")
                path = d / f"{up.name}.map"
                path.write_text(up.map, encoding="utf-8")
                imported = load_movingai_map(path, resolution=up.resolution, name=up.name,
                                             **limits)
            else:
                path = _write_nav2(d, up)
                imported = load_ros_map(path, name=up.name, **limits)
        except MapLimitError as exc:
            raise MapUploadError(413, "map" if up.format == "movingai" else "image",
                                 _service_hint(_strip(str(exc), d))) from None
        except ScenarioError as exc:
            raise MapUploadError(422, "map" if up.format == "movingai" else "image",
                                 _strip(str(exc), d)) from None
        except MapImportError as exc:
            raise MapUploadError(422, "map" if up.format == "movingai" else "yaml",
                                 _strip(str(exc), d)) from None
    scenario = scenario_to_dict(imported.scenario)
    size = len(json.dumps(scenario))
    if size > MAX_SCENARIO_BYTES:  # leases name it by hash; a worker fetches it in one reply
        raise MapUploadError(413, "map" if up.format == "movingai" else "image",
                             f"the imported scenario is {size:,} bytes of JSON, over "
                             f"MAX_SCENARIO_BYTES={MAX_SCENARIO_BYTES:,}: upload a smaller or "
                             "coarser map")
    return scenario


def _service_hint(text: str) -> str:
    """The importer's "how to raise it" names its keyword and CLI flag; a coordinator has a
    setting (and an environment variable) for each."""
    for name in ("max_cells", "max_obstacles"):
        setting = f"max_map_{name[4:]}"
        text = text.replace(f"(raise it with {name}= / --{name.replace('_', '-')})",
                            f"(raise it with the coordinator setting {setting}, environment "
                            f"SWARMPATH_{setting.upper()})")
    return text


def _strip(text: str, d: Path) -> str:
    return text.replace(str(d) + "/", "")


def _write_nav2(d: Path, up: MapUpload) -> Path:
    if not up.yaml:
        raise MapUploadError(422, "yaml", "required for format 'nav2' (the map_server YAML)")
    if not up.image:
        raise MapUploadError(422, "image", "required for format 'nav2' (base64 image file)")
    try:
        doc = yaml.safe_load(up.yaml)
    except yaml.YAMLError as exc:
        raise MapUploadError(422, "yaml", f"cannot parse YAML: {exc}") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("image"), str):
        raise MapUploadError(422, "yaml", "expected a mapping with an 'image' key")
    try:
        data = base64.b64decode(up.image, validate=True)
    except (binascii.Error, ValueError):
        raise MapUploadError(422, "image", "not valid base64") from None
    suffix = PurePath(doc["image"]).suffix.lower() or ".pgm"
    if suffix not in (".pgm", ".png", ".bmp"):
        raise MapUploadError(422, "yaml", f"image: {suffix} files are not read (pgm, png, bmp)")
    (d / f"image{suffix}").write_bytes(data)
    doc["image"] = f"image{suffix}"  # never a path outside the upload's directory
    path = d / f"{up.name}.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    return path


def resolve_refs(spec: MapJobSpec,
                 lookup: Callable[[str], dict[str, Any] | None]) -> MapJobSpec:
    """The job with every ``{"map": id, ...}`` replaced by the stored scenario (named by the id;
    ``start`` / ``goal`` applied and checked); raises :class:`FieldProblems` at
    ``maps.i.map`` / ``maps.i.start`` / ``maps.i.goal``."""
    from swarmpath.world.scenario import scenario_problems
    from swarmpath.world.scenario_io import ScenarioError, scenario_from_dict

    if not any(isinstance(m, MapRef) for m in spec.maps):
        return spec
    problems: list[tuple[tuple[str | int, ...], str]] = []
    maps: list[Any] = []
    for i, entry in enumerate(spec.maps):
        if not isinstance(entry, MapRef):
            maps.append(entry)
            continue
        stored = lookup(entry.map)
        if stored is None:
            problems.append(((i, "map"), f"unknown map id {entry.map!r} (see GET /maps)"))
            continue
        doc = dict(stored, name=entry.map)
        for key in ("start", "goal"):
            value = getattr(entry, key)
            if value is not None:
                doc[key] = [float(value[0]), float(value[1])]
        try:
            found = scenario_problems(scenario_from_dict(doc))
        except ScenarioError as exc:
            found = list(exc.problems)
        problems += [((i, field), message) for field, message in found]
        maps.append(doc)
    if problems:
        raise FieldProblems(problems)
    names = [m if isinstance(m, str) else m["name"] for m in maps]
    if len(set(names)) != len(names):
        raise FieldProblems([((), "two maps have the same name: give each uploaded map once")])
    return spec.model_copy(update={"maps": maps})

