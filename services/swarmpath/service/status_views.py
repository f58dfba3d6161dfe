"""What the REST API answers about workers and jobs (``GET /workers``, ``GET /jobs/{id}``):
views of the store, not messages of the bus (those are in :mod:`.protocol`, which re-exports
these names)."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Literal

from pydantic import Field, computed_field

from swarmpath.service.model import Identifier, JobState, Model


def iso_time(t: float | None) -> str | None:
    """Unix time -> ISO 8601 in UTC with milliseconds (``2026-11-25T07:41:01.123Z``)."""
    if not t:
        return None
    stamp = datetime.fromtimestamp(t, tz=UTC)
    return stamp.strftime("%Y-%m-%dT%H:%M:%S.") + f"{stamp.microsecond // 1000:03d}Z"


class WorkerStatus(Model):
    """One entry of ``GET /workers``."""

    id: Identifier
    host: str = ""
    pid: int = 0
    slots: int = 1
    current_runs: list[str] = Field(default_factory=list, description="'<job_id>:<run_id>'")
    runs_done: int = 0
    last_seen: float = Field(0.0, description="Unix time")
    alive: bool = True
    platform: dict[str, str] = Field(
        default_factory=dict, description="numeric platform the worker last reported")

    @computed_field  # type: ignore[prop-decorator]
    @property
    def last_seen_at(self) -> str | None:
        """``last_seen`` in ISO 8601 (UTC)."""
        return iso_time(self.last_seen)


class JobStatus(Model):
    """``GET /jobs/{id}``."""

    id: str
    kind: Literal["benchmark", "map"]
    state: JobState
    runs_total: int
    runs_done: int
    runs_failed: int
    created: float = Field(description="Unix time; created_at is the same in ISO 8601")
    started: float | None = None
    finished: float | None = None
    contents: str | None = Field(default=None, description="what the job runs, one line "
                                 "(`GWO, PSO x F1-F13 x D 30`, `MFB x mfb-static`)")
    waiting: str | None = Field(
        default=None, description="state 'waiting': why no live worker can run the job now "
        "(e.g. 'no live worker has optimizer MyGWO (digest 3f2a9c1b4d5e)')")
    pins: dict[str, dict[str, str]] = Field(
        default_factory=dict, description="the job's extensions ('<kind>:<name>') pinned at "
        "submission: source (built-in, distribution, file, module), origin, version and the "
        "sha256 of their code; only workers with the same code run its cells")

    @computed_field  # type: ignore[prop-decorator]
    @property
    def created_at(self) -> str | None:
        """``created`` in ISO 8601 (UTC)."""
        return iso_time(self.created)

    @computed_field  # type: ignore[prop-decorator]
    @property
    def started_at(self) -> str | None:
        return iso_time(self.started)

    @computed_field  # type: ignore[prop-decorator]
    @property
    def finished_at(self) -> str | None:
        return iso_time(self.finished)
