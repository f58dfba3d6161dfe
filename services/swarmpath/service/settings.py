"""The coordinator's configuration (the CLI fills it)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from swarmpath.service.cost import DEFAULT_MAX_EVALUATIONS, DEFAULT_MAX_STEPS
from swarmpath.service.protocol import DEFAULT_PREFIX
from swarmpath.service.zenoh_config import DEFAULT_ZENOH, router_config

DEFAULT_HTTP = "127.0.0.1:8000"
DEFAULT_MAX_MAP_UPLOAD_BYTES = 32 * 1024 * 1024
#: An upload is parsed in a child process with these bounds (service/bounded.py). The largest
#: map within the grid limits (2048 x 2048 cells, 4,800 obstacles) took 28 s and 0.6 GB of
#: address space on a loaded 2-core machine.
DEFAULT_MAX_MAP_IMPORT_SECONDS = 120.0
DEFAULT_MAX_MAP_IMPORT_BYTES = 2 * 1024**3


def _env_number(name: str, default: float) -> float:
    text = os.environ.get(name)
    if not text:
        return float(default)
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{name}={text!r} is not a number") from None
    if not value > 0:
        raise ValueError(f"{name} must be positive, got {text}")
    return value


def _env_count(name: str) -> int:
    """A positive whole number from the environment, 0 when unset."""
    return int(_env_number(name, 1)) if os.environ.get(name) else 0


@dataclass
class CoordinatorSettings:
    """Everything a coordinator process is configured with (the CLI fills it)."""

    data_dir: Path = field(default_factory=lambda: Path("swarmpath-data"))
    zenoh_listen: list[str] = field(default_factory=lambda: [DEFAULT_ZENOH])
    prefix: str = DEFAULT_PREFIX
    lease_seconds: float = 30.0  # a lease without heartbeat for this long is requeued
    heartbeat_seconds: float | None = None  # default lease_seconds / 3
    target_lease_seconds: float = 10.0  # a lease (or bundle of leases) is about this much work
    min_lease_runs: int = 8  # benchmark leases: at least this many runs (vectorization)
    # the farm is granted about this many leases per second at most (lease_sizer.py: a lease
    # holds at least live slots / this seconds of work)
    max_lease_rate: float = 100.0
    retry_after: float = 0.5  # NoWork: ask again after this long
    token: str | None = None  # bearer token of mutating endpoints (None: $SWARMPATH_TOKEN)
    shm: bool = False
    dictionary_file: str | None = None  # Zenoh usrpwd authentication of workers
    zenoh_extra: dict[str, Any] | None = None
    synchronous: str = "FULL"  # SQLite durability (FULL: acks survive a power cut)
    tick_seconds: float = 1.0
    # write the MCAP files in a process of their own that follows the store (recorder/process.py)
    recorder_process: bool = False
    require_liveliness: bool = True  # lease only to workers whose liveliness token is seen
    max_workers: int = 1024  # worker table entries at most (see worker_table.py)
    forget_workers_seconds: float = 600.0  # a gone worker is listed this long, then forgotten
    # the job cost guard (see cost.py): larger jobs are refused with a 422 naming the estimate
    max_job_evaluations: float = field(default_factory=lambda: _env_number(
        "SWARMPATH_MAX_JOB_EVALUATIONS", DEFAULT_MAX_EVALUATIONS))
    max_job_steps: float = field(default_factory=lambda: _env_number(
        "SWARMPATH_MAX_JOB_STEPS", DEFAULT_MAX_STEPS))
    # POST /maps bodies (a base64 image is 4/3 of the file); every other route: MAX_BODY_BYTES
    max_map_upload_bytes: int = field(default_factory=lambda: int(_env_number(
        "SWARMPATH_MAX_MAP_UPLOAD_BYTES", DEFAULT_MAX_MAP_UPLOAD_BYTES)))
    # an upload's grid limits (0: the importer's, 4,194,304 cells and 5,000 obstacles)
    max_map_cells: int = field(default_factory=lambda: _env_count("SWARMPATH_MAX_MAP_CELLS"))
    max_map_obstacles: int = field(
        default_factory=lambda: _env_count("SWARMPATH_MAX_MAP_OBSTACLES"))
    # the child process parsing an upload: wall-clock seconds and the address space (bytes) an
    # import may add to the child's own (its imports are not counted)
    max_map_import_seconds: float = field(default_factory=lambda: _env_number(
        "SWARMPATH_MAX_MAP_IMPORT_SECONDS", DEFAULT_MAX_MAP_IMPORT_SECONDS))
    max_map_import_bytes: int = field(default_factory=lambda: int(_env_number(
        "SWARMPATH_MAX_MAP_IMPORT_BYTES", DEFAULT_MAX_MAP_IMPORT_BYTES)))

    # Host names the HTTP side answers (http/middleware.py, allowed_hosts): the CLI sets them
    # from --http and --allowed-host / SWARMPATH_ALLOWED_HOSTS; None: not checked
    allowed_hosts: list[str] | None = None

    def zenoh_config(self) -> dict[str, Any]:
        return router_config(
            self.zenoh_listen, shm=self.shm, dictionary_file=self.dictionary_file,
            extra=self.zenoh_extra,
        )

