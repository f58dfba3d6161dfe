"""POST /maps (nav2 YAML + image, MovingAI .map), GET /maps, map jobs that name an uploaded map,
durability across a coordinator restart, and the size limits (413/422 naming the limit)."""

from __future__ import annotations

import base64
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from swarmpath.service.http.app import create_app
from swarmpath.service.settings import CoordinatorSettings
from swarmpath.world.importers import MAX_CELLS, MAX_OBSTACLES
from test_service_buckets import work_off

DATA = Path(__file__).parent / "data"
ARENA = (DATA / "arena.map").read_text()


def _app(data_dir: Path):
    return create_app(CoordinatorSettings(data_dir=data_dir), use_zenoh=False)


@pytest.fixture
def data_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    return tmp_path / "data"


def _nav2_body() -> dict:
    return {"name": "tb3", "format": "nav2",
            "yaml": (DATA / "tb3_sandbox.yaml").read_text(),
            "image": base64.b64encode((DATA / "tb3_sandbox.pgm").read_bytes()).decode()}


def test_upload_list_read_and_use_in_a_job_across_a_restart(data_dir: Path) -> None:
    with TestClient(_app(data_dir)) as client:
        up = client.post("/maps", json={"name": "arena", "format": "movingai", "map": ARENA,
                                        "resolution": 0.5})
        assert up.status_code == 201, up.text
        arena = up.json()
        assert arena["size"] == [24.5, 24.5] and arena["obstacles"] > 0
        nav = client.post("/maps", json=_nav2_body())
        assert nav.status_code == 201, nav.text
        tb3 = nav.json()
        assert tb3["format"] == "nav2" and tb3["size"] == pytest.approx([19.2, 19.2])
        listed = client.get("/maps").json()
        assert {m["id"] for m in listed} == {arena["id"], tb3["id"]}
        job = client.post("/jobs", json={
            "kind": "map", "planners": ["OMPL-RRTstar"], "runs": 1,
            "maps": [{"map": arena["id"], "start": [0.75, 1.25], "goal": [23.25, 23.75]},
                     {"map": tb3["id"]}],
        })
        assert job.status_code == 201, job.text
        job_id = job.json()["id"]
    with TestClient(_app(data_dir)) as client:  # a restarted coordinator lost nothing
        read = client.get(f"/maps/{arena['id']}").json()
        assert read["scenario"]["size"] == [24.5, 24.5] and read["name"] == "arena"
        status = client.get(f"/jobs/{job_id}").json()
        assert status["runs_total"] == 2
        spec = client.app.state.core.store.job_spec(job_id)  # type: ignore[attr-defined]
        first, second = spec.maps  # the job carries the scenarios, not references
        # named as uploaded (the job page shows the name), the id in the description
        assert first["name"] == "arena" and first["start"] == [0.75, 1.25]
        assert first["description"].startswith(f"uploaded map {arena['id']}")
        # GET /maps and a job's start/goal are in the map's own frame (nav2: its YAML origin);
        # the job's scenario keeps the scenario frame
        assert (arena["frame"], arena["origin"]) == ("scenario", [0.0, 0.0])
        assert (tb3["frame"], tb3["origin"]) == ("map", [-10.0, -10.0])
        assert second["name"] == "tb3" and second["goal"] == pytest.approx(
            [tb3["goal"][0] + 10.0, tb3["goal"][1] + 10.0])
        assert second["grid"]["origin"] == [-10.0, -10.0]


def test_unknown_map_and_bad_start_name_the_field(data_dir: Path) -> None:
    with TestClient(_app(data_dir)) as client:
        arena = client.post("/maps", json={"name": "arena", "format": "movingai",
                                           "map": ARENA}).json()
        r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"],
                                       "maps": [{"map": "map-nothere"}]})
        assert r.status_code == 422
        assert r.json()["detail"][0]["loc"] == ["body", "maps", 0, "map"]
        r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"],
                                       "maps": [{"map": arena["id"], "start": [0.5, 0.5]}]})
        assert r.status_code == 422  # the corner cell of arena is blocked
        assert r.json()["detail"][0]["loc"] == ["body", "maps", 0, "start"]
        assert client.get("/maps/map-nothere").status_code == 404


