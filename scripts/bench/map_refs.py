#!/usr/bin/env python3
"""A real-size uploaded map through the coordinator, in process (no network): what a lease
weighs when it names the scenario by hash, and what the fetch costs on each side.

    .venv/bin/python scripts/bench/map_refs.py [--width 1500] [--height 1200] [--spacing 150]

Builds a nav2 PGM of ``--width`` x ``--height`` cells (5 cm) with a border wall and plus-shaped
pillars every ``--spacing`` cells (tests/test_service_map_refs.py's map at the defaults), then
times: POST /maps (base64 upload, import), POST /jobs naming it, one lease request, the
coordinator's answer to the scenario query (first: reads the cell and hashes; then: from its
cache) and the worker's check of the reply (hash and JSON parse). Markdown on stdout.
"""

from __future__ import annotations

import argparse
import base64
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "services"))
sys.path.insert(0, str(ROOT / "tests"))

from fastapi.testclient import TestClient  # noqa: E402

from swarmpath.service.http.app import create_app  # noqa: E402
from swarmpath.service.protocol import (  # noqa: E402
    Keys,
    LeaseRequest,
    MapCell,
    ScenarioRequest,
    decode_work_reply,
    encode,
)
from swarmpath.service.scenarios import ByteLRU, answer, request_proof, resolve  # noqa: E402
from swarmpath.service.settings import CoordinatorSettings  # noqa: E402
from test_service_map_refs import YAML, pillars_pgm  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=1500)
    ap.add_argument("--height", type=int, default=1200)
    ap.add_argument("--spacing", type=int, default=150)
    args = ap.parse_args()
    os.environ.pop("SWARMPATH_TOKEN", None)
    image = pillars_pgm(args.width, args.height, args.spacing)
    body = {"name": "pillars", "format": "nav2", "yaml": YAML,
            "image": base64.b64encode(image).decode()}
    rows: list[tuple[str, str]] = []
    with tempfile.TemporaryDirectory() as tmp, TestClient(create_app(
            CoordinatorSettings(data_dir=Path(tmp) / "data"), use_zenoh=False)) as client:
        t = time.perf_counter()
        up = client.post("/maps", json=body)
        rows.append(("POST /maps (upload + import)", f"{time.perf_counter() - t:.2f} s"))
        assert up.status_code == 201, up.text
        info = up.json()
        t = time.perf_counter()
        job = client.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"],
                                         "runs": 10, "maps": [{"map": info["id"]}]})
        rows.append(("POST /jobs naming it", f"{time.perf_counter() - t:.2f} s"))
        assert job.status_code == 201, job.text
        core = client.app.state.core  # type: ignore[attr-defined]
        core.publish = lambda key, payload: None
        core.worker_alive("w1")
        t = time.perf_counter()
        lease = core.handle_lease_request(encode(LeaseRequest(worker="w1", max_runs=10)))
        rows.append(("lease request (first: parses and hashes the cell)",
                     f"{(time.perf_counter() - t) * 1e3:.1f} ms"))
        got = decode_work_reply(lease)
        spec = got.spec  # type: ignore[union-attr]
        assert isinstance(spec, MapCell) and spec.scenario_ref is not None
        ref = spec.scenario_ref
        key = Keys().scenario(ref.sha256)
        req = ScenarioRequest(worker="w1", lease_id=got.lease_id,  # type: ignore[union-attr]
                              proof=request_proof(got.capability,  # type: ignore[union-attr]
                                                  got.lease_id,  # type: ignore[union-attr]
                                                  ref.sha256)).model_dump_json().encode()
        cache = ByteLRU(1 << 27)
        store = core.store
        times = []
        for _ in range(3):
            t = time.perf_counter()
            data = answer(key, req, store.lease_scenario_ref, store.lease_scenario, cache)
            times.append(time.perf_counter() - t)
        t = time.perf_counter()
        resolve(got, key, lambda _k, _p: data, ByteLRU(1 << 27))  # type: ignore[arg-type]
        check = time.perf_counter() - t
    rows = [
        ("grid", f"{args.width} x {args.height} cells, {len(image):,} bytes of PGM, "
                 f"{len(body['image']):,} bytes of base64"),
        ("imported", f"{info['obstacles']} obstacles, scenario {ref.bytes:,} bytes of "
                     "canonical JSON"),
        *rows,
        ("lease JSON (names the scenario)", f"{len(lease):,} bytes"),
        ("scenario answer, first (reads the cell, hashes)", f"{times[0] * 1e3:.1f} ms"),
        ("scenario answer, cached", f"{min(times[1:]) * 1e3:.2f} ms"),
        ("worker check (SHA-256, JSON parse)", f"{check * 1e3:.1f} ms"),
    ]
    print(f"load average before: {os.getloadavg()[0]:.1f}\n")
    print("| what | value |\n| --- | --- |")
    for what, value in rows:
        print(f"| {what} | {value} |")


if __name__ == "__main__":
    main()
