"""MovingAI difficulty curves in the service: a .scen uploaded with its map (POST /maps), a job
naming pairs of it by row or bucket, the cells' buckets in the summary and the dashboard, the
success and gap per planner and bucket (the same rows as ``swarmpath plan --scen``), and bad
input (4xx naming the field)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from swarmpath.evidence.buckets import bucket_rows
from swarmpath.service.http.app import create_app
from swarmpath.service.protocol import Lease, LeaseRequest, decode_work_reply, encode
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.service.worker import execute_lease, pack_batches
from swarmpath.world.movingai_scen import MAX_SCEN_ROWS

DATA = Path(__file__).parent / "data"
ARENA = (DATA / "arena.map").read_text()
SCEN = (DATA / "arena.map.scen").read_text()


@pytest.fixture
def client(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Any:
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app) as c:
        yield c


def _upload(client: Any, scen: str | None = SCEN) -> dict[str, Any]:
    body = {"name": "arena", "format": "movingai", "map": ARENA}
    if scen is not None:
        body["scen"] = scen
    r = client.post("/maps", json=body)
    assert r.status_code == 201, r.text
    return dict(r.json())


def work_off(client: Any, job_id: str) -> int:
    """Every run of the job through a worker's lease, execute and result steps."""
    core = client.app.state.core
    core.publish = lambda key, payload: None
    core.worker_alive("w1")
    done = 0
    reply = decode_work_reply(core.handle_lease_request(
        encode(LeaseRequest(worker="w1", max_runs=20))))
    while isinstance(reply, Lease):
        results = execute_lease(reply)
        for payload in pack_batches("w1", [data for _run, data in results]):
            core.handle_results(f"swarmpath/results/{reply.job_id}", payload)
        done += len(results)
        reply = decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker="w1", max_runs=20))))
    return done


