"""Import of ROS map_server / nav2 maps (YAML + PGM/PNG) into an :class:`ImportedMap` (frames,
defaults and limits: :mod:`swarmpath.world.importers`)."""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray
from PIL import Image

from swarmpath.errors import brief
from swarmpath.world.grid_import import (
    ENDPOINT_MARGIN,
    MAX_CELLS,
    MAX_OBSTACLES,
    SURE_FREE,
    ImportedMap,
    MapImportError,
    MapLimitError,
    _build,
)
from swarmpath.world.raster import FREE, OCCUPIED, UNKNOWN
from swarmpath.world.safe_yaml import load_yaml
from swarmpath.world.scenario import (
    RobotSpec,
)

#: The image formats read (nav2's common ones); anything else is refused before a decoder runs.
IMAGE_FORMATS = ("PPM", "PNG", "BMP")


def _truncated(im: Image.Image, path: Path, name: str) -> str:
    """Why an image's pixel data ended early, in the header's terms where it has them (PGM/PPM:
    width x height x bytes per sample from the header, against the bytes after it)."""
    w, h = im.size
    tile = getattr(im, "tile", None)  # an ImageFile's decoder list: (codec, box, offset, args)
    if im.format == "PPM" and tile and tile[0][0] == "raw":
        offset = int(tile[0][2])
        per_pixel = {"1": 1, "L": 1, "I": 2, "I;16": 2, "I;16B": 2, "RGB": 3}.get(im.mode)
        have = path.stat().st_size - offset
        if per_pixel is not None:
            need = w * h * per_pixel
            return (f"{name}: the header says {w} x {h} pixels ({need:,} bytes of pixel "
                    f"data) but the file has {have:,} bytes after the header: the header and "
                    "the data disagree (a truncated file?)")
    return (f"{name}: the pixel data ends before the {w} x {h} pixels its header announces "
            "(a truncated file, or a header that does not match the data)")


