"""Uploaded maps: import a nav2 YAML + image or a MovingAI .map sent to ``POST /maps``, and put
the stored scenario in place of ``{"map": id, "start"?, "goal"?}`` entries of a map job.

Plain functions (no HTTP): the ``/maps`` router and the ``/jobs`` router call them. Errors are
:class:`MapUploadError` with the body field and an HTTP status: 413 for a size limit (the message
names the limit), 422 for anything else. The coordinator parses uploads in a child process
bounded in memory and time (:func:`import_bounded`, :mod:`swarmpath.service.bounded`).
"""

from __future__ import annotations

import base64
import binascii
import json
import re
import tempfile
from collections.abc import Callable
from pathlib import Path, PurePath
from typing import Annotated, Any, Literal

import yaml
from pydantic import Field

from swarmpath.service.bounded import (
    BoundedRunner,
    CallDied,
    CallOutOfMemory,
    CallTimedOut,
    RunnerBusy,
)
from swarmpath.service.protocol import (
    ID_PATTERN,
    MAX_RUNS_PER_JOB,
    MAX_SCENARIO_BYTES,
    FieldProblems,
    MapJobSpec,
    MapRef,
    Model,
)

#: A nav2 map YAML is a dozen lines; anything longer is not one.
MAX_NAV2_YAML_CHARS = 65_536
#: A .scen of MAX_SCEN_ROWS rows of 40-80 characters.
MAX_SCEN_CHARS = 8_000_000
_UPLOAD_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")


class Nav2Upload(Model):
    """``POST /maps`` body of a nav2 map: the map_server YAML text and the image file."""

    name: str = Field(pattern=ID_PATTERN, max_length=64)
    format: Literal["nav2"]
    yaml: str = Field(max_length=MAX_NAV2_YAML_CHARS, description="the map_server YAML text")
    image: str = Field(description="base64 of the PGM/PNG/BMP file the YAML names")


class MovingAIUpload(Model):
    """``POST /maps`` body of a MovingAI grid: the .map text and its cell size."""

    name: str = Field(pattern=ID_PATTERN, max_length=64)
    format: Literal["movingai"]
    map: str = Field(description="the .map text")
    resolution: float = Field(default=1.0, gt=0, allow_inf_nan=False,
                              description="metres per cell")
    scen: str | None = Field(
        default=None, max_length=MAX_SCEN_CHARS,
        description="the map's MovingAI .scen text (its start/goal pairs and their buckets): a "
        "job then names pairs as {'map': id, 'scen': {'rows': [...]} or {'buckets': [...], "
        "'per_bucket': n}}")


#: The ``POST /maps`` body: one of the two, told apart by ``format``.
MapUpload = Annotated[Nav2Upload | MovingAIUpload, Field(discriminator="format")]


class MapUploadError(ValueError):
    def __init__(self, status: int, field: str, message: str, kind: str | None = None):
        super().__init__(message)
        self.status = status
        self.field = field
        self.kind = kind or ("map_too_large" if status == 413 else "map_invalid")

    def __reduce__(self) -> tuple[Any, ...]:  # crosses the import process's pipe
        return (MapUploadError, (self.status, self.field, str(self), self.kind))


def _image_field(up: Nav2Upload | MovingAIUpload) -> str:
    return "map" if isinstance(up, MovingAIUpload) else "image"


def import_upload(up: Nav2Upload | MovingAIUpload, max_cells: int | None = None,
                  max_obstacles: int | None = None) -> dict[str, Any]:
    """The scenario (JSON object) of an upload; raises :class:`MapUploadError`. The grid limits
    default to the importer's (the coordinator's ``max_map_cells`` / ``max_map_obstacles``).
    The coordinator calls it in a bounded process (:func:`import_bounded`)."""
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
    grid_field = _image_field(up)
    with tempfile.TemporaryDirectory(prefix="swarmpath-map-") as tmp:
        d = Path(tmp)
        try:
            if isinstance(up, MovingAIUpload):
                path = d / f"{up.name}.map"
                path.write_text(up.map, encoding="utf-8")
                imported = load_movingai_map(path, resolution=up.resolution, name=up.name,
                                             **limits)
            else:
                path, image_name = _write_nav2(d, up)
                imported = load_ros_map(path, name=up.name, image_name=image_name, **limits)
        except MapLimitError as exc:
            raise MapUploadError(413, grid_field, _service_hint(_strip(str(exc), d))) from None
        except ScenarioError as exc:
            raise MapUploadError(422, grid_field, _strip(str(exc), d)) from None
        except MapImportError as exc:
            text = _strip(str(exc), d)
            field = "image" if _about_image(text, up) else ("map" if grid_field == "map"
                                                             else "yaml")
            raise MapUploadError(422, field, text) from None
    scenario = scenario_to_dict(imported.scenario)
    size = len(json.dumps(scenario))
    if size > MAX_SCENARIO_BYTES:  # leases name it by hash; a worker fetches it in one reply
        raise MapUploadError(413, grid_field,
                             f"the imported scenario is {size:,} bytes of JSON, over "
                             f"MAX_SCENARIO_BYTES={MAX_SCENARIO_BYTES:,}: upload a smaller or "
                             "coarser map")
    return scenario


