"""A small synchronous client of the coordinator's REST API (httpx), for the CLI, scripts and tests.

>>> c = ServiceClient("http://127.0.0.1:8000")          # or $SWARMPATH_URL
>>> job = c.submit({"kind": "benchmark", "algorithms": ["GWO"], "functions": ["F1"]})
>>> c.wait(job["id"])["state"]
'done'

Errors: :class:`ServiceError` with the HTTP status, the server's ``detail`` and, for 422s, the
fields it names (``fields``: dotted paths such as ``dims.0``, without the ``body`` and union-tag
prefix).
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import httpx

DEFAULT_URL = "http://127.0.0.1:8000"
FINAL_STATES = frozenset({"done", "failed", "cancelled"})


class ServiceError(RuntimeError):
    def __init__(self, status: int, detail: Any, fields: list[str] | None = None):
        self.status = status
        self.detail = detail
        self.fields = fields or []
        super().__init__(describe_detail(detail))


class Unreachable(ServiceError):
    """The coordinator did not answer (connection refused, timeout)."""


def error_field(loc: list[Any] | tuple[Any, ...]) -> str:
    """``['body', 'benchmark', 'dims', 0]`` -> ``'dims.0'``; ``['query', 'state']`` -> ``'state'``.
    """
    parts = [str(p) for p in loc]
    if parts and parts[0] in ("body", "query", "path"):
        parts = parts[1:]
    if parts and parts[0] in ("benchmark", "map"):
        parts = parts[1:]
    return ".".join(parts) or "body"


def describe_detail(detail: Any) -> str:
    if isinstance(detail, list):
        return "; ".join(
            f"{error_field(d.get('loc', []))}: {d.get('msg', '')}"
            if isinstance(d, dict) else str(d)
            for d in detail
        )
    return str(detail)


class ServiceClient:
    def __init__(
        self, url: str | None = None, token: str | None = None, timeout: float = 30.0,
        transport: httpx.BaseTransport | None = None,
    ):
        self.url = (url or os.environ.get("SWARMPATH_URL") or DEFAULT_URL).rstrip("/")
        token = token if token is not None else os.environ.get("SWARMPATH_TOKEN")
        headers = {"Authorization": f"Bearer {token}"} if token else {}
        self._http = httpx.Client(base_url=self.url, headers=headers, timeout=timeout,
                                  transport=transport)

    def close(self) -> None:
        self._http.close()

    def __enter__(self) -> ServiceClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------------------ plumbing
    def _request(self, method: str, path: str, **kwargs: Any) -> httpx.Response:
        try:
            response = self._http.request(method, path, **kwargs)
        except httpx.TransportError as exc:
            raise Unreachable(0, f"cannot reach the coordinator at {self.url}: {exc}") from None
        if response.status_code >= 400:
            try:
                detail = response.json().get("detail", response.text)
            except ValueError:
                detail = response.text
            fields = (
                [error_field(d.get("loc", [])) for d in detail if isinstance(d, dict)]
                if isinstance(detail, list) else []
            )
            raise ServiceError(response.status_code, detail, fields)
        return response

    def _json(self, method: str, path: str, **kwargs: Any) -> Any:
        return self._request(method, path, **kwargs).json()

    # ----------------------------------------------------------------------------------- API
    def submit(self, spec: Mapping[str, Any]) -> dict[str, Any]:
        return self._json("POST", "/jobs", json=dict(spec))

    def upload_map(self, body: Mapping[str, Any]) -> dict[str, Any]:
        """POST /maps (see :class:`swarmpath.service.maps.MapUpload`)."""
        return self._json("POST", "/maps", json=dict(body))

    def maps(self, limit: int = 100, offset: int = 0) -> list[dict[str, Any]]:
        return list(self._json("GET", "/maps", params={"limit": limit, "offset": offset}))

    def jobs(self, state: str | None = None, limit: int = 100, offset: int = 0) -> list[dict]:
        params: dict[str, Any] = {"limit": limit, "offset": offset}
        if state:
            params["state"] = state
        return self._json("GET", "/jobs", params=params)

    def job(self, job_id: str) -> dict[str, Any]:
        return self._json("GET", f"/jobs/{job_id}")

    def cancel(self, job_id: str) -> dict[str, Any]:
        return self._json("DELETE", f"/jobs/{job_id}")

    def extend(self, job_id: str, runs: int) -> dict[str, Any]:
        """POST /jobs/{id}/extend: a new job reusing the ended job's runs."""
        return self._json("POST", f"/jobs/{job_id}/extend", json={"runs": runs})

    def race(self, job_id: str) -> dict[str, Any]:
        return self._json("GET", f"/jobs/{job_id}/race")

    def summary(self, job_id: str) -> dict[str, Any]:
        return self._json("GET", f"/jobs/{job_id}/summary")

    def summary_csv(self, job_id: str) -> str:
        return self._request("GET", f"/jobs/{job_id}/summary", params={"format": "csv"}).text

    def runs(self, job_id: str, limit: int = 100, offset: int = 0) -> dict[str, Any]:
        return self._json("GET", f"/jobs/{job_id}/runs",
                          params={"limit": limit, "offset": offset})

    def all_runs(self, job_id: str, page: int = 1000) -> list[dict[str, Any]]:
        items: list[dict[str, Any]] = []
        while True:
            got = self.runs(job_id, page, len(items))
            items += got["items"]
            if not got["items"] or len(items) >= got["total"]:
                return items

    def iter_runs(self, job_id: str) -> Iterator[dict[str, Any]]:
        """Every run of the job with its cell spec and series, streamed (``format=jsonl``)."""
        for line in self._stream_lines(f"/jobs/{job_id}/runs", {"format": "jsonl"}):
            yield json.loads(line)

    def download_runs(self, job_id: str, fmt: str, path: str | Path) -> Path:
        """Save every run as CSV or Parquet (``GET /jobs/{id}/runs?format=...``)."""
        return self._save(f"/jobs/{job_id}/runs", Path(path), {"format": fmt})

    def _stream_lines(self, path: str, params: dict[str, Any]) -> Iterator[bytes]:
        try:
            with self._http.stream("GET", path, params=params) as response:
                self._raise_streamed(response)
                rest = b""
                for chunk in response.iter_bytes():  # bytes split by hand: iter_lines decodes
                    *lines, rest = (rest + chunk).split(b"\n")  # and splits 3x slower
                    yield from (line for line in lines if line.strip())
                if rest.strip():
                    yield rest
        except httpx.TransportError as exc:
            raise Unreachable(0, f"cannot reach the coordinator at {self.url}: {exc}") from None

    @staticmethod
    def _raise_streamed(response: httpx.Response) -> None:
        if response.status_code >= 400:
            response.read()
            try:
                detail = response.json().get("detail", response.text)
            except ValueError:
                detail = response.text
            raise ServiceError(response.status_code, detail)

    def _save(self, url_path: str, path: Path, params: dict[str, Any] | None = None) -> Path:
        try:
            with self._http.stream("GET", url_path, params=params) as response:
                self._raise_streamed(response)
                tmp = path.with_name(path.name + ".part")
                with open(tmp, "wb") as f:
                    for chunk in response.iter_bytes():
                        f.write(chunk)
                os.replace(tmp, path)
        except httpx.TransportError as exc:
            raise Unreachable(0, f"cannot reach the coordinator at {self.url}: {exc}") from None
        return path

    def run(self, job_id: str, run_id: int) -> dict[str, Any]:
        return self._json("GET", f"/jobs/{job_id}/runs/{run_id}")

    def download(self, job_id: str, path: str | Path) -> Path:
        """Save the job's MCAP (ServiceError 409 while the job runs)."""
        return self._save(f"/jobs/{job_id}/mcap", Path(path))

    def workers(self) -> list[dict[str, Any]]:
        return self._json("GET", "/workers")

    def catalog(self) -> dict[str, Any]:
        return self._json("GET", "/catalog")

    def healthz(self) -> dict[str, Any]:
        return self._json("GET", "/healthz")

    def metrics(self) -> str:
        return self._request("GET", "/metrics").text

    def wait(
        self,
        job_id: str,
        poll: float = 0.5,
        timeout: float | None = None,
        on_status: Callable[[dict[str, Any]], None] | None = None,
    ) -> dict[str, Any]:
        """Poll until the job is done, failed or cancelled; returns its last status."""
        started = time.monotonic()
        while True:
            status = self.job(job_id)
            if on_status is not None:
                on_status(status)
            if status["state"] in FINAL_STATES:
                return status
            if timeout is not None and time.monotonic() - started > timeout:
                raise TimeoutError(f"job {job_id} still {status['state']} after {timeout} s")
            time.sleep(poll)