def test_scen_pairs_by_bucket_give_a_difficulty_curve_in_the_summary_and_dashboard(
        client: Any) -> None:
    arena = _upload(client)
    assert arena["scen"] == {"pairs": 160, "buckets": {str(b): 10 for b in range(16)}}
    assert client.get("/maps").json()[0]["scen"]["pairs"] == 160
    # rows 0, 1 (bucket 0), 150, 151 (bucket 15): the first two of each
    spec = {"kind": "map", "planners": ["OMPL-RRTstar", "OMPL-BITstar"], "runs": 2, "seed": 4,
            "params": {"OMPL-RRTstar": {"iterations": 60}, "OMPL-BITstar": {"iterations": 400}},
            "maps": [{"map": arena["id"], "scen": {"buckets": [0, 15], "per_bucket": 2}}]}
    r = client.post("/jobs", json=spec)
    assert r.status_code == 201, r.text
    job = r.json()
    assert job["runs_total"] == 2 * 4 * 2
    assert work_off(client, job["id"]) == 16
    summary = client.get(f"/jobs/{job['id']}/summary").json()
    maps = [f"arena#{i}" for i in (0, 1, 150, 151)]
    assert [r["map"] for r in summary["rows"]] == maps * 2
    assert [r["bucket"] for r in summary["rows"]] == [0, 0, 15, 15] * 2
    assert "bucket" in summary["columns"]

    # the curve is bucket_rows (what swarmpath plan --scen prints) over the runs REST lists
    runs = client.get(f"/jobs/{job['id']}/runs", params={"limit": 100}).json()["items"]
    assert len(runs) == 16
    # each run names its bucket: REST items and the exports' column
    assert [r["bucket"] for r in runs] == [0 if r["map"] in maps[:2] else 15 for r in runs]
    import csv

    limit = csv.field_size_limit(2**31 - 1)  # a path is one JSON cell of the CSV
    try:
        table = list(csv.DictReader(client.get(f"/jobs/{job['id']}/runs",
                                               params={"format": "csv"}).text.splitlines()))
    finally:
        csv.field_size_limit(limit)
    assert [(row["map"], row["bucket"]) for row in table] == [
        (r["map"], str(r["bucket"])) for r in runs]
    expected = bucket_rows(runs, dict.fromkeys(maps[:2], 0) | dict.fromkeys(maps[2:], 15))
    assert summary["buckets"] == expected
    assert [(b["planner"], b["bucket"], b["runs"], b["pairs"]) for b in summary["buckets"]] == [
        (p, b, 4, 2) for p in ("OMPL-RRTstar", "OMPL-BITstar") for b in (0, 15)]
    # hand count of one row: successes and the median gap of the successful runs
    mine = [r for r in runs if r["planner"] == "OMPL-BITstar" and r["map"] in maps[2:]]
    ok = sorted(r["gap"] for r in mine if r["success"])
    row = next(b for b in summary["buckets"] if b["planner"] == "OMPL-BITstar"
               and b["bucket"] == 15)
    assert row["successes"] == len(ok)
    if ok:
        assert row["gap_median"] == pytest.approx((ok[(len(ok) - 1) // 2] + ok[len(ok) // 2]) / 2)
    # a short RRT* budget fails somewhere: the curve is not all ones (it can fail to be flat)
    assert {b["success_rate"] for b in summary["buckets"]} != {1.0}

    # swarmpath results prints the table swarmpath plan --scen prints
    import io

    from swarmpath.cli.results import _summary
    from swarmpath.service.client import ServiceClient

    out = io.StringIO()
    _summary(ServiceClient("http://testserver", transport=client._transport), job["id"],
             "table", out)
    text = out.getvalue()
    assert "Per MovingAI bucket" in text
    for b in summary["buckets"]:
        assert any(line.split()[:4] == [str(b["bucket"]), b["planner"], str(b["pairs"]),
                                        f"{b['successes']}/{b['runs']}"]
                   for line in text.splitlines()), (b, text)

    page = client.get(f"/ui/jobs/{job['id']}/data").json()
    assert page["buckets"] == expected  # the dashboard counts its own aggregates the same
    assert [g["bucket"] for g in page["groups"]] == [0, 0, 15, 15]


def test_scen_pairs_by_row_carry_the_octile_optimum_and_a_spec_bucket_for_inline_maps(
        client: Any) -> None:
    arena = _upload(client)
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "runs": 1,
                                   "maps": [{"map": arena["id"], "scen": {"rows": [3, 40]}}]})
    assert r.status_code == 201, r.text
    spec = client.app.state.core.store.job_spec(r.json()["id"])
    status = client.get(f"/jobs/{r.json()['id']}").json()
    assert "arena#3" in status["contents"] and "arena#40" in status["contents"]
    assert spec.buckets == {"arena#3": 0, "arena#40": 4}
    assert spec.octile["arena#3"] == pytest.approx(3.41421)
    start = next(m for m in spec.maps if m["name"] == "arena#3")["start"]
    assert start == [1.5, 49 - 3 - 0.5]  # cell (1, 3) counts from the top left
    # a preset or inline map may be given a bucket in the spec itself
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "runs": 1,
                                   "maps": ["mfb-static"], "buckets": {"mfb-static": 3}})
    assert r.status_code == 201, r.text
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "runs": 1,
                                   "maps": ["mfb-static"], "buckets": {"nothere": 3}})
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body", "buckets", "nothere"]


BAD_CHOICES = [
    ({"rows": [3, 400]}, ["scen", "rows", 1], "beyond the 160 pairs"),
    ({"buckets": [2, 99]}, ["scen", "buckets", 1], "no pair in bucket 99 (its buckets: 0-15)"),
    ({"rows": [1, 1]}, ["scen", "rows"], "duplicate"),
    ({"rows": [1], "buckets": [2]}, ["scen", "rows"], "either rows or buckets"),
    ({"buckets": [1], "per_bucket": 0}, ["scen", "per_bucket"], "greater than or equal to 1"),
    ({"buckets": list(range(16)), "per_bucket": 40}, ["scen", "per_bucket"], "over 500 pairs"),
    ({"rowz": [1]}, ["scen", "rowz"], "xtra"),
    ({"rows": [-1]}, ["scen", "rows", 0], "greater than or equal to 0"),
]


@pytest.mark.parametrize(("choice", "loc", "words"), BAD_CHOICES)
def test_a_bad_choice_of_pairs_is_a_422_naming_the_field(client: Any, choice: dict[str, Any],
                                                         loc: list[Any], words: str) -> None:
    arena = _upload(client)
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"],
                                   "maps": ["mfb-static", {"map": arena["id"], "scen": choice}]})
    assert r.status_code == 422, r.text
    detail = r.json()["detail"]
    assert any(d["loc"] == ["body", "maps", 1, *loc] and words in d["msg"] for d in detail), \
        detail