def import_map(up: Nav2Upload | MovingAIUpload, max_cells: int | None = None,
               max_obstacles: int | None = None) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """The scenario of an upload (:func:`import_upload`) and the pairs of its ``.scen``
    (:func:`swarmpath.service.map_pairs.scen_rows`; None without one), both made in the
    bounded child process."""
    from swarmpath.service.map_pairs import scen_rows
    from swarmpath.world.movingai_scen import ScenError, ScenLimitError

    scenario = import_upload(up, max_cells, max_obstacles)
    scen = getattr(up, "scen", None)
    if scen is None:
        return scenario, None
    assert isinstance(up, MovingAIUpload)
    try:
        return scenario, scen_rows(scen, up.name, scenario, up.resolution)
    except ScenError as exc:
        raise MapUploadError(413 if isinstance(exc, ScenLimitError) else 422, "scen",
                             str(exc)) from None


def _about_image(text: str, up: Nav2Upload | MovingAIUpload) -> bool:
    """Whether an importer's message is about the upload's image (not about its YAML, whose
    messages start with the YAML's name)."""
    return isinstance(up, Nav2Upload) and not text.startswith(f"{up.name}.yaml")


def _service_hint(text: str) -> str:
    """The importer's "how to raise it" names its keyword and CLI flag; a coordinator has a
    setting (and an environment variable) for each."""
    for name in ("max_cells", "max_obstacles"):
        text = text.replace(f" (raise it with {name}= / --{name.replace('_', '-')})",
                            _raise_hint(f"max_map_{name[4:]}"))
    return text


def _strip(text: str, d: Path) -> str:
    return text.replace(str(d) + "/", "")


def _write_nav2(d: Path, up: Nav2Upload) -> tuple[Path, str]:
    """The upload's YAML and image written into ``d`` (the image under the base name the YAML
    gives it, so messages name the user's file; never a path outside ``d``); returns the YAML's
    path and the image's name."""
    from swarmpath.errors import brief
    from swarmpath.world.safe_yaml import load_yaml

    try:
        doc = load_yaml(up.yaml)
    except yaml.YAMLError as exc:
        raise MapUploadError(422, "yaml", f"cannot parse YAML: {exc}") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("image"), str):
        raise MapUploadError(422, "yaml", "expected a mapping with an 'image' key (the image's "
                             "file name)")
    try:
        data = base64.b64decode(up.image, validate=True)
    except (binascii.Error, ValueError):
        raise MapUploadError(422, "image", "not valid base64") from None
    given = PurePath(doc["image"].replace("\\", "/")).name
    suffix = PurePath(given).suffix.lower() or ".pgm"
    if suffix not in (".pgm", ".png", ".bmp"):
        raise MapUploadError(422, "yaml", f"image: {brief(given)}: {brief(suffix)} files are "
                             "not read (pgm, png, bmp)")
    name = given if _UPLOAD_NAME.fullmatch(given) and given != f"{up.name}.yaml" else \
        f"image{suffix}"
    (d / name).write_bytes(data)
    doc["image"] = name
    path = d / f"{up.name}.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    return path, name


def warm_importer() -> None:
    """The import process's imports, paid before its first upload's time starts."""
    import swarmpath.service.map_pairs
    import swarmpath.world.importers
    import swarmpath.world.scenario_io  # noqa: F401


def _raise_hint(setting: str) -> str:
    return (f" (raise it with the coordinator setting {setting}, environment "
            f"SWARMPATH_{setting.upper()})")


