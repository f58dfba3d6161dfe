"""/catalog: what can be run."""

from typing import Any

from fastapi import APIRouter

from swarmpath.service.catalog import build_catalog

router = APIRouter(tags=["service"])


@router.get("/catalog")
def catalog() -> dict[str, Any]:
    """Optimizers (with parameters), functions, planners (with parameters) and maps."""
    return build_catalog()
