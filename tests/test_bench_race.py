"""``swarmpath bench --race``: the same rounds, allowances, decisions and numbers as a raced job in
the store and as the pure replay over directly computed runs, whatever ``--jobs``; the table,
the LaTeX table and the JSON carry the race; bad race options are named (exit 2)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence import tables
from swarmpath.service.store import Store
from test_store import T0
from test_store_racing import SPEC, check_race_against_direct_runs, direct, drain

runner = CliRunner()
# the store test's raced job (FDO, PSO, GWO x F1, F10; 5 dims, at most 60 runs), both on the
# numpy backend (a race's blocks record the backend; numpy: no kernel compiles in this test)
ARGS = ["-a", ",".join(SPEC["algorithms"]), "-f", ",".join(SPEC["functions"]), "-d", "5",
        "--backend", "numpy",
        "--runs", "60", "--agents", "8", "--iterations", "30", "--seed", "3", "--race",
        "--race-min-runs", "10", "--race-batch", "10"]


def bench(*args: str) -> tuple[int, str, str]:
    result = runner.invoke(app, ["bench", *args])
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def raced() -> dict:
    code, out, err = bench(*ARGS, "--json", "-j", "2")
    assert code == 0, err
    return json.loads(out)


def test_bench_race_is_the_store_race_and_the_replay_over_direct_runs(raced, tmp_path):
    with Store(tmp_path) as store:
        job = store.create_job({**SPEC, "backend": "numpy"}, now=T0)
        drain(store, job)
        check_race_against_direct_runs(store, job)  # the store against race_block over runs
        race = store.race(job)
        items = store.runs(job, limit=1000)
    # the whole race document: settings, blocks, rounds, allowances, stops, decisions, intervals
    assert raced["race"] == race
    assert raced["statistics"]["race"] == race
    stored = {}
    for item in items:
        a, f, d = item["cell"].split("/")
        stored.setdefault((a, f, int(d)), []).append(item["best_fitness"])
    runs = {c["key"]: c["runs"] for b in race["blocks"] for c in b["cells"]}
    for cell in raced["cells"]:
        key = (cell["algorithm"], cell["function"], cell["dim"])
        assert cell["run_ids"] == list(range(runs["/".join(map(str, key))]))
        assert cell["best_fitness"] == stored[key]  # each run the job's run r
        assert cell["best_fitness"] == direct(SPEC, key[0], key[1])[: len(cell["run_ids"])
                                                                    ].tolist()
    used = sum(runs.values())
    assert raced["race_summary"]["runs"] == used < 6 * 60
    # the default design: the job spec's and --race's, Pocock-spent looks every round
    assert {k: race["settings"][k] for k in ("looks", "look_share", "sequence_share",
                                             "spending", "futility", "recycle")} == {
        "looks": "every-round", "look_share": 0.8, "sequence_share": 0.05, "spending": "pocock",
        "futility": 0.05, "recycle": True}
    assert "looks every round from 20 (pocock)" in raced["race_summary"]["line"]
    assert raced["race_summary"]["unraced_runs"] == 6 * 60
    assert raced["settings"]["racing"]["max_runs"] == 60


@pytest.mark.parametrize(("options", "looks"), [
    (["--race-looks", "20,30,40", "--race-look-share", "0.8", "--race-sequence-share", "0.05",
      "--race-spending", "obrien-fleming"],
     {"looks": [20, 30, 40], "look_share": 0.8, "sequence_share": 0.05,
      "spending": "obrien-fleming"}),
    (["--race-looks", "none"], {"looks": []}),  # the race without looks, the default before
    (["--race-futility", "0.3"], {"futility": 0.3}),
    (["--race-no-recycle"], {"recycle": False}),
], ids=["looks", "none", "futility", "no-recycle"])
def test_bench_race_with_planned_looks_is_the_store_race(tmp_path, options, looks):
    """--race-looks, --race-look-share, --race-sequence-share, --race-spending and
    --race-futility are the job spec's racing fields: the same race document as the store's
    job with them."""
    code, out, err = bench(*ARGS, "--json", *options)
    assert code == 0, err
    spec = {**SPEC, "backend": "numpy", "racing": {**SPEC["racing"], **looks}}
    with Store(tmp_path) as store:
        job = store.create_job(spec, now=T0)
        drain(store, job)
        race = store.race(job)
    assert json.loads(out)["race"] == race
    assert race["settings"]["looks"] == looks.get("looks", "every-round")
    looked = looks.get("looks") != []  # no looks: no futility, nothing to recycle
    assert race["settings"]["futility"] == looks.get("futility", 0.05 if looked else 0.0)
    assert race["settings"]["recycle"] is looks.get("recycle", looked)


def test_the_markers_are_the_race_decisions_not_rank_sum_tests(raced):
    comparison = raced["statistics"]["comparison"]
    assert comparison["correction"] == "bonferroni" and comparison["test"].startswith("race")
    duels = {(b["block"]["function"], d["a"]): d for b in raced["race"]["blocks"]
             for d in b["duels"]}
    for cell in raced["cells"]:
        test = cell["test"]
        assert test["p"] is None and test["p_holm"] is None and test["similar"] is False
        if cell["algorithm"] == "GWO":  # the reference
            assert test["marker"] is None
        else:
            assert test["marker"] == duels[(cell["function"], cell["algorithm"])]["marker"]
    assert comparison["counts"]["FDO"] == {"+": 0, "=": 0, "-": 2}


def test_jobs_change_no_number(raced):
    code, out, err = bench(*ARGS, "--json", "-j", "1")
    assert code == 0, err
    one = json.loads(out)
    assert one["race"] == raced["race"]
    assert [c["best_fitness"] for c in one["cells"]] == [c["best_fitness"] for c in raced["cells"]]


def test_the_table_and_latex_show_runs_decisions_and_rounds(raced):
    code, out, err = bench(*ARGS, "-j", "1")
    assert code == 0, err
    cells = {c["key"]: c for b in raced["race"]["blocks"] for c in b["cells"]}
    duels = {(b["block"]["function"], d["a"]): d for b in raced["race"]["blocks"]
             for d in b["duels"]}
    race_rows = [line.split()[1:] for line in out.splitlines()
                 if (line.split()[:1] == ["race"] or line.split()[2:3] == ["race"])
                 and not line.startswith("race (")]  # not the race line under the tables
    assert len(race_rows) == 2  # one per function
    for function, row in zip(SPEC["functions"], race_rows, strict=True):
        text = " ".join(row)
        for a in SPEC["algorithms"]:
            c = cells[f"{a}/{function}/5"]
            duel = duels.get((function, a))
            word = "" if duel is None else {"different": "diff ", "equivalent": "equiv ",
                                             "open": "open "}[duel["decision"]]
            assert f"{c['runs']} {word}r{c['stopped_round']}" in text
    assert "as the race decided it" in out and "rank-sum" not in out.split("Friedman D=5")[0]
    assert raced["race_summary"]["line"] in " ".join(out.split())

    code, tex, err = bench(*ARGS, "--format", "latex")
    assert code == 0, err
    assert "\\begin{tabular}" in tex and "as the race decided it" in tex
    assert "Wilcoxon" not in tex
    fdo = cells["FDO/F1/5"]
    assert f"{fdo['runs']} diff r{fdo['stopped_round']}" in tex
    assert "$^{-}$" in tex  # FDO's race markers as superscripts


def test_race_text_of_a_cell_still_racing_and_of_the_reference():
    assert tables.race_text({"race_runs": 40, "race_decision": "open", "race_state": "racing",
                             "race_round": None}) == "40 open racing"
    assert tables.race_text({"race_runs": 60, "race_decision": None, "race_state": "max_runs",
                             "race_round": 5}) == "60 r5"
    assert tables.race_text({}) == ""


BAD = [
    (["--race-alpha", "0.1"], "--race-alpha"),  # without --race
    (["--race", "--race-alpha", "0"], "--race-alpha"),
    (["--race", "--race-alpha", "nan"], "--race-alpha"),
    (["--race", "--race-min-runs", "0"], "--race-min-runs"),
    (["--race", "--race-min-runs", "31"], "--race-min-runs"),
    (["--race", "--race-batch", "0"], "--race-batch"),
    (["--race", "--race-margin", "0.5"], "--race-margin"),
    (["--race", "--race-margin", "-0.1"], "--race-margin"),
    (["--race", "--race-pairs", "some"], "--race-pairs"),
    (["--race-final-test", "sign"], "--race-final-test"),  # without --race
    (["--race", "--race-final-test", "t-test"], "--race-final-test"),
    (["--race-looks", "20"], "--race-looks"),  # without --race
    (["--race", "--race-looks", "20,x", "--race-look-share", "0.5"], "--race-looks"),
    (["--race", "--race-looks", "25", "--race-look-share", "0.4"], "--race-looks"),
    (["--race", "--race-looks", "20", "--race-look-share", "0.6", "--race-sequence-share",
      "0.5"], "--race-sequence-share"),
    (["--race", "--race-sequence-share", "0.5"], "--race-sequence-share"),  # default looks
    (["--race", "--race-looks", "none", "--race-look-share", "0.3"], "--race-looks"),
    (["--race", "--race-looks", "every-round", "--race-final-test", "sign"], "--race-looks"),
    (["--race", "--race-looks", "every-other"], "--race-looks"),
    (["--race", "--race-looks", "20", "--race-look-share", "nan"], "--race-look-share"),
    (["--race", "--race-spending", "linear"], "--race-spending"),
    (["--race-futility", "0.1"], "--race-futility"),  # without --race
    (["--race", "--race-futility", "1"], "--race-futility"),
    (["--race", "--race-futility", "nan"], "--race-futility"),
    (["--race", "--race-looks", "none", "--race-futility", "0.1"], "--race-futility"),
    (["--race-no-recycle"], "--race-recycle"),  # without --race
    (["--race", "--race-looks", "none", "--race-recycle"], "--race-recycle"),
    (["--race", "-a", "GWO"], "--algorithms"),
    (["--race", "-f", "bbob:f1", "--instances", "1-2", "--pool-instances"], "--pool-instances"),
]


@pytest.mark.parametrize(("args", "named"), BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_race_options_are_named_with_exit_code_2(args, named):
    base = ["-a", "GWO,PSO", "-f", "F1", "-d", "2", "--runs", "30", "--iterations", "2"]
    code, out, err = bench(*base, *args)
    assert code == 2 and out == ""
    assert err.strip().startswith("swarmpath bench: error: ") and named in err
    assert len(err.strip().splitlines()) == 1