def import_bounded(runner: BoundedRunner, up: Nav2Upload | MovingAIUpload,
                   max_cells: int | None = None, max_obstacles: int | None = None
                   ) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """:func:`import_map` in ``runner``'s child process (bounded memory and time); the
    bounds' refusals as :class:`MapUploadError` (413 naming the limit and the setting that
    raises it; 503 while too many uploads wait)."""
    field = _image_field(up)
    try:
        imported: tuple[dict[str, Any], dict[str, Any] | None] = runner.call(
            import_map, up, max_cells, max_obstacles)
        return imported
    except CallTimedOut:
        raise MapUploadError(413, field, f"importing this map took longer than "
                             f"{runner.seconds:g} s{_raise_hint('max_map_import_seconds')}",
                             "map_import_timeout") from None
    except CallOutOfMemory:
        raise MapUploadError(413, field, f"importing this map needed more than "
                             f"{runner.memory_bytes / 2**20:,.0f} MiB of memory"
                             f"{_raise_hint('max_map_import_bytes')}",
                             "map_import_memory") from None
    except CallDied as exc:
        raise MapUploadError(422, field, f"the map could not be imported: {exc}",
                             "map_import_died") from None
    except RunnerBusy:
        raise MapUploadError(503, "", "too many map uploads are being imported; retry in a "
                             "few seconds", "busy") from None


def resolve_refs(spec: MapJobSpec,
                 lookup: Callable[[str], dict[str, Any] | None],
                 pairs_lookup: Callable[[str], dict[str, Any] | None] | None = None
                 ) -> MapJobSpec:
    """The job with every ``{"map": id, ...}`` replaced by the stored scenario (named as it was
    uploaded, ``name (id)`` when another map of the job has that name; its description names
    the id; ``start`` / ``goal`` applied and checked), and every ``{"map": id, "scen": ...}``
    by one scenario per chosen pair of the map's stored ``.scen`` (``pairs_lookup``; named
    ``NAME#row``, their buckets and octile optima in the spec's ``buckets`` / ``octile``:
    :func:`swarmpath.service.map_pairs.expand_pairs`); raises :class:`FieldProblems` at
    ``maps.i.map`` / ``maps.i.start`` / ``maps.i.goal`` / ``maps.i.scen...``."""
    from swarmpath.service.map_pairs import expand_pairs
    from swarmpath.world.scenario import scenario_problems
    from swarmpath.world.scenario_io import ScenarioError, scenario_from_dict

    if not any(isinstance(m, MapRef) for m in spec.maps):
        return spec
    problems: list[tuple[tuple[str | int, ...], str]] = []
    maps: list[Any] = []
    buckets, octile = dict(spec.buckets), dict(spec.octile)
    taken = {m if isinstance(m, str) else str(m.get("name")) for m in spec.maps
             if not isinstance(m, MapRef) and isinstance(m, str | dict)}
    for i, entry in enumerate(spec.maps):
        if not isinstance(entry, MapRef):
            maps.append(entry)
            continue
        stored = lookup(entry.map)
        if stored is None:
            problems.append(((i, "map"), f"unknown map id {entry.map!r} (see GET /maps)"))
            continue
        name = str(stored.get("name") or entry.map)
        name = name if name not in taken else f"{name} ({entry.map})"
        taken.add(name)
        doc = dict(stored, name=name, description=f"uploaded map {entry.map}: "
                   f"{stored.get('description', '')}".rstrip(": "))
        # start and goal in the map's own frame (a nav2 map's YAML origin), as GET /maps
        # reports them; the scenario keeps its own frame (0, 0 = the lower-left corner)
        if entry.scen is not None:
            found_pairs = expand_pairs(entry, stored, (pairs_lookup or _none)(entry.map),
                                       name, doc)
            maps += found_pairs[0]
            buckets.update(found_pairs[1])
            octile.update(found_pairs[2])
            problems += [((i, *loc), message) for loc, message in found_pairs[3]]
            taken.update(found_pairs[1])
            continue
        ox, oy = (float(v) for v in (stored.get("grid") or {}).get("origin") or (0.0, 0.0))
        for key in ("start", "goal"):
            value = getattr(entry, key)
            if value is not None:
                doc[key] = [float(value[0]) - ox, float(value[1]) - oy]
        try:
            found = scenario_problems(scenario_from_dict(doc))
        except ScenarioError as exc:
            found = list(exc.problems)
        problems += [((i, field), message) for field, message in found]
        maps.append(doc)
    total = len(spec.planners) * len(maps) * spec.runs
    if total > MAX_RUNS_PER_JOB and not problems:  # the pairs multiplied the maps
        first = next(i for i, m in enumerate(spec.maps) if isinstance(m, MapRef) and m.scen)
        problems.append(((first, "scen"), f"{len(spec.planners)} planners x {len(maps)} maps "
                         f"x {spec.runs} runs = {total} runs; a job may have at most "
                         f"{MAX_RUNS_PER_JOB}"))
    if problems:
        raise FieldProblems(problems)
    return spec.model_copy(update={"maps": maps, "buckets": buckets, "octile": octile})


def _none(_map_id: str) -> None:
    return None

