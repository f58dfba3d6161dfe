"""Large scenarios by reference: a lease names a map cell's scenario by the SHA-256 of its
canonical JSON (:class:`~swarmpath.service.protocol.ScenarioRef`) instead of carrying it, and the
worker fetches it once from the coordinator (a query on ``<prefix>/scenarios/<sha256>``), checks
the hash and keeps it in a bounded cache.

Plain functions and one small class, no I/O of their own: the store, the Zenoh bridge and the
worker call them.

* :func:`by_reference` - the cell a lease carries (the coordinator's side);
* :func:`answer` - the coordinator's reply to a ScenarioRequest: the canonical JSON, only to the
  worker that holds a lease (not cancelled: an expired lease's late results are still accepted)
  on a cell with exactly that scenario, proven with the lease's capability;
  :class:`ScenarioRefused` with the reason otherwise;
* :func:`resolve` - the worker's side: the lease with its scenario in place, from the cache or
  fetched and checked; :class:`ScenarioUnavailable` with the reason otherwise (the lease's runs
  then fail with it).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

from swarmpath.service.protocol import (
    INLINE_SCENARIO_BYTES,
    MAX_SCENARIO_BYTES,
    CellSpec,
    Lease,
    MapCell,
    ScenarioRef,
    ScenarioRequest,
    decode,
)


class ScenarioRefused(ValueError):
    """The coordinator does not answer a scenario request (the message says why)."""


class ScenarioUnavailable(RuntimeError):
    """A worker could not get a lease's scenario (the message says why). ``transient``: nobody
    answered (the lease is left to expire and its runs are leased again) rather than a refusal
    or a wrong scenario (the runs fail with the reason)."""

    def __init__(self, message: str, transient: bool = False):
        super().__init__(message)
        self.transient = transient


def canonical(scenario: dict[str, Any]) -> bytes:
    """The bytes a ScenarioRef hashes: compact JSON with sorted keys (floats round-trip exactly,
    so the worker builds the very scenario the job holds)."""
    return json.dumps(scenario, sort_keys=True, separators=(",", ":"),
                      allow_nan=False).encode()


def reference(scenario: dict[str, Any]) -> ScenarioRef:
    data = canonical(scenario)
    return ScenarioRef(sha256=hashlib.sha256(data).hexdigest(), bytes=len(data))


def by_reference(spec: CellSpec, inline_bytes: int = INLINE_SCENARIO_BYTES) -> CellSpec:
    """The cell as a lease carries it: a map cell's scenario over ``inline_bytes`` of canonical
    JSON is replaced by its ScenarioRef; anything else unchanged."""
    if not isinstance(spec, MapCell) or spec.scenario is None:
        return spec
    ref = reference(spec.scenario)
    if ref.bytes <= inline_bytes:
        return spec
    return spec.model_copy(update={"scenario": None, "scenario_ref": ref})


def request_proof(capability: str, lease_id: str, sha256: str) -> str:
    """HMAC-SHA256 with the lease's capability over (purpose, lease, hash): a request made
    without the lease's secret, or for another scenario, is refused."""
    text = f"scenario\n{lease_id}\n{sha256}"
    return hmac.new(capability.encode(), text.encode(), hashlib.sha256).hexdigest()


class ByteLRU:
    """A thread-safe least-recently-used map of bytes values, bounded by their total length."""

    def __init__(self, max_bytes: int):
        self.max_bytes = int(max_bytes)
        self._items: OrderedDict[str, bytes] = OrderedDict()
        self._size = 0
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    @property
    def size(self) -> int:
        return self._size

    def __len__(self) -> int:
        return len(self._items)

    def get(self, key: str) -> bytes | None:
        with self._lock:
            value = self._items.get(key)
            if value is None:
                self.misses += 1
                return None
            self._items.move_to_end(key)
            self.hits += 1
            return value

    def put(self, key: str, value: bytes) -> None:
        if len(value) > self.max_bytes:
            return  # larger than the whole cache: not kept
        with self._lock:
            old = self._items.pop(key, None)
            if old is not None:
                self._size -= len(old)
            self._items[key] = value
            self._size += len(value)
            while self._size > self.max_bytes:
                _key, dropped = self._items.popitem(last=False)
                self._size -= len(dropped)