def test_pairs_need_a_scen_and_set_the_endpoints_and_blocked_cells_are_refused(
        client: Any) -> None:
    plain = _upload(client, scen=None)
    assert plain["scen"] is None
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"],
                                   "maps": [{"map": plain["id"], "scen": {"rows": [0]}}]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body", "maps", 0, "scen"]
    assert "without a .scen" in r.json()["detail"][0]["msg"]
    arena = _upload(client)
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "maps": [
        {"map": arena["id"], "start": [5.5, 5.5], "scen": {"rows": [0]}}]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["body", "maps", 0, "scen"]
    assert "leave start out" in r.json()["detail"][0]["msg"]
    # a pair whose start is a blocked cell (arena's corner (0, 0)) names its place in rows
    blocked = _upload(client, "version 1\n0\tarena.map\t49\t49\t1\t11\t1\t12\t1\n"
                              "0\tarena.map\t49\t49\t0\t0\t1\t12\t12\n")
    r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"], "maps": [
        {"map": blocked["id"], "scen": {"rows": [0, 1]}}]})
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert detail[0]["loc"] == ["body", "maps", 0, "scen", "rows", 1], detail
    assert "row 1: start" in detail[0]["msg"]


@pytest.mark.parametrize(
    ("scen", "status", "words"),
    [
        ("1\tarena.map\t49\t49\t1\t1\t2\t2\t1.4\n", 422, "first line must be 'version 1'"),
        ("version 1\n0\tarena.map\t50\t49\t1\t1\t2\t2\t1.4\n", 422,
         "line 2: a pair of a 50 x 49 map"),
        ("version 1\n0\tarena.map\t49\t49\t1\t49\t2\t2\t1.4\n", 422, "outside the 49 x 49"),
        ("version 1\n0\tarena.map\t49\t49\t1\t1\t2\n", 422, "expected 9 columns"),
        ("version 1\nx\tarena.map\t49\t49\t1\t1\t2\t2\t1.4\n", 422, "integers"),
        ("version 1\n0\tarena.map\t49\t49\t1\t1\t2\t2\tnan\n", 422, "finite"),
        ("version 1\n-2\tarena.map\t49\t49\t1\t1\t2\t2\t1\n", 422, "bucket -2"),
        ("version 1\n" + "0\ta\t49\t49\t1\t11\t1\t12\t1\n" * (MAX_SCEN_ROWS + 1), 413,
         f"more than {MAX_SCEN_ROWS:,} pairs"),
    ],
)
def test_a_bad_scen_upload_is_refused_naming_scen(client: Any, scen: str, status: int,
                                                  words: str) -> None:
    r = client.post("/maps", json={"name": "arena", "format": "movingai", "map": ARENA,
                                   "scen": scen})
    assert r.status_code == status, r.text
    detail = r.json()["detail"][0]
    assert detail["loc"] == ["body", "scen"] and words in detail["msg"], detail
    assert client.get("/maps").json() == []  # nothing half-stored


def test_a_nav2_upload_takes_no_scen(client: Any) -> None:
    r = client.post("/maps", json={"name": "tb3", "format": "nav2", "yaml": "image: m.pgm\n",
                                   "image": "AAAA", "scen": "version 1\n"})
    assert r.status_code == 422
    assert any(d["loc"] == ["body", "scen"] for d in r.json()["detail"]), r.json()


def test_upload_map_sends_the_scen_and_refuses_it_where_it_does_not_apply(
        client: Any, tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from swarmpath.cli import app as cli
    from swarmpath.cli.upload import _pairs, upload_body
    from swarmpath.service.client import ServiceClient

    body = upload_body(DATA / "arena.map", None, None, DATA / "arena.map.scen")
    assert body == {"name": "arena", "format": "movingai", "map": ARENA, "scen": SCEN}
    info = ServiceClient("http://testserver", transport=client._transport).upload_map(body)
    assert info["scen"]["pairs"] == 160
    assert _pairs(info) == "; 160 .scen pairs in buckets 0-15"
    runner = CliRunner()
    for args in (["upload-map", str(DATA / "tb3_sandbox.yaml"), "--scen",
                  str(DATA / "arena.map.scen")],
                 ["upload-map", str(DATA / "arena.map"), "--scen", str(tmp_path / "none")]):
        result = runner.invoke(cli, args)
        assert result.exit_code == 2 and "--scen" in result.stderr, result.stderr
