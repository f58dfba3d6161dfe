"""``swarmpath upload-map``: send a nav2 map (YAML + image) or a MovingAI .map to a coordinator
(``POST /maps``); prints the map id to name in a map job: ``{"map": ID, "start": [x, y],
"goal": [x, y]}``."""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Annotated, Any

import typer

from swarmpath.cli.core import InputError, app
from swarmpath.cli.service import UrlOpt, _client, _fail


def _text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError("FILE", f"{path}: not a text file (UTF-8)") from None


def upload_body(path: Path, name: str | None, resolution: float | None,
                scen: Path | None = None) -> dict[str, Any]:
    """The POST /maps body for a file (a MovingAI map with its ``.scen`` when given); raises
    InputError naming the argument at fault."""
    import yaml

    from swarmpath.world.safe_yaml import load_yaml

    if not path.is_file():
        raise InputError("FILE", f"no such file {str(path)!r}")
    stem = name or path.stem
    if path.suffix.lower() == ".map":
        body: dict[str, Any] = {"name": stem, "format": "movingai", "map": _text(path)}
        if resolution is not None:
            body["resolution"] = resolution
        if scen is not None:
            if not scen.is_file():
                raise InputError("--scen", f"no such file {str(scen)!r}")
            try:
                body["scen"] = scen.read_text(encoding="utf-8")
            except UnicodeDecodeError:
                raise InputError("--scen", f"{scen}: not a text file (UTF-8)") from None
        return body
    if scen is not None:
        raise InputError("--scen", "applies to MovingAI .map files only")
    if path.suffix.lower() not in (".yaml", ".yml"):
        raise InputError("FILE", "a nav2 map .yaml (with its image) or a MovingAI .map")
    if resolution is not None:
        raise InputError("--resolution", "applies to MovingAI .map files only")
    text = _text(path)
    try:
        doc = load_yaml(text)
    except yaml.YAMLError as exc:
        raise InputError("FILE", f"{path}: not valid YAML ({exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("image"), str):
        raise InputError("FILE", f"{path}: a nav2 map YAML needs an 'image' key")
    image = Path(doc["image"])
    image = image if image.is_absolute() else path.parent / image
    if not image.is_file():
        raise InputError("FILE", f"{path}: image file not found: {image}")
    return {"name": stem, "format": "nav2", "yaml": text,
            "image": base64.b64encode(image.read_bytes()).decode()}


@app.command("upload-map")
def upload_map(
    file: Annotated[Path, typer.Argument(metavar="FILE", help="nav2 map .yaml or MovingAI .map")],
    name: Annotated[str | None, typer.Option("--name", help="Map name (default: file stem).")]
    = None,
    resolution: Annotated[float | None, typer.Option(
        "--resolution", metavar="M", help="MovingAI cell size in metres (default 1).")] = None,
    scen: Annotated[Path | None, typer.Option(
        "--scen", metavar="SCEN", help="The MovingAI map's .scen: a job then names pairs of "
        "it by row or bucket.")] = None,
    url: UrlOpt = None,
) -> None:
    """Upload a map to the coordinator (POST /maps); prints its id, which a map job names in
    its maps as {"map": ID} with an optional start and goal, or with --scen as {"map": ID,
    "scen": {"buckets": [0, 5, 10], "per_bucket": 2}} (one map per pair, success and gap per
    bucket in the summary and the dashboard)."""
    from swarmpath.service.client import ServiceError, describe_detail

    body = upload_body(file, name, resolution, scen)
    with _client(url) as client:
        try:
            info = client.upload_map(body)
        except ServiceError as exc:
            if exc.status == 413:
                raise InputError("FILE", describe_detail(exc.detail)) from None
            _fail(exc)
            raise
        except Exception as exc:
            _fail(exc)
            raise
    typer.echo(info["id"])
    typer.echo(f"map {info['id']}: {info['name']}, {info['size'][0]:g} x {info['size'][1]:g} m, "
               f"{info['obstacles']} obstacles, default start {_point(info['start'])} goal "
               f"{_point(info['goal'])}" + _frame(info) + _pairs(info), err=True)


def _pairs(info: Any) -> str:
    """How many .scen pairs came with the map, and in which buckets."""
    scen = info.get("scen")
    if not scen:
        return ""
    buckets = [int(b) for b in scen["buckets"]]
    return (f"; {scen['pairs']} .scen pairs in buckets {min(buckets)}-{max(buckets)}"
            if buckets else "; an empty .scen")


def _frame(info: Any) -> str:
    """Which frame the start and goal are in (a nav2 map's own, with its origin)."""
    frame = info.get("frame") or "scenario"
    if frame == "scenario":
        return ""
    return f" ({frame} frame; the map's lower-left corner is at {_point(info['origin'])})"


def _point(xy: Any) -> str:
    """(x, y) in metres as a user reads them: 10.975, not 10.975000000000001."""
    return f"({float(xy[0]):.6g}, {float(xy[1]):.6g})"
