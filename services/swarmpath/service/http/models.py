"""Response models of the result routes, for /openapi.json (and the dashboard's and other
clients' code generators). Open models: a metric added to a run or a column to a summary is
passed through (``extra="allow"``); non-finite numbers travel as "inf", "-inf", "nan"."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from swarmpath.service.cell_notes import TrajectoryWarning

Number = float | str | None
RunState = Literal["queued", "leased", "done", "failed", "cancelled"]


class _Open(BaseModel):
    model_config = ConfigDict(extra="allow")


class JobCreated(BaseModel):
    """``POST /jobs`` 201: the new job's id (``GET /jobs/{id}``), its state and run count."""

    id: str = Field(description="the job id: GET /jobs/{id}, /summary, /runs, /mcap")
    state: Literal["queued", "running", "done", "failed", "cancelled", "waiting"] = Field(
        description="'waiting': no live worker has the job's pinned extensions yet")
    runs_total: int


class MapScen(_Open):
    """The pairs of a map's uploaded MovingAI .scen."""

    pairs: int
    buckets: dict[str, int] = Field(description="{bucket: pairs}")


class MapInfo(_Open):
    """``POST /maps`` 201 and ``GET /maps``: an uploaded map (a job names it by ``id``);
    positions in the map's own frame (``frame``, its ``origin``: a nav2 map's YAML origin)."""

    id: str = Field(description='name it in a map job: {"map": id, "start"?, "goal"?}')
    name: str
    format: Literal["nav2", "movingai"]
    created: float
    size: list[float] = Field(description="[w, h] in metres")
    frame: str
    origin: list[float]
    start: list[float] = Field(description="the default start")
    goal: list[float] = Field(description="the default goal")
    obstacles: int
    scen: MapScen | None = Field(default=None, description="the .scen uploaded with the map "
                                 "(null: none)")


class BucketRow(_Open):
    """One planner in one MovingAI bucket (swarmpath.evidence.buckets.bucket_rows)."""

    planner: str
    bucket: int
    pairs: int = Field(description="maps of the bucket the planner ran")
    runs: int
    successes: int
    success_rate: float
    gap_median: Number = Field(description="over the successful runs with an exact optimum")
    gap_mean: Number


class Summary(_Open):
    """``GET /jobs/{id}/summary``: the CLI's table (partial while the job runs)."""

    job_id: str
    kind: Literal["benchmark", "map"]
    state: str
    partial: bool
    runs_total: int
    runs_done: int
    runs_failed: int
    columns: list[str]
    rows: list[dict[str, Any]] = Field(description="one per cell, keyed by the columns")
    statistics: dict[str, Any] | None = Field(
        None, description="the statistical tests of docs/statistics.md")
    legend: dict[str, str] = Field(
        default_factory=dict,
        description="what the columns mean (failed, collisions, gap_mean, ...): "
                    "swarmpath.evidence.legend, the text under the CLI tables")
    warnings: list[TrajectoryWarning] | None = Field(
        None, description="map jobs: moving goals or obstacles whose stated path crosses a "
        "static obstacle, each naming its field (maps[i].goal_motion, maps[i].obstacles[k]); "
        "found by the workers (swarmpath.service.cell_notes). Map rows also carry "
        "optimum_reason: why the cell has no exact optimum (so no gap), null when it has one")
    buckets: list[BucketRow] | None = Field(
        None, description="map jobs: success and gap per planner and MovingAI bucket (the "
        "difficulty curve; empty when no map has a bucket: the spec's buckets, set for "
        "{'map': id, 'scen': ...} pairs). Map rows also carry their bucket")


class RunItem(_Open):
    """One run: identity, state and (once finished) its metrics."""

    run_id: int
    run: int
    cell: str
    seed: int
    state: RunState
    worker: str | None = None
    algorithm: str | None = None
    function: str | None = None
    dim: int | None = None
    planner: str | None = None
    map: str | None = None
    bucket: int | None = Field(None, description="map runs: the map's MovingAI bucket (a .scen "
                               "pair's, the spec's buckets); null without one")
    best_fitness: Number = None
    evaluations: int | None = None
    success: bool | None = None
    collisions: int | None = None
    length: Number = None
    gap: Number = None
    seconds: Number = None
    failure: str | None = None
    optimum_reason: str | None = Field(
        None, description="map runs without an exact optimum: why (absent when it was found)")
    lease_id: str | None = None
    completed: float | None = Field(None, description="Unix time the result was accepted")


class RunsPage(BaseModel):
    """``GET /jobs/{id}/runs``: a page of runs in run_id order."""

    job_id: str
    total: int
    limit: int
    offset: int
    items: list[RunItem]


class Run(RunItem):
    """``GET /jobs/{id}/runs/{run_id}``: one run with its series."""

    curve: list[Number] | None = Field(None, description="best so far after each iteration")
    best_position: list[Number] | None = None
    path: list[list[Number]] | None = Field(None, description="rows [x, y, t]")