@pytest.mark.parametrize(
    ("body", "status", "field", "words"),
    [
        ({"name": "big", "format": "movingai",  # refused on its header, before the grid
          "map": "type octile\nheight 2100\nwidth 2000\nmap\n" + ("." * 2000 + "\n") * 10},
         413, "map", f"max_cells={MAX_CELLS:,}"),
        ({"name": "noise", "format": "movingai",  # a checkerboard: 5,500 single cells
          "map": "type octile\nheight 110\nwidth 100\nmap\n"
          + "\n".join(("@." if r % 2 else ".@") * 50 for r in range(110)) + "\n"},
         413, "map", f"max_obstacles={MAX_OBSTACLES:,}"),
        ({"name": "bad", "format": "movingai",
          "map": "type octile\nheight 2\nwidth 2\nmap\n.x\n..\n"},
         422, "map", "unknown terrain"),
        ({"name": "nav", "format": "nav2", "yaml": "image: m.pgm\nresolution: 0.05\n"
          "origin: [0, 0, 0]\n", "image": "!!!"}, 422, "image", "base64"),
        ({"name": "nav", "format": "nav2", "image": "AAAA"}, 422, "yaml", "required"),
    ],
)
def test_limits_and_bad_uploads(data_dir: Path, body: dict, status: int, field: str,
                                words: str) -> None:
    with TestClient(_app(data_dir)) as client:
        r = client.post("/maps", json=body)
        assert r.status_code == status, r.text
        detail = r.json()["detail"][0]
        assert detail["loc"] == ["body", field] and words in detail["msg"]


