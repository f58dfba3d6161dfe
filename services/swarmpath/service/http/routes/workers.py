"""/workers: the workers the coordinator knows."""

from fastapi import APIRouter

from swarmpath.service.http.deps import CoreDep
from swarmpath.service.protocol import WorkerStatus

router = APIRouter(tags=["service"])


@router.get("/workers")
def workers(core: CoreDep) -> list[WorkerStatus]:
    return core.workers()
