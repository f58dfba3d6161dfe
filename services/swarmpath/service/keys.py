"""The Zenoh key expressions of the service, all under one prefix (the messages that travel on
them are in :mod:`swarmpath.service.protocol`, which re-exports :class:`Keys`)."""

from __future__ import annotations

import re

from swarmpath.service.model import _ID_RE, DEFAULT_PREFIX, ID_PATTERN


class Keys:
    """The key expressions, all under one prefix (default ``swarmpath``)."""

    def __init__(self, prefix: str = DEFAULT_PREFIX):
        if not prefix or prefix.startswith("/") or prefix.endswith("/") or any(
            c in prefix for c in "*$#?"
        ):
            raise ValueError(f"bad key prefix {prefix!r}")
        self.prefix = prefix

    @property
    def work(self) -> str:
        """Queryable: LeaseRequest -> Lease | NoWork."""
        return f"{self.prefix}/work"

    def results(self, job_id: str) -> str:
        return f"{self.prefix}/results/{_chunk(job_id)}"

    def progress(self, job_id: str) -> str:
        return f"{self.prefix}/progress/{_chunk(job_id)}"

    def ack(self, worker: str) -> str:
        return f"{self.prefix}/ack/{_chunk(worker)}"

    def worker_token(self, worker: str) -> str:
        """Liveliness token of a worker."""
        return f"{self.prefix}/workers/{_chunk(worker)}"

    @property
    def cancel(self) -> str:
        return f"{self.prefix}/cancel"

    @property
    def wake(self) -> str:
        """Put by the coordinator when work appeared (a hint, no payload): workers told
        ``empty`` ask again at once instead of at the end of their ``retry_after``."""
        return f"{self.prefix}/wake"

    def scenario(self, sha256: str) -> str:
        """Queryable of the coordinator: ScenarioRequest -> the scenario's canonical JSON."""
        if not re.fullmatch(r"[0-9a-f]{64}", sha256):
            raise ValueError(f"{sha256!r} is not a SHA-256 hex digest")
        return f"{self.prefix}/scenarios/{sha256}"

    @property
    def all_scenarios(self) -> str:
        return f"{self.prefix}/scenarios/*"

    # subscriptions of the coordinator
    @property
    def all_results(self) -> str:
        return f"{self.prefix}/results/*"

    @property
    def all_progress(self) -> str:
        return f"{self.prefix}/progress/*"

    @property
    def all_workers(self) -> str:
        return f"{self.prefix}/workers/*"

    @staticmethod
    def last_chunk(key: str) -> str:
        return key.rsplit("/", 1)[-1]


def _chunk(value: str) -> str:
    if not _ID_RE.match(value):
        raise ValueError(f"{value!r} is not a valid identifier ({ID_PATTERN})")
    return value

