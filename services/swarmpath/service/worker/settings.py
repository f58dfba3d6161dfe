"""A worker's configuration (the CLI fills it) and its default id."""

from __future__ import annotations

import logging
import os
import re
import socket
from dataclasses import dataclass, field
from typing import Any, Literal

from swarmpath.service.protocol import (
    DEFAULT_PREFIX,
)
from swarmpath.service.zenoh_config import DEFAULT_ZENOH, client_config

log = logging.getLogger("swarmpath.worker")


def default_worker_id() -> str:
    host = re.sub(r"[^A-Za-z0-9_.-]", "-", socket.gethostname()).strip("-._") or "host"
    return f"{host[:100]}-{os.getpid()}"


@dataclass
class WorkerSettings:
    connect: list[str] = field(default_factory=lambda: [DEFAULT_ZENOH])
    prefix: str = DEFAULT_PREFIX
    slots: int = 1
    worker_id: str | None = None
    max_runs: int = 1000  # per lease request; the coordinator sizes leases below this
    max_leases: int = 32  # per lease request: small leases come as bundles of up to this many
    prefetch: int = 1  # bundles held beyond the slots: the next one is at hand when a slot frees
    stacking: bool = True  # a bundle's leases differing only in the function run as one batch
    # process slots compile (or load) the numba kernels before they take work (slots.py);
    # SWARMPATH_WARM=0 turns it off (backend auto then runs the numpy reference in the slots)
    warm: bool = field(default_factory=lambda: os.environ.get("SWARMPATH_WARM", "1").lower()
                       not in ("0", "false", "no", "off"))
    executor: Literal["process", "thread"] = "process"
    user: str | None = None
    password: str | None = None
    shm: bool = False
    zenoh_extra: dict[str, Any] | None = None
    query_timeout: float = 10.0  # waiting for a lease reply (and for a scenario's)
    scenario_cache_bytes: int = 256 * 1024 * 1024  # fetched scenarios kept (LRU by bytes)
    ack_timeout: float = 5.0  # results not settled within this are put again (with backoff)
    max_backoff: float = 5.0  # coordinator absent: retry pulls at most this far apart
    grace_seconds: float = 10.0  # on stop: running leases get this long to finish
    exit_with_parent: int | None = None  # stop when this process is no longer our parent

    def zenoh_config(self) -> dict[str, Any]:
        return client_config(self.connect, shm=self.shm, user=self.user, password=self.password,
                             extra=self.zenoh_extra)