#: (worker, capability, state, the ScenarioRef its lease carries or None) of a lease, or None
LeaseLookup = Callable[[str], tuple[str, str, str, ScenarioRef | None] | None]
#: the full scenario of a lease's cell
ScenarioLoad = Callable[[str], dict[str, Any] | None]


def answer(key: str, payload: bytes, lookup: LeaseLookup, load: ScenarioLoad,
           cache: ByteLRU) -> bytes:
    """The coordinator's reply to a query on ``<prefix>/scenarios/<sha256>`` (``key``): the
    canonical JSON of the scenario, or :class:`ScenarioRefused` naming why. Answered only when
    the request is proven with the capability of a lease (not cancelled) held by the asking
    worker whose cell carries exactly that ScenarioRef."""
    sha256 = key.rsplit("/", 1)[-1]
    try:
        req = decode(ScenarioRequest, payload)
    except Exception as exc:
        raise ScenarioRefused(f"malformed scenario request: {' '.join(str(exc).split())[:200]}"
                              ) from None
    found = lookup(req.lease_id)
    if found is None:
        raise ScenarioRefused(f"unknown lease {req.lease_id}")
    worker, capability, state, ref = found
    if worker != req.worker or not hmac.compare_digest(
            request_proof(capability, req.lease_id, sha256), req.proof):
        raise ScenarioRefused(f"lease {req.lease_id}: not proven by its holder")
    if state == "cancelled":  # an expired lease's late results still count: it is answered
        raise ScenarioRefused(f"lease {req.lease_id} is {state}")
    if ref is None or ref.sha256 != sha256:
        raise ScenarioRefused(f"lease {req.lease_id}: its cell has no scenario {sha256}")
    data = cache.get(sha256)
    if data is None:
        scenario = load(req.lease_id)
        data = b"" if scenario is None else canonical(scenario)
        if hashlib.sha256(data).hexdigest() != sha256:  # pragma: no cover - cells never change
            raise ScenarioRefused(f"lease {req.lease_id}: its stored scenario is not {sha256}")
        cache.put(sha256, data)
    return data


#: fetch(key, payload) -> the reply payload; raises with the reason when there is none
Fetch = Callable[[str, bytes], bytes]


def resolve(lease: Lease, key: str, fetch: Fetch, cache: ByteLRU) -> Lease:
    """The lease with its scenario in place (unchanged when it carries no ScenarioRef): from
    ``cache``, or fetched with ``fetch(key, ScenarioRequest)``, checked against the hash and
    length and then cached. Raises :class:`ScenarioUnavailable` naming the map and the reason."""
    spec = lease.spec
    if not isinstance(spec, MapCell) or spec.scenario_ref is None:
        return lease
    ref = spec.scenario_ref
    data = cache.get(ref.sha256)
    if data is None:
        request = ScenarioRequest(worker=lease.worker, lease_id=lease.lease_id,
                                  proof=request_proof(lease.capability, lease.lease_id,
                                                      ref.sha256))
        try:
            data = fetch(key, request.model_dump_json().encode())
        except Exception as exc:
            raise ScenarioUnavailable(
                f"map {spec.map}: the coordinator did not send scenario {ref.sha256[:16]}: "
                f"{' '.join(str(exc).split())[:300]}",
                transient=isinstance(exc, TimeoutError)) from None
        if len(data) != ref.bytes or len(data) > MAX_SCENARIO_BYTES or \
                hashlib.sha256(data).hexdigest() != ref.sha256:
            raise ScenarioUnavailable(
                f"map {spec.map}: the scenario received ({len(data)} bytes) does not match its "
                f"reference (sha256 {ref.sha256[:16]}..., {ref.bytes} bytes)")
        cache.put(ref.sha256, data)
    try:
        scenario = json.loads(data)
    except ValueError as exc:  # pragma: no cover - the hash matched the coordinator's JSON
        raise ScenarioUnavailable(f"map {spec.map}: scenario is not JSON: {exc}") from None
    cell = spec.model_copy(update={"scenario": scenario, "scenario_ref": None})
    return lease.model_copy(update={"spec": cell})