def _walled_pgm(width: int, height: int) -> bytes:
    """A nav2 PGM (P5): free (254) cells inside a one-cell border wall, with two inner walls."""
    import numpy as np

    img = np.full((height, width), 254, dtype=np.uint8)
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    img[: height * 2 // 3, width // 3] = 0
    img[height // 3:, 2 * width // 3] = 0
    return f"P5\n{width} {height}\n255\n".encode() + img.tobytes()


BIG_YAML = ("image: big.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n")


def test_map_uploads_have_their_own_body_limit(data_dir: Path) -> None:
    """A 1.8 MB PGM (2.4 MB of base64) is over the 1 MB limit of the other routes but within
    max_map_upload_bytes; over that setting the upload is a 413 naming it, and /jobs keeps its
    small limit."""
    image = base64.b64encode(_walled_pgm(1500, 1200)).decode()
    assert len(image) > 2_000_000
    with TestClient(_app(data_dir)) as client:
        r = client.post("/maps", json={"name": "big", "format": "nav2", "yaml": BIG_YAML,
                                       "image": image})
        assert r.status_code == 201, r.text
        assert r.json()["size"] == pytest.approx([75.0, 60.0])
        r = client.post("/jobs", json={"kind": "map", "planners": ["MFB"],
                                       "maps": ["x" * 1_100_000]})
        assert r.status_code == 422 and "exceeds 1000000 bytes" in r.text
    small = create_app(CoordinatorSettings(data_dir=data_dir, max_map_upload_bytes=1_000_000),
                       use_zenoh=False)
    with TestClient(small) as client:
        r = client.post("/maps", json={"name": "big", "format": "nav2", "yaml": BIG_YAML,
                                       "image": image})
        assert r.status_code == 413
        msg = r.json()["detail"][0]["msg"]
        assert "exceeds 1000000 bytes" in msg and "max_map_upload_bytes" in msg


def test_a_job_on_an_uploaded_map_is_worked_off(data_dir: Path) -> None:
    """A worker runs the cells of an uploaded map from the scenario the job carries."""
    with TestClient(_app(data_dir)) as client:
        arena = client.post("/maps", json={"name": "arena", "format": "movingai",
                                           "map": ARENA}).json()
        job = client.post("/jobs", json={
            "kind": "map", "planners": ["OMPL-RRTstar"], "runs": 2, "seed": 3,
            "params": {"OMPL-RRTstar": {"iterations": 2000}}, "maps": [{"map": arena["id"]}],
        }).json()
        assert work_off(client, job["id"]) == 2
        status = client.get(f"/jobs/{job['id']}").json()
        assert status["state"] == "done" and status["runs_done"] + status["runs_failed"] == 2
        rows = client.get(f"/jobs/{job['id']}/summary").json()["rows"]
        assert rows[0]["map"] == "arena" and rows[0]["runs"] == 2  # named as uploaded
        assert rows[0]["success_rate"] == 1.0 and rows[0]["collisions"] == 0
        assert rows[0]["gap_mean"] > 0  # the workers computed the uploaded map's exact optimum


def test_upload_map_command_bodies_and_the_client(data_dir: Path, tmp_path: Path) -> None:
    """`swarmpath upload-map FILE`: the body it sends for each format, bad arguments exit 2
    naming them, and the client's upload against the app."""
    from typer.testing import CliRunner

    from swarmpath.cli import app as cli
    from swarmpath.cli.upload import upload_body
    from swarmpath.service.client import ServiceClient

    nav = upload_body(DATA / "tb3_sandbox.yaml", None, None)
    assert nav["name"] == "tb3_sandbox" and nav["format"] == "nav2"
    assert base64.b64decode(nav["image"]) == (DATA / "tb3_sandbox.pgm").read_bytes()
    grid = upload_body(DATA / "arena.map", "a1", 0.25)
    assert grid == {"name": "a1", "format": "movingai", "map": ARENA, "resolution": 0.25}
    runner = CliRunner()
    for args, option in ((["upload-map", str(tmp_path / "none.map")], "FILE"),
                         (["upload-map", str(DATA / "arena.map.scen")], "FILE"),
                         (["upload-map", str(DATA / "tb3_sandbox.yaml"), "--resolution", "2"],
                          "--resolution")):
        result = runner.invoke(cli, args)
        assert result.exit_code == 2 and option in result.stderr
    with TestClient(_app(data_dir)) as c:
        client = ServiceClient("http://testserver", transport=c._transport)
        info = client.upload_map(grid)
        assert info["size"] == [12.25, 12.25] and client.maps()[0]["id"] == info["id"]
        nav_info = client.upload_map(nav)
    # the command's summary prints metres as a user reads them (it printed 10.975000000000001)
    from swarmpath.cli.upload import _point

    assert _point(nav_info["start"]) == \
        f"({nav_info['start'][0]:.6g}, {nav_info['start'][1]:.6g})"
    assert _point([0.47500000000000003, 10.975000000000001]) == "(0.475, 10.975)"


def test_the_grid_limits_are_coordinator_settings_named_in_the_413(data_dir: Path) -> None:
    settings = CoordinatorSettings(data_dir=data_dir, max_map_cells=100, max_map_obstacles=3)
    with TestClient(create_app(settings, use_zenoh=False)) as client:
        r = client.post("/maps", json={"name": "arena", "format": "movingai", "map": ARENA})
        assert r.status_code == 413
        msg = r.json()["detail"][0]["msg"]
        assert "max_cells=100" in msg and "max_map_cells" in msg
        assert "SWARMPATH_MAX_MAP_CELLS" in msg and "--max-cells" not in msg
        checker = "type octile\nheight 4\nwidth 4\nmap\n@.@.\n....\n@.@.\n....\n"
        r = client.post("/maps", json={"name": "c", "format": "movingai", "map": checker})
        assert r.status_code == 413
        msg = r.json()["detail"][0]["msg"]
        assert "max_obstacles=3" in msg and "max_map_obstacles" in msg


def test_a_job_names_its_uploaded_maps_as_they_were_uploaded(data_dir: Path) -> None:
    """A job page named an uploaded map by its id (issue 25): the job's scenario keeps the
    upload's name (the id in its description), and ``name (id)`` only when another map of the
    job has that name; job lists say what the job runs."""
    with TestClient(_app(data_dir)) as client:
        ids = [client.post("/maps", json={"name": "arena", "format": "movingai", "map": ARENA,
                                          "resolution": res}).json()["id"] for res in (0.5, 1.0)]
        job = client.post("/jobs", json={
            "kind": "map", "planners": ["OMPL-RRTstar"], "runs": 1,
            "maps": ["mfb-static", {"map": ids[0]}, {"map": ids[1]}]})
        assert job.status_code == 201, job.text
        spec = client.app.state.core.store.job_spec(job.json()["id"])  # type: ignore[attr-defined]
        assert [m if isinstance(m, str) else m["name"] for m in spec.maps] == [
            "mfb-static", "arena", f"arena ({ids[1]})"]
        assert spec.maps[2]["description"].startswith(f"uploaded map {ids[1]}: imported from")
        twice = client.post("/jobs", json={"kind": "map", "planners": ["OMPL-RRTstar"],
                                           "maps": [{"map": ids[0]}, {"map": ids[0]}]})
        assert twice.status_code == 422 and "duplicate map" in twice.text
        line = f"OMPL-RRTstar x mfb-static, arena, arena ({ids[1]})"
        assert client.get("/jobs").json()[0]["contents"] == line
        assert client.get(f"/jobs/{job.json()['id']}").json()["contents"] == line
        bench = client.post("/jobs", json={
            "kind": "benchmark", "algorithms": ["GWO", "PSO"], "dims": [10, 30], "runs": 2,
            "functions": ["F1-F13", "bbob:f1", "bbob:f2"], "agents": 6, "iterations": 3})
        assert client.get(f"/jobs/{bench.json()['id']}").json()["contents"] == \
            "GWO, PSO x F1-F13, bbob:f1-bbob:f2 x D 10, 30"
