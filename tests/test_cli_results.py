"""The result commands against the coordinator's app in-process (no network): cancel, download,
per-run exports, IOHprofiler files and plots of a finished job."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

import swarmpath.cli.service as service_cli
from swarmpath.cli import app as cli_app
from swarmpath.service.client import ServiceClient
from swarmpath.service.coordinator import CoordinatorSettings, create_app
from swarmpath.service.protocol import Lease, LeaseRequest, decode_work_reply, encode
from swarmpath.service.worker import execute_lease, pack_batches

BENCH = {
    "kind": "benchmark", "algorithms": ["GWO", "PSO"], "functions": ["F1", "F8"], "dims": [2],
    "runs": 3, "agents": 6, "iterations": 10, "seed": 4,
}
MAPS = {"kind": "map", "planners": ["OMPL-RRTstar"], "maps": ["mfb-static"], "runs": 2,
        "seed": 2, "params": {"OMPL-RRTstar": {"iterations": 1000}}}


@pytest.fixture
def service(tmp_path, monkeypatch):
    """(cli(*args), http client, core) against one in-process coordinator."""
    monkeypatch.delenv("SWARMPATH_TOKEN", raising=False)
    monkeypatch.chdir(tmp_path)
    app = create_app(CoordinatorSettings(data_dir=tmp_path / "data"), use_zenoh=False)
    with TestClient(app) as http:
        monkeypatch.setattr(service_cli, "_client",
                            lambda url: ServiceClient("http://testserver",
                                                      transport=http._transport))
        runner = CliRunner()
        app.state.core.publish = lambda key, payload: None
        yield (lambda *args: runner.invoke(cli_app, list(args))), http, app.state.core


def work_off(core) -> int:
    core.worker_alive("w1")
    n = 0
    while isinstance(lease := decode_work_reply(core.handle_lease_request(
            encode(LeaseRequest(worker="w1", max_runs=100)))), Lease):
        results = execute_lease(lease)
        for payload in pack_batches("w1", [data for _run, data in results]):
            core.handle_results(f"swarmpath/results/{lease.job_id}", payload)
        n += len(results)
    return n


def finished(service, spec) -> str:
    _cli, http, core = service
    job = http.post("/jobs", json=spec).json()["id"]
    work_off(core)
    assert http.get(f"/jobs/{job}").json()["state"] == "done"
    return job


def test_cancel_cancels_and_prints_the_state(service):
    cli, http, _core = service
    job = http.post("/jobs", json=BENCH).json()["id"]
    result = cli("cancel", job)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.strip() == f"job {job}: cancelled (0/12 runs finished, 0 failed)"
    assert http.get(f"/jobs/{job}").json()["state"] == "cancelled"
    bad = cli("cancel", "nosuchjob")
    assert bad.exit_code == 2 and bad.stderr.count("\n") == 1 and "JOB" in bad.stderr


def test_download_without_output_writes_job_mcap_here(service):
    cli, _http, _core = service
    job = finished(service, BENCH)
    result = cli("download", job)
    assert result.exit_code == 0, result.stderr
    data = Path(f"{job}.mcap").read_bytes()
    assert data.startswith(b"\x89MCAP0\r\n") and len(data) > 1000


def test_results_and_status_tables_explain_their_columns(service):
    cli = service[0]
    job = finished(service, MAPS)
    table = cli("results", job)
    assert table.exit_code == 0, table.stderr
    out = " ".join(table.stdout.split())
    assert "failed: runs that crashed" in out and "not failed" in out
    assert "collisions: simulated steps in which the robot body touched an obstacle, summed" in out
    assert "gap_mean: " in out and "moving obstacles" in out
    status = " ".join(cli("status").stdout.split())
    assert "failed: runs that crashed" in status and "gap_mean" not in status


@pytest.mark.parametrize("width", [80, 200, 400])
def test_summary_tables_fit_the_terminal_and_cut_no_header(service, monkeypatch, width):
    """A map summary has ~48 columns: printed as one table every header was cut to '…' even at
    400 columns (issue 25). Now the columns are split over tables no wider than the terminal,
    each repeating planner and map; columns empty in every row are named, not printed."""
    from rich.console import Console

    cli, http, _core = service
    job = finished(service, {**MAPS, "planners": ["OMPL-RRTstar", "OMPL-BITstar"], "params": {
        "OMPL-RRTstar": {"iterations": 1000}, "OMPL-BITstar": {"iterations": 1000}}})
    monkeypatch.setattr(service_cli, "_console", lambda: Console(width=width))
    result = cli("results", job)
    assert result.exit_code == 0, result.stderr
    summary = http.get(f"/jobs/{job}/summary").json()
    rows = summary["rows"]
    empty = [c for c in summary["columns"]
             if c not in ("planner", "map") and all(r.get(c) is None for r in rows)]
    assert "costmap_cost_mean" in empty  # mfb-static is not a nav2 map
    text = result.stdout
    tables = text.split(f"job {job} (map)")[1:]
    assert len(tables) > 1 if width < 400 else len(tables) >= 1
    header_lines = [t.splitlines()[2] for t in tables]  # title, top rule, the header row
    headers = [h.strip() for line in header_lines for h in line.strip("┃").split("┃")]
    shown = [c for c in summary["columns"] if c not in empty]
    assert sorted(set(headers)) == sorted(shown)  # every non-empty column, whole
    assert headers.count("planner") == headers.count("map") == len(tables)
    assert "…" not in text
    assert max(len(line) for line in text.splitlines() if "┃" in line or "│" in line) <= width
    assert "OMPL-BITstar" in text and "OMPL-RRTstar" in text
    assert "empty in every row, left out: " + ", ".join(empty) in " ".join(text.split())


def test_legend_follows_the_columns_it_is_given():
    from swarmpath.evidence.legend import NOTES, legend

    assert [c for c, _ in legend(["planner", "failed", "Gap (%)", "x"])] == ["failed", "Gap (%)"]
    assert legend(["Collisions"]) == [("Collisions", NOTES["collisions"])]


# ------------------------------------------------------------------------------ per-run exports
def rest_runs(http, job):
    items = http.get(f"/jobs/{job}/runs", params={"limit": 1000}).json()["items"]
    return [http.get(f"/jobs/{job}/runs/{i['run_id']}").json() for i in items]


def test_runs_export_in_every_format_holds_every_run_with_its_curve(service, tmp_path):
    import pandas as pd

    from swarmpath.evidence import exports

    cli, http, _core = service
    job = finished(service, BENCH)
    expected = rest_runs(http, job)
    frames = {}
    for fmt in exports.FORMATS:
        out = tmp_path / f"runs.{fmt}"
        result = cli("results", job, "--runs", "--format", fmt, "-o", str(out))
        assert result.exit_code == 0, result.stderr
        frames[fmt] = exports.load_results(out)
    names = [n for n, _ in exports.BENCHMARK_COLUMNS]
    for fmt, df in frames.items():
        assert list(df.columns) == names, fmt
        assert len(df) == 12 and df["run_id"].tolist() == list(range(12))
        assert (df["job_id"] == job).all() and (df["iterations"] == 10).all()
        for row, item in zip(df.to_dict("records"), expected, strict=True):
            assert (row["algorithm"], row["function"], row["dim"], row["run"]) == (
                item["algorithm"], item["function"], item["dim"], item["run"])
            assert row["best_fitness"] == item["best_fitness"]
            assert list(row["curve"]) == item["curve"] and len(row["curve"]) == 10
            assert list(row["best_position"]) == item["best_position"]
            # CPU beside wall time, as the worker measured it (REST and every export)
            assert isinstance(item["cpu_seconds"], float) and item["cpu_seconds"] >= 0.0
            assert row["cpu_seconds"] == pytest.approx(item["cpu_seconds"], rel=1e-15)
    summary = http.get(f"/jobs/{job}/summary").json()
    assert all(r["cpu_seconds_mean"] >= 0.0 for r in summary["rows"])
    csv_head = http.get(f"/jobs/{job}/summary", params={"format": "csv"}).text.splitlines()[0]
    assert "seconds_mean,cpu_seconds_mean" in csv_head
    pd.testing.assert_frame_equal(frames["csv"].drop(columns=["curve", "best_position",
                                                              "worker", "failure",
                                                              "curve_stride"]),
                                  frames["parquet"].drop(columns=["curve", "best_position",
                                                                  "worker", "failure",
                                                                  "curve_stride"]),
                                  check_dtype=False)


def test_rest_streams_runs_as_csv_and_parquet(service):
    import io

    import pyarrow as pa
    import pyarrow.parquet as pq

    from swarmpath.evidence import exports

    _cli, http, _core = service
    job = finished(service, MAPS)
    csv = http.get(f"/jobs/{job}/runs", params={"format": "csv"})
    assert csv.status_code == 200 and csv.headers["content-type"].startswith("text/csv")
    lines = csv.text.splitlines()
    assert lines[0].split(",") == [n for n, _ in exports.map_columns()]
    assert len(lines) == 3
    pq_bytes = http.get(f"/jobs/{job}/runs", params={"format": "parquet"}).content
    table = pq.read_table(io.BytesIO(pq_bytes))
    assert table.num_rows == 2
    assert table.schema.field("path").type == pa.list_(pa.list_(pa.float64()))
    paths = table.column("path").to_pylist()
    for run_id, path in enumerate(paths):
        assert path == http.get(f"/jobs/{job}/runs/{run_id}").json()["path"]
        assert path[0][:2] == [0.0, 0.0] and len(path[0]) == 3
    # (OMPL with a 0.1 s budget may miss on a loaded machine: compare, do not assume success)
    assert table.column("success").to_pylist() == [
        http.get(f"/jobs/{job}/runs/{i}").json()["success"] for i in range(2)]
    assert "planned_length" in table.column_names  # every RunOutcome field is a column


def test_load_results_of_a_job_id_asks_the_coordinator(service, monkeypatch):
    import swarmpath.service.client as client_module
    from swarmpath import load_results

    _cli, http, _core = service
    job = finished(service, BENCH)
    real = client_module.ServiceClient
    monkeypatch.setattr(client_module, "ServiceClient",
                        lambda url=None: real("http://testserver", transport=http._transport))
    df = load_results(job)
    assert len(df) == 12
    assert df["best_fitness"].tolist() == [i["best_fitness"] for i in rest_runs(http, job)]


def test_runs_export_errors_name_the_option(service, tmp_path):
    cli, _http, _core = service
    job = finished(service, BENCH)
    for args, option in [
        (["--runs", "--format", "xml"], "--format"),
        (["--runs", "--format", "parquet"], "--output"),
        (["--format", "ioh"], "--output"),
        (["--runs", "--format", "csv", "-o", str(tmp_path / "no" / "x.csv")], "--output"),
    ]:
        result = cli("results", job, *args)
        assert result.exit_code == 2, (args, result.stdout)
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and option in lines[0], (args, lines)
    maps = finished(service, MAPS)
    result = cli("results", maps, "--format", "ioh", "-o", str(tmp_path / "ioh"))
    assert result.exit_code == 2 and "benchmark job" in result.stderr


def test_results_output_format_follows_its_extension(service, tmp_path):
    """README's `results JOB --runs -o runs.parquet` wrote CSV into the .parquet file (issue
    25): without --format the extension decides; a --format the extension contradicts is
    refused naming --output; the summary goes into -o too (it went to stdout)."""
    import pyarrow.parquet as pq

    cli, http, _core = service
    job = finished(service, BENCH)
    result = cli("results", job, "--runs", "-o", str(tmp_path / "runs.parquet"))
    assert result.exit_code == 0, result.stderr
    assert pq.read_table(tmp_path / "runs.parquet").num_rows == 12
    assert cli("results", job, "--runs", "-o", str(tmp_path / "runs.json")).exit_code == 0
    assert len(json.loads((tmp_path / "runs.json").read_text())) == 12
    assert cli("results", job, "--runs", "-o", str(tmp_path / "runs.txt")).exit_code == 0
    assert (tmp_path / "runs.txt").read_text().count("\n") == 13  # csv: header and 12 rows
    bad = cli("results", job, "--runs", "--format", "csv", "-o", str(tmp_path / "r.parquet"))
    assert bad.exit_code == 2 and "--output" in bad.stderr and "parquet" in bad.stderr
    assert not (tmp_path / "r.parquet").exists()
    summary = http.get(f"/jobs/{job}/summary").json()
    assert cli("results", job, "-o", str(tmp_path / "summary.json")).exit_code == 0
    assert json.loads((tmp_path / "summary.json").read_text())["rows"] == summary["rows"]
    assert cli("results", job, "-o", str(tmp_path / "summary.csv")).exit_code == 0
    assert (tmp_path / "summary.csv").read_text().splitlines()[0].startswith("algorithm,")
    table = cli("results", job, "-o", str(tmp_path / "summary.txt"))
    assert table.exit_code == 0 and table.stdout == ""
    assert "GWO" in (tmp_path / "summary.txt").read_text()
    wrong = cli("results", job, "-o", str(tmp_path / "summary.parquet"))
    assert wrong.exit_code == 2 and "--format" in wrong.stderr
    missing = cli("results", "nosuchjob", "-o", str(tmp_path / "none.json"))
    assert missing.exit_code == 2 and not (tmp_path / "none.json").exists()


def test_results_plot_writes_the_figures_of_a_job(service, tmp_path):
    cli, _http, _core = service
    job = finished(service, BENCH)
    result = cli("results", job, "--plot", str(tmp_path / "b"))
    assert result.exit_code == 0, result.stderr
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == [
        "box_F1_d2.png", "box_F8_d2.png", "cd-D2.png", "curves_F1_d2.png", "curves_F8_d2.png"]
    maps = finished(service, MAPS)
    result = cli("results", maps, "--plot", str(tmp_path / "m"))
    assert result.exit_code == 0, result.stderr
    assert sorted(p.name for p in (tmp_path / "m").iterdir()) == [
        "OMPL-RRTstar_mfb-static.png", "box_mfb-static.png"]


# ------------------------------------------------------------------------------- IOHprofiler
# The rules of IOHanalyzer's "Supported Data Format" page (github.com/IOHprofiler/IOHanalyzer,
# inst/shiny-server/markdown/dataformat.md) and the .info lines IOHexperimenter writes.
SEPARATOR = '"function evaluation" "best-so-far f(x)"'
NUMBER = r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?"


def parse_info(path: Path) -> list[dict]:
    """Three lines per block: name = value pairs (funcId, DIM, algId mandatory), a line
    starting with a single %, then the raw-data path and instance:evaluations|best per run."""
    import re

    lines = path.read_text().splitlines()
    assert len(lines) % 3 == 0 and lines
    blocks = []
    for i in range(0, len(lines), 3):
        head, comment, data = lines[i:i + 3]
        pairs = dict(p.split(" = ", 1) for p in head.split(", "))
        assert {"funcId", "DIM", "algId"} <= set(pairs)
        assert comment.startswith("%") and not comment.startswith("%%")
        rel, *entries = data.split(", ")
        runs = []
        for e in entries:
            m = re.fullmatch(rf"(\d+):(\d+)\|({NUMBER})", e)
            assert m, e
            runs.append((int(m[1]), int(m[2]), float(m[3])))
        blocks.append({"pairs": pairs, "dat": path.parent / rel, "runs": runs})
    return blocks


def parse_dat(path: Path) -> list[list[tuple[int, float]]]:
    """Blocks separated by the double-quoted separation line; records of two numbers split by a
    single space; evaluations increase, best-so-far never gets worse (minimization)."""
    import re

    blocks: list[list[tuple[int, float]]] = []
    for line in path.read_text().splitlines():
        if line == SEPARATOR:
            blocks.append([])
            continue
        assert re.fullmatch(rf"\d+ {NUMBER}", line), line
        e, v = line.split(" ")
        blocks[-1].append((int(e), float(v)))
    for b in blocks:
        assert b and all(b[k][0] < b[k + 1][0] for k in range(len(b) - 1))
        assert all(b[k][1] >= b[k + 1][1] for k in range(len(b) - 1))
    return blocks


def test_ioh_info_export_follows_the_iohprofiler_format(service, tmp_path):
    from swarmpath.evidence.benchmark_stats import f_star

    cli, http, _core = service
    job = finished(service, BENCH)
    out = tmp_path / "ioh"
    result = cli("results", job, "--format", "ioh-info", "-o", str(out))
    assert result.exit_code == 0, result.stderr
    items = rest_runs(http, job)
    assert sorted(p.name for p in out.iterdir()) == ["GWO", "PSO"]
    for algorithm in ("GWO", "PSO"):
        infos = sorted((out / algorithm).glob("*.info"))
        # stable ids: F8 is IOHanalyzer's f8 although F6-floor is registered before it
        assert [p.name for p in infos] == ["IOHprofiler_f1_F1.info", "IOHprofiler_f8_F8.info"]
        for info in infos:
            (block,) = parse_info(info)
            pairs = block["pairs"]
            function = pairs["funcName"].strip('"')
            assert int(pairs["funcId"]) == int(function[1:])
            assert (pairs["DIM"], pairs["algId"], pairs["maximization"]) == (
                "2", f'"{algorithm}"', '"F"')
            runs = [i for i in items if (i["algorithm"], i["function"]) == (algorithm, function)]
            dat = parse_dat(block["dat"])
            assert len(dat) == len(block["runs"]) == len(runs) == 3
            fs = f_star(function, 2)  # values are f - f* (F8's minimum is negative)
            for (instance, evals, best), records, item in zip(block["runs"], dat, runs,
                                                              strict=True):
                assert instance == 1  # not shifted: one instance
                assert records[-1] == (evals, best)  # each block ends at the last evaluation
                assert evals == item["evaluations"]
                assert best == pytest.approx(item["best_fitness"] - fs, rel=1e-9, abs=1e-300)
                assert records[0][1] == pytest.approx(item["curve"][0] - fs, rel=1e-9)
                assert best >= 0


def test_ioh_export_loads_in_iohinspector(service, tmp_path):
    """The JSON form loads in IOHprofiler's own Python reader with every run, its function id
    and its best value; each run starts at evaluation 1 and never gets worse."""
    import iohinspector

    from swarmpath.evidence.benchmark_stats import f_star

    cli, http, _core = service
    job = finished(service, BENCH)
    out = tmp_path / "ioh"
    result = cli("results", job, "--format", "ioh", "-o", str(out))
    assert result.exit_code == 0, result.stderr
    items = rest_runs(http, job)
    dm = iohinspector.DataManager()
    dm.add_folder(str(out))
    overview = dm.overview
    assert overview.height == len(items) == 12
    assert sorted(set(overview["function_id"].to_list())) == [1, 8]
    assert sorted(set(overview["algorithm_name"].to_list())) == ["GWO", "PSO"]
    expected = sorted(i["best_fitness"] - f_star(i["function"], 2) for i in items)
    assert sorted(overview["best_y"].to_list()) == pytest.approx(expected, rel=1e-9,
                                                                 abs=1e-300)
    data = dm.load(monotonic=False, include_meta_data=True)
    for _, run in data.group_by("data_id"):
        evals, ys = run["evaluations"].to_list(), run["raw_y"].to_list()
        assert evals[0] == 1 and evals == sorted(evals)
        assert all(a >= b for a, b in itertools.pairwise(ys))


def test_ioh_function_ids_are_stable_and_extendable():
    from swarmpath.evidence import ioh

    assert [ioh.function_id(n) for n in ("F1", "F8", "F13", "F23")] == [1, 8, 13, 23]
    assert ioh.function_id("F6-floor") == 106
    # suite functions as their suite numbers them (unique within the suite label)
    assert ioh.function_id("bbob:f3") == 3 and ioh.function_id("cec2022:F12") == 12
    ioh._check_ids(["F3", "bbob:f3"])  # two suite labels: no clash
    assert ioh.function_id("mysuite:g4") == 4
    fallback = ioh.function_id("my-plugin-function")
    assert fallback == ioh.function_id("my-plugin-function") and fallback >= 10_000
    ioh.register_function_id("my-plugin-function", 77)
    try:
        assert ioh.function_id("my-plugin-function") == 77
        with pytest.raises(ValueError, match="both have IOHprofiler id 77"):
            ioh._check_ids(["my-plugin-function", "F77"])
    finally:
        ioh._IDS.pop("my-plugin-function")


def test_ioh_evaluation_points_follow_thinned_curves():
    from swarmpath.evidence.ioh import evaluation_points, run_block

    assert evaluation_points(4, 4, 40) == [10, 20, 30, 40]
    assert evaluation_points(3, 9, 90, stride=4) == [10, 50, 90]  # iterations 1, 5, 9
    # 10 agents evaluated first, then 10 per iteration: iteration 1 ends at 20, 50 at 510
    assert evaluation_points(50, 50, 510, initial=10)[:2] == [20, 30]
    assert evaluation_points(50, 50, 510, initial=10)[-1] == 510
    assert run_block([float("inf"), 5.0, 5.0, 2.0], [1, 2, 3, 4]) == [(2, 5.0), (4, 2.0)]
    assert run_block([3.0, 3.0], [1, 2]) == [(1, 3.0), (2, 3.0)]


# ------------------------------------------------------------------ timestamps, response models
def test_status_timestamps_are_iso_8601_beside_the_unix_float(service):
    from datetime import datetime

    _cli, http, _core = service
    job = finished(service, BENCH)
    status = http.get(f"/jobs/{job}").json()
    for name in ("created", "started", "finished"):
        stamp = datetime.fromisoformat(status[f"{name}_at"].replace("Z", "+00:00"))
        assert stamp.utcoffset().total_seconds() == 0
        assert abs(stamp.timestamp() - status[name]) < 1e-3
    (worker,) = http.get("/workers").json()
    assert abs(datetime.fromisoformat(worker["last_seen_at"].replace("Z", "+00:00"))
               .timestamp() - worker["last_seen"]) < 1e-3
    queued = http.post("/jobs", json=BENCH).json()["id"]
    assert http.get(f"/jobs/{queued}").json()["finished_at"] is None


def test_openapi_describes_summary_runs_and_run(service):
    _cli, http, _core = service
    api = http.get("/openapi.json").json()
    paths = api["paths"]

    def model(path):
        content = paths[path]["get"]["responses"]["200"]["content"]["application/json"]
        return content["schema"]["$ref"].rsplit("/", 1)[-1]

    assert model("/jobs/{job_id}/summary") == "Summary"
    assert model("/jobs/{job_id}/runs") == "RunsPage"
    assert model("/jobs/{job_id}/runs/{run_id}") == "Run"
    schemas = api["components"]["schemas"]
    assert {"rows", "columns", "legend"} <= set(schemas["Summary"]["properties"])
    assert {"curve", "path", "run_id", "state"} <= set(schemas["Run"]["properties"])
    job = finished(service, MAPS)
    summary = http.get(f"/jobs/{job}/summary").json()
    from swarmpath.evidence.legend import NOTES

    assert set(summary["legend"]) == set(NOTES) & set(summary["columns"])
    assert {"failed", "collisions", "gap_mean"} <= set(summary["legend"])
    assert "moving obstacles" in summary["legend"]["gap_mean"]
    run = http.get(f"/jobs/{job}/runs/1").json()
    assert "algorithm" not in run and run["planner"] == "OMPL-RRTstar" and run["path"]


def _leaves(node):
    if isinstance(node, str):
        return [node]
    return _leaves(node["first"]) + _leaves(node["second"])


def test_download_layout_shows_the_files_topics_and_only_their_panels(service, tmp_path):
    """A layout names only topics its file has (issue 25: the benchmark layout had a 3D panel
    on /tf, which benchmark files lack; the map layout plotted /curves, which map files lack)."""
    from swarmpath.service import foxglove
    from swarmpath.service.recorder import CURVE_SCHEMA, WORLD_FRAME

    cli, _http, _core = service
    job = finished(service, MAPS)
    result = cli("download", job, "-o", str(tmp_path), "--layout")
    assert result.exit_code == 0, result.stderr
    doc = json.loads((tmp_path / f"{job}.layout.json").read_text())
    topics = foxglove.mcap_topics(tmp_path / f"{job}.mcap")
    panels = doc["configById"]
    scene = panels["3D!swarmpath"]
    assert scene["followTf"] == WORLD_FRAME
    shown = set(scene["topics"])
    assert shown == {t for t in topics if t.startswith(foxglove.SCENE_TOPIC_PREFIXES)}
    assert {"/tf", "/map/mfb-static/occupancy", "/scene/OMPL-RRTstar/mfb-static"} <= shown
    assert "/curves" not in topics and set(panels) == {"3D!swarmpath", "RawMessages!swarmpath"}
    assert panels["RawMessages!swarmpath"]["topicPath"] in topics
    assert sorted(_leaves(doc["layout"])) == sorted(panels)  # every panel placed, none missing

    bench = finished(service, BENCH)
    assert cli("download", bench, "-o", str(tmp_path), "--layout").exit_code == 0
    doc = json.loads((tmp_path / f"{bench}.layout.json").read_text())
    topics = foxglove.mcap_topics(tmp_path / f"{bench}.mcap")
    panels = doc["configById"]
    assert not any(t.startswith(foxglove.SCENE_TOPIC_PREFIXES) for t in topics)
    assert set(panels) == {"Plot!swarmpath", "RawMessages!swarmpath"}
    assert sorted(_leaves(doc["layout"])) == sorted(panels)
    (plot,) = panels["Plot!swarmpath"]["paths"]
    topic, field = plot["value"].removesuffix("[:]").split(".")
    assert topic in topics and (topic, panels["Plot!swarmpath"]["xAxisVal"]) == ("/curves", "index")
    assert CURVE_SCHEMA["properties"][field]["type"] == "array"
    assert json.loads(foxglove.LAYOUT_FILE.read_text()) == foxglove.layout()
    assert sorted(_leaves(foxglove.layout()["layout"])) == sorted(foxglove.PANEL_TOPICS)


def test_runs_of_a_job_not_run_yet_export_with_empty_metrics(service, tmp_path):
    from swarmpath.evidence import exports

    cli, http, _core = service
    job = http.post("/jobs", json=BENCH).json()["id"]
    nothing = cli("results", job, "--plot", str(tmp_path / "none"))
    assert nothing.exit_code == 0 and "no finished run to plot" in nothing.stderr
    assert list((tmp_path / "none").iterdir()) == []
    out = tmp_path / "queued.parquet"
    result = cli("results", job, "--runs", "--format", "parquet", "-o", str(out))
    assert result.exit_code == 0, result.stderr
    df = exports.load_results(out)
    assert len(df) == 12 and set(df["state"]) == {"queued"}
    assert df["curve"].isna().all() and df["best_fitness"].isna().all()
