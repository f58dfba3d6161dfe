"""/maps: upload a nav2 or MovingAI map, list and read the uploaded maps (logic:
:mod:`swarmpath.service.maps`)."""

import asyncio
from typing import Annotated, Any

from fastapi import APIRouter, Body, Depends, HTTPException

from swarmpath.service.http.deps import CoreDep, Limit, Offset, authorized
from swarmpath.service.http.models import MapInfo
from swarmpath.service.maps import (
    MapUploadError,
    MovingAIUpload,
    Nav2Upload,
    import_bounded,
)

router = APIRouter(tags=["maps"])


@router.post("/maps", status_code=201, dependencies=[Depends(authorized)],
             response_model=MapInfo)
async def upload_map(
    up: Annotated[Nav2Upload | MovingAIUpload, Body(discriminator="format")], core: CoreDep,
) -> dict[str, Any]:
    """Import a nav2 YAML + base64 image or a MovingAI .map (with its .scen: ``scen``); 201
    with the map id (name it in a map job: ``{"map": id, "start": [x, y], "goal": [x, y]}``, or
    pairs of its .scen: ``{"map": id, "scen": {"buckets": [...], "per_bucket": n}}``). 413
    when the map is over a size limit, or its import over the time or memory limit (named in
    the message), 422 when it cannot be imported. The import runs in a child process bounded
    in memory and time."""
    settings = core.settings
    try:
        scenario, pairs = await asyncio.to_thread(
            import_bounded, core.map_importer, up, settings.max_map_cells,
            settings.max_map_obstacles)
    except MapUploadError as exc:
        loc = ["body", exc.field] if exc.field else ["body"]
        raise HTTPException(exc.status, [{"loc": loc, "msg": str(exc), "type": exc.kind}],
                            headers={"Retry-After": "5"} if exc.status == 503 else None
                            ) from None
    source = up.model_dump()
    map_id = await asyncio.to_thread(core.store.add_map, up.name, up.format, source, scenario,
                                     None, pairs)
    info = core.store.map_info(map_id)
    assert info is not None
    info.pop("scenario")
    return info


@router.get("/maps", response_model=list[MapInfo])
def list_maps(
    core: CoreDep,
    limit: Limit = 100,
    offset: Offset = 0,
) -> list[dict[str, Any]]:
    """Uploaded maps, newest first: id, name, format, size, start, goal, obstacle count."""
    return core.store.list_maps(limit, offset)


@router.get("/maps/{map_id}")
def read_map(map_id: str, core: CoreDep) -> dict[str, Any]:
    """One uploaded map with its imported scenario."""
    info = core.store.map_info(map_id)
    if info is None:
        raise HTTPException(404, f"unknown map {map_id!r}")
    return info