def _image_shade(
    path: Path, with_alpha: bool, max_cells: int = MAX_CELLS, name: str | None = None
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Per-pixel shade in [0, 1] (image order, row 0 = top) and an 'is opaque' mask. ``name``:
    the image as the user calls it in messages (default: its path)."""
    name = name or str(path)
    # A crafted file can make a decoder raise nearly anything (ValueError for a PGM maxval
    # over 65535, SyntaxError, struct.error, ...): every failure is the file's, said as such.
    try:
        im_ctx = Image.open(path, formats=IMAGE_FORMATS)
    except Image.DecompressionBombError as e:
        raise MapLimitError(f"{name}: {e}") from None
    except MemoryError:
        raise
    except Exception as e:
        raise MapImportError(f"{name}: cannot read the image (PGM, PNG or BMP): "
                             f"{_reason(e)}") from None
    with im_ctx as im:
        w, h = im.size
        if w * h > max_cells:
            raise MapLimitError(
                f"{name}: {w} x {h} = {w * h:,} cells exceed max_cells={max_cells:,} "
                "(raise it with max_cells= / --max-cells)"
            )
        try:
            im.load()
        except MemoryError:
            raise
        except OSError as e:
            if "truncated" in str(e):
                raise MapImportError(_truncated(im, path, name)) from None
            raise MapImportError(f"{name}: cannot read the pixels: {_reason(e)}") from None
        except Exception as e:
            raise MapImportError(f"{name}: cannot read the pixels: {_reason(e)}") from None
        has_alpha = im.mode in ("LA", "RGBA", "PA", "La", "RGBa") or (
            im.mode == "P" and "transparency" in im.info
        )
        if im.mode in ("I", "I;16", "I;16B", "I;16L", "F"):
            a = np.asarray(im, dtype=np.float64)
            top = 65535.0 if a.max() > 255 else 255.0
            return a / top, np.ones(a.shape, dtype=bool)
        rgba = np.asarray((im.convert("L") if im.mode == "1" else im).convert("RGBA"), np.float64)
    alpha = rgba[..., 3] if has_alpha else np.full(rgba.shape[:2], 255.0)
    channels = [rgba[..., 0], rgba[..., 1], rgba[..., 2]]
    if with_alpha and has_alpha:
        channels.append(alpha)
    shade = np.mean(channels, axis=0) / 255.0
    return shade, alpha >= 255.0


def _reason(e: BaseException) -> str:
    text = " ".join(str(e).split())[:200]
    return text or type(e).__name__


def ros_occupancy(
    shade: NDArray[np.float64],
    opaque: NDArray[np.bool_],
    mode: str,
    negate: bool,
    occupied_thresh: float,
    free_thresh: float,
) -> NDArray[np.int8]:
    """ROS occupancy values for an image (image row order kept), following nav2's map_io rules."""
    occ = shade if negate else 1.0 - shade
    if mode == "trinary":
        out = np.where(occ > occupied_thresh, OCCUPIED, np.where(occ < free_thresh, FREE, UNKNOWN))
    elif mode == "scale":
        mid = np.rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        out = np.where(occ > occupied_thresh, OCCUPIED, np.where(occ < free_thresh, FREE, mid))
        out = np.where(opaque, out, UNKNOWN)
    elif mode == "raw":
        v = np.round(shade * 255.0)
        out = np.where((v >= 0) & (v <= 100), v, UNKNOWN)
    else:
        raise ValueError(f"mode must be trinary, scale or raw, got {mode!r}")
    return np.asarray(out).astype(np.int8)


def _number(doc: dict[str, Any], key: str, src: str, default: float | None = None) -> float:
    if key not in doc:
        if default is None:
            raise MapImportError(f"{src}: {key}: required")
        return default
    v = doc[key]
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise MapImportError(f"{src}: {key}: must be a finite number, got {brief(v)}")
    return float(v)


def load_ros_map(
    yaml_path: str | os.PathLike[str],
    *,
    start: Sequence[float] | None = None,
    goal: Sequence[float] | None = None,
    robot: RobotSpec | None = None,
    name: str | None = None,
    unknown_as_occupied: bool = True,
    sensors: str | None = None,
    time_step: float = 0.1,
    max_cells: int = MAX_CELLS,
    max_obstacles: int = MAX_OBSTACLES,
    endpoint_margin: float = ENDPOINT_MARGIN,
    progress: Callable[[float], None] | None = None,
    image_name: str | None = None,
    endpoints_frame: str = "scenario",
) -> ImportedMap:
    """Import a ROS map_server / nav2 map (YAML + PGM/PNG/BMP image).

    ``start``/``goal`` in the scenario frame (metres from the map's lower-left corner), or with
    ``endpoints_frame="map"`` in the map frame (the YAML origin honoured); defaults as in the
    module docstring. ``robot`` defaults to the ``turtlebot3-burger`` preset.
    ``image_name``: what messages call the image (default: its path).
    """
    if endpoints_frame not in ("scenario", "map"):
        raise ValueError(f"endpoints_frame must be scenario or map, got {endpoints_frame!r}")
    ypath = Path(yaml_path)
    src = str(ypath)
    try:
        doc = load_yaml(ypath.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise MapImportError(f"{src}: not a text file (UTF-8)") from None
    except yaml.YAMLError as e:
        raise MapImportError(f"{src}: cannot parse YAML: {e}") from None
    if not isinstance(doc, dict):
        raise MapImportError(f"{src}: expected a YAML mapping")
    if not isinstance(doc.get("image"), str) or not doc["image"]:
        raise MapImportError(f"{src}: image: required (path of the map image)")
    if "\0" in doc["image"]:
        raise MapImportError(f"{src}: image: not a file name: {brief(doc['image'])}")
    image = Path(doc["image"])
    if not image.is_absolute():
        image = ypath.parent / image
    res = _number(doc, "resolution", src)
    if not res > 0:
        raise MapImportError(f"{src}: resolution: must be > 0")
    origin = doc.get("origin")
    if (
        not isinstance(origin, list | tuple)
        or len(origin) != 3
        or not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                   for v in origin)
    ):
        raise MapImportError(f"{src}: origin: must be [x, y, yaw] (three finite numbers)")
    occ_t = _number(doc, "occupied_thresh", src, 0.65)
    free_t = _number(doc, "free_thresh", src, 0.25)
    if not (0.0 <= free_t < occ_t <= 1.0):
        raise MapImportError(
            f"{src}: occupied_thresh/free_thresh: need 0 <= free_thresh < occupied_thresh <= 1"
        )
    neg = doc.get("negate", 0)
    if neg not in (0, 1, True, False):
        raise MapImportError(f"{src}: negate: must be 0 or 1")
    mode = doc.get("mode", "trinary")
    if not isinstance(mode, str) or mode.lower() not in ("trinary", "scale", "raw"):
        raise MapImportError(f"{src}: mode: must be trinary, scale or raw, got {brief(mode)}")
    mode = mode.lower()
    if not image.is_file():
        raise MapImportError(f"{src}: image: file not found: {image}")
    if endpoints_frame == "map":  # the scenario's (0, 0) is the origin's x, y
        start, goal = (None if p is None else (float(p[0]) - float(origin[0]),
                                               float(p[1]) - float(origin[1]))
                       for p in (start, goal))
    shade, opaque = _image_shade(image, with_alpha=(mode == "trinary"), max_cells=max_cells,
                                 name=image_name)
    values = ros_occupancy(shade, opaque, mode, bool(neg), occ_t, free_t)
    data = values[::-1]  # image row 0 is the top of the map; grid row 0 is the bottom
    occ = shade if neg else 1.0 - shade
    sure_free = np.ascontiguousarray(((occ < SURE_FREE) & opaque)[::-1])
    if mode == "raw":
        sure_free = data == FREE
    return _build(
        name or ypath.stem,
        np.ascontiguousarray(data),
        res,
        start=start,
        goal=goal,
        robot=robot,
        unknown_as_occupied=unknown_as_occupied,
        sensors=sensors,
        time_step=time_step,
        source=src,
        offset=(float(origin[0]), float(origin[1])),
        meta={
            "format": "ros",
            "image": str(image),
            "origin": [float(v) for v in origin],
            "mode": mode,
            "negate": bool(neg),
            "occupied_thresh": occ_t,
            "free_thresh": free_t,
        },
        max_obstacles=max_obstacles,
        endpoint_margin=endpoint_margin,
        allowed=sure_free,
        progress=progress,
        frame="map",
    )


