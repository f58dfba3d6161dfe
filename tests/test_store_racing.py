"""Raced jobs in the store: rounds decided as results arrive, cells stopping, the job finishing
with the runs the race used; the same race as the pure replay over directly computed runs;
a reopened store going on with the same decisions; racing fields validated."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError

from swarmpath.evidence.race_report import RACE_COLUMNS, study_race
from swarmpath.evidence.racing import race_block
from swarmpath.optimizers import minimize
from swarmpath.service.protocol import expand_cells, parse_job_spec
from swarmpath.service.racing import group_blocks
from swarmpath.service.spec_checks import FieldProblems
from swarmpath.service.store import ExtendError, Store
from test_store import T0, execute

SPEC = {
    "kind": "benchmark", "algorithms": ["FDO", "PSO", "GWO"], "functions": ["F1", "F10"],
    "dims": [5], "runs": 60, "agents": 8, "iterations": 30, "seed": 3,
    "racing": {"min_runs": 10, "batch": 10, "alpha": 0.05},
}


def direct(spec: dict, algorithm: str, function: str) -> np.ndarray:
    return minimize(algorithm, function, spec["dims"][0], spec["agents"], spec["iterations"],
                    seed=spec["seed"], runs=spec["runs"]).best_fitness


def drain(store: Store, job: str, max_runs: int = 7, stop_after: int | None = None) -> int:
    leased = 0
    while (lease := store.lease("w1", max_runs, now=T0)) is not None:
        cells = {c["index"]: c for c in store.cells(job)}
        assert max(lease.runs) < cells[lease.cell_index]["runs"]  # only the round's runs
        assert set(store.accept_results(execute(lease), now=T0)) == {"accepted"}
        leased += len(lease.runs)
        if stop_after is not None and leased >= stop_after:
            break
    return leased


def replay(raw: dict, names_per_block: dict[str, list[str]], comparisons: int) -> dict:
    """The race document of ``raw``'s study replayed over directly computed runs."""
    spec = parse_job_spec(raw)
    settings = spec.racing.settings(raw["runs"])
    blocks = []
    for function, names in names_per_block.items():
        values = {a: direct(raw, a, function) for a in names}
        blocks.append(({"function": function}, race_block(values, names, settings, comparisons),
                       list(enumerate(names))))
    return study_race(settings, comparisons, blocks)


def check_race_against_direct_runs(store: Store, job: str, raw: dict = SPEC) -> dict:
    race = store.race(job)
    assert race is not None and race["settings"]["max_runs"] == raw["runs"]
    spec = parse_job_spec(raw)
    cells = [(i, c.model_dump()) for i, c in enumerate(expand_cells(spec))]
    blocks = group_blocks(cells, None, "reference")
    assert race["comparisons"] == blocks.comparisons == 4
    expected = replay(raw, {b["block"]["function"]: [c["algorithm"] for c in b["cells"]]
                            for b in race["blocks"]}, 4)
    for block, want in zip(race["blocks"], expected["blocks"], strict=True):
        assert block["rounds"] == want["rounds"] and block["finished"] == want["finished"]
        assert [c["runs"] for c in block["cells"]] == [c["runs"] for c in want["cells"]]
        keys = ("decision", "better", "final", "closing_p", "look", "power")
        assert [[d.get(k) for k in keys] for d in block["duels"]] == [
            [d.get(k) for k in keys] for d in want["duels"]]
        for c in block["cells"]:
            assert c["finished_runs"] == c["runs"]
    return race


def test_a_raced_job_runs_its_rounds_and_finishes_with_the_runs_it_used(tmp_path):
    with Store(tmp_path) as store:
        job = store.create_job(SPEC, now=T0)
        status = store.job_status(job)
        assert status.runs_total == 6 * 10  # min_runs each, to begin with
        leased = drain(store, job)
        status = store.job_status(job)
        assert status.state == "done"
        race = check_race_against_direct_runs(store, job)
        used = sum(c["runs"] for b in race["blocks"] for c in b["cells"])
        assert leased == status.runs_done == status.runs_total == used < 6 * SPEC["runs"]
        # FDO (the weakest) loses to GWO on both functions within the first rounds
        fdo = [d for b in race["blocks"] for d in b["duels"] if d["a"] == "FDO"]
        assert all(d["decision"] == "different" and d["better"] == "GWO" for d in fdo)
        # the job lists the runs the race gave each cell, each the unraced study's run r
        items = store.runs(job, limit=1000)
        cells = {c["key"]: c["runs"] for c in store.cells(job)}
        assert [(i["cell"], i["run"]) for i in items] == [
            (key, r) for key, n in cells.items() for r in range(n)]
        assert {i["state"] for i in items} == {"done"}
        assert store.runs(job, limit=7, offset=25) == items[25:32]
        for item in items[::17]:
            a, f, _ = item["cell"].split("/")
            assert item["best_fitness"] == direct(SPEC, a, f)[item["run"]]
            assert store.run(job, item["run_id"])["run"] == item["run"]
        gap = items[0]["run_id"] + cells[items[0]["cell"]]  # past the first cell's last run
        assert store.run(job, gap) is None and store.run_record(job, gap) is None


@pytest.mark.parametrize("look", ["rank-sum", True])
def test_a_raced_job_with_a_closing_look_is_its_replay(tmp_path, look):
    """racing.final_test reaches the store's race: the job's decisions, the closing look's
    among them, are those of the replay over the directly computed runs; true, the look of
    jobs stored before the rank-sum look, is the sign test. Without planned looks (looks [];
    the default's look at 50 runs decides F5's PSO before its closing look)."""
    spec = {**SPEC, "functions": ["F1", "F5"],
            "racing": {**SPEC["racing"], "final_test": look, "looks": []}}
    with Store(tmp_path) as store:
        job = store.create_job(spec, now=T0)
        drain(store, job)
        assert store.job_status(job).state == "done"
        race = check_race_against_direct_runs(store, job, spec)
    assert race["settings"]["final_test"] == ("sign" if look is True else look)
    # PSO against GWO on F5 is open after 60 runs (theta 0.7) and the look decides it
    finals = [(b["block"]["function"], d["a"], d["better"]) for b in race["blocks"]
              for d in b["duels"] if d["final"]]
    assert finals == [("F5", "PSO", "PSO")]


def _restarted_beside(tmp_path: Path, spec: dict, other: dict, stop_after: int
                      ) -> tuple[dict, dict, dict]:
    """``spec``'s job stopped mid-race after ``stop_after`` runs, the store reopened (a
    coordinator restart) and the job finished, checked against the replay over directly
    computed runs; then a job with the racing field ``other`` beside it: the first job's race,
    the other's, and the first job's stored racing spec."""
    with Store(tmp_path) as store:
        job = store.create_job(spec, now=T0)
        drain(store, job, stop_after=stop_after)
        before = store.race(job)
        assert not all(b["finished"] for b in before["blocks"])
    with Store(tmp_path) as store:
        assert store.race(job) == before
        drain(store, job)
        assert store.job_status(job).state == "done"
        race = check_race_against_direct_runs(store, job, spec)
        beside = store.create_job({**spec, "racing": {**SPEC["racing"], **other}}, now=T0)
        drain(store, beside)
        stored = json.loads(store._db.execute("SELECT spec FROM jobs WHERE id = ?",
                                              (job,)).fetchone()[0])["racing"]
        return race, store.race(beside), stored


def test_a_raced_job_with_planned_looks_resumes_after_a_restart_with_its_decisions(tmp_path):
    """A raced job's default design, group-sequential looks at every round (20, 30, 40, 50 runs
    here), reaches the store, written into its spec: the job, stopped in the middle of its race
    and the store reopened (a coordinator restart), finishes as the replay over the directly
    computed runs, some comparisons decided at a look, and with fewer runs than the same job
    without looks (looks [], the default before)."""
    spec = {**SPEC, "functions": ["F1", "F5"]}
    race, without, stored = _restarted_beside(tmp_path, spec, {"looks": []}, 110)
    assert {k: stored[k] for k in ("looks", "look_share", "sequence_share", "spending")} == {
        "looks": "every-round", "look_share": 0.8, "sequence_share": 0.05, "spending": "pocock"}
    assert race["settings"]["looks"] == "every-round"
    assert without["settings"]["looks"] == [] and without["settings"]["sequence_share"] == 0.5
    at_look = [(b["block"]["function"], d["a"], d["look"]) for b in race["blocks"]
               for d in b["duels"] if d["look"]]
    assert at_look and all(n in (20, 30, 40, 50) for _, _, n in at_look)
    assert not any(d["look"] for b in without["blocks"] for d in b["duels"])

    def used(r: dict) -> int:
        return sum(c["runs"] for b in r["blocks"] for c in b["cells"])

    assert used(race) < used(without)


#: The racing fields of the planned looks, which specs stored before them do not hold (nor
#: futility and recycle, which came later: LATER_FIELDS).
LATER_FIELDS = ("futility", "recycle")
LOOK_FIELDS = ("looks", "look_share", "sequence_share", "spending", *LATER_FIELDS)


def _as_stored_by(path: Path, job: str, version: int, without: tuple[str, ...],
                  **fields: object) -> None:
    """The store file as schema ``version`` wrote it: the job's racing spec without the fields
    ``without``, with ``fields``."""
    db = sqlite3.connect(path)
    (text,) = db.execute("SELECT spec FROM jobs WHERE id = ?", (job,)).fetchone()
    spec = json.loads(text)
    for key in without:
        del spec["racing"][key]
    spec["racing"].update(fields)
    db.execute("UPDATE jobs SET spec = ? WHERE id = ?", (json.dumps(spec), job))
    db.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'", (str(version),))
    db.commit()
    db.close()


def _as_stored_before_the_rank_sum_look(path: Path, job: str, look: bool | None) -> None:
    """The store file as schema version 4 wrote it: the job's racing spec without final_test
    (None: the code before any closing look), or with the boolean of the sign look's code, and
    without the planned looks' fields."""
    closing = {} if look is None else {"final_test": look}
    _as_stored_by(path, job, 4, ("final_test", *LOOK_FIELDS), **closing)


@pytest.mark.parametrize(("stored", "look"), [(None, "none"), (False, "none"), (True, "sign")])
def test_a_job_stored_before_the_rank_sum_look_resumes_with_its_decisions(tmp_path, stored,
                                                                         look):
    """A raced job stored without final_test (raced by the sequence alone) or with the boolean
    of the sign look, half run, then the coordinator restarts with this code (whose default is
    the rank-sum look): the migration writes its look into its spec, and it finishes as the
    replay with that look. Without the migration it would end otherwise (the replay with the
    rank-sum look differs: the check can fail). A new job's stored spec names its look, so no
    later default changes it."""
    spec = {**SPEC, "functions": ["F1", "F5"], "racing": {**SPEC["racing"], "final_test": look}}
    with Store(tmp_path) as store:
        job = store.create_job(spec, now=T0)
        drain(store, job, stop_after=100)
        before = store.race(job)
    _as_stored_before_the_rank_sum_look(tmp_path / "swarmpath.sqlite3", job, stored)
    with Store(tmp_path) as store:
        assert store.job_spec(job).racing.final_test == look
        assert store.race(job) == before
        drain(store, job)
        race = check_race_against_direct_runs(store, job, spec)
        fresh = store.create_job({**spec, "racing": SPEC["racing"]}, now=T0)
        stored_spec = store._db.execute("SELECT spec FROM jobs WHERE id = ?", (fresh,)).fetchone()
    assert json.loads(stored_spec[0])["racing"]["final_test"] == "rank-sum"
    assert race["settings"]["final_test"] == look
    names = {b["block"]["function"]: [c["algorithm"] for c in b["cells"]]
             for b in race["blocks"]}
    with_look = replay({**spec, "racing": SPEC["racing"]}, names, 4)
    assert with_look["blocks"] != race["blocks"]


@pytest.mark.parametrize("version", [4, 5])
def test_a_job_stored_before_looks_every_round_resumes_with_its_decisions(tmp_path, version):
    """A raced job stored before the planned looks existed (no looks fields: the rank-sum
    closing look, no looks), half run, then the coordinator restarts with this code, whose
    default is a look every round: the migration (schema 6) writes the race without looks into
    its spec, and it finishes as the replay without looks. Without the migration it would end
    otherwise (the replay with the default's looks differs: the check can fail)."""
    spec = {**SPEC, "functions": ["F1", "F5"], "racing": {**SPEC["racing"], "looks": []}}
    with Store(tmp_path) as store:
        job = store.create_job(spec, now=T0)
        drain(store, job, stop_after=100)
        before = store.race(job)
    _as_stored_by(tmp_path / "swarmpath.sqlite3", job, version, LOOK_FIELDS)
    with Store(tmp_path) as store:
        racing = store.job_spec(job).racing
        assert (racing.looks, racing.look_share, racing.sequence_share) == ([], 0.0, 0.5)
        assert store.race(job) == before
        drain(store, job)
        race = check_race_against_direct_runs(store, job, spec)
    assert race["settings"]["looks"] == [] and race["settings"]["final_test"] == "rank-sum"
    names = {b["block"]["function"]: [c["algorithm"] for c in b["cells"]]
             for b in race["blocks"]}
    by_default = replay({**spec, "racing": SPEC["racing"]}, names, 4)
    assert by_default["blocks"] != race["blocks"]


def test_a_raced_job_stops_a_futile_comparison_and_resumes_after_a_restart(tmp_path):
    """The default design's futility (0.05) reaches the store, written into the spec: on F7
    PSO against GWO (theta 0.43 after 30 runs) stops at the look at 30 runs, its predictive
    power below 0.05; stopped mid-race and the store reopened, the job finishes as the replay
    over the directly computed runs, with fewer runs than the same job with futility 0."""
    spec = {**SPEC, "functions": ["F1", "F7"]}
    race, without, stored = _restarted_beside(tmp_path, spec, {"futility": 0}, 40)
    assert stored["futility"] == 0.05 and race["settings"]["futility"] == 0.05
    futile = [(b["block"]["function"], d["a"], d["look"]) for b in race["blocks"]
              for d in b["duels"] if d["decision"] == "futile"]
    assert futile == [("F7", "PSO", 30)]
    assert not any(d["decision"] == "futile" for b in without["blocks"] for d in b["duels"])

    def used(r: dict) -> int:
        return sum(c["runs"] for b in r["blocks"] for c in b["cells"])

    assert used(race) < used(without)


def test_a_job_stored_before_futility_resumes_with_its_decisions(tmp_path):
    """A raced job stored by schema 6 (looks every round, no futility or recycle fields: raced
    without either), half run, then the coordinator restarts with this code, whose default stops
    for futility and recycles: the migration (schema 7) writes futility 0 and recycle false into
    its spec, and it finishes as the replay without them. Without the migration it would end
    otherwise (the replay with the default's futility differs on F7: the check can fail)."""
    spec = {**SPEC, "functions": ["F1", "F7"],
            "racing": {**SPEC["racing"], "futility": 0, "recycle": False}}
    with Store(tmp_path) as store:
        job = store.create_job(spec, now=T0)
        drain(store, job, stop_after=40)
        before = store.race(job)
    _as_stored_by(tmp_path / "swarmpath.sqlite3", job, 6, LATER_FIELDS)
    with Store(tmp_path) as store:
        racing = store.job_spec(job).racing
        assert (racing.futility, racing.recycle, racing.looks) == (0.0, False, "every-round")
        assert store.race(job) == before
        drain(store, job)
        race = check_race_against_direct_runs(store, job, spec)
    names = {b["block"]["function"]: [c["algorithm"] for c in b["cells"]]
             for b in race["blocks"]}
    by_default = replay({**spec, "racing": SPEC["racing"]}, names, 4)
    assert by_default["blocks"] != race["blocks"]


def test_the_job_spec_offers_the_closing_looks_the_race_knows():
    from typing import get_args

    from swarmpath.evidence.group_sequential import SPENDING
    from swarmpath.evidence.racing import CLOSING, DEFAULT_DESIGN
    from swarmpath.service.racing import RacingSpec

    field = RacingSpec.model_fields["final_test"]
    assert get_args(field.annotation) == CLOSING and field.default == CLOSING[0]
    field = RacingSpec.model_fields["spending"]
    assert get_args(get_args(field.annotation)[0]) == SPENDING
    settings = parse_job_spec(SPEC).racing.settings(60)
    assert settings.final_test == "rank-sum" and settings.spending == DEFAULT_DESIGN["spending"]
    assert settings.look_runs == (20, 30, 40, 50)  # every round after the first


@pytest.mark.parametrize("racing, loc", [
    ({"max_runs": 50}, ("racing", "max_runs")),
    ({"min_runs": 61}, ("racing", "min_runs")),
    ({"pairs": "some"}, ("racing", "pairs")),
    ({"margin": 0.5}, ("racing", "margin")),
    ({"alpha": 0}, ("racing", "alpha")),
    ({"rounds": 3}, ("racing", "rounds")),
    ({"final_test": "yes"}, ("racing", "final_test")),
    ({"looks": [25], "look_share": 0.3}, ("racing", "looks")),
    ({"looks": [20, 10], "look_share": 0.3}, ("racing", "looks")),
    ({"looks": ["20"], "look_share": 0.3}, ("racing", "looks")),
    ({"looks": [20], "look_share": 0.6, "sequence_share": 0.5}, ("racing", "sequence_share")),
    ({"sequence_share": 0.5}, ("racing", "sequence_share")),  # beside the default's looks
    ({"looks": [], "look_share": 0.3}, ("racing", "looks")),
    ({"looks": "every-other"}, ("racing", "looks")),
    ({"looks": "every-round", "final_test": "sign"}, ("racing", "looks")),
    ({"look_share": 1.0}, ("racing", "look_share")),
    ({"spending": "linear"}, ("racing", "spending")),
    ({"futility": 1.0}, ("racing", "futility")),
    ({"futility": 0.1, "looks": []}, ("racing", "futility")),
    ({"futility": 0.1, "final_test": "none"}, ("racing", "futility")),
    ({"recycle": True, "looks": []}, ("racing", "recycle")),
    ({"recycle": "yes"}, ("racing", "recycle")),
])
def test_bad_racing_fields_are_named(racing, loc):
    with pytest.raises(ValidationError) as err:
        parse_job_spec({**SPEC, "racing": racing})
    assert loc in set(_locations(err.value))


def _locations(err: ValidationError):
    """Error locations below the job kind, a field's own problems (FieldProblems) included, as
    the REST error handler reports them."""
    for e in err.errors():
        problems = e.get("ctx", {}).get("error")
        if isinstance(problems, FieldProblems):
            yield from (tuple(e["loc"][1:]) + tuple(loc) for loc, _ in problems.problems)
        else:
            yield tuple(e["loc"][1:])


def test_a_race_needs_two_algorithms_and_a_benchmark_job():
    with pytest.raises(ValidationError) as err:
        parse_job_spec({**SPEC, "algorithms": ["GWO"]})
    assert "two algorithms" in str(err.value)
    with pytest.raises(ValidationError) as err:
        parse_job_spec({"kind": "map", "planners": ["MFB"], "maps": ["mfb-static"],
                        "racing": {}})
    assert any(e["loc"][-1] == "racing" for e in err.value.errors())


def test_a_budget_race_compares_the_algorithms_of_a_function_despite_their_iterations():
    """With budget_evals each algorithm runs the iterations spending the budget (FDO, mCOOT and
    GWO count evaluations differently): they still race in one block per function and dim."""
    spec = parse_job_spec({**SPEC, "algorithms": ["FDO", "mCOOT", "GWO"],
                           "budget_evals": "200xD"})
    cells = [(i, c.model_dump()) for i, c in enumerate(expand_cells(spec))]
    assert len({c["iterations"] for _, c in cells}) == 3
    blocks = group_blocks(cells, None, "reference")
    functions = [[cells[i][1]["function"] for i, _ in m] for m in blocks.members.values()]
    assert functions == [["F1"] * 3, ["F10"] * 3]
    assert blocks.comparisons == 4


def test_the_stored_spec_names_max_runs():
    spec = parse_job_spec(SPEC)
    assert spec.racing is not None and spec.racing.max_runs == 60
    assert parse_job_spec({**SPEC, "racing": {"max_runs": 60}}).racing.max_runs == 60


def test_a_raced_summary_has_the_race_markers_and_runs(tmp_path):
    with Store(tmp_path) as store:
        job = store.create_job(SPEC, now=T0)
        drain(store, job)
        summary = store.summary(job)
        race = store.race(job)
    assert summary["columns"][-len(RACE_COLUMNS):] == list(RACE_COLUMNS)
    assert summary["statistics"]["race"] == race
    comparison = summary["statistics"]["comparison"]
    assert comparison["reference"] == "GWO" and comparison["correction"] == "bonferroni"
    cells = {c["cell"]: c for b in race["blocks"] for c in b["cells"]}
    duels = {(json_key(b), d["a"]): d for b in race["blocks"] for d in b["duels"]}
    for i, row in enumerate(summary["rows"]):
        assert row["race_runs"] == cells[i]["runs"] == row["runs"]
        assert row["p"] is None
        if row["algorithm"] == "GWO":
            assert row["marker"] is None
        else:
            assert row["marker"] == duels[(row["function"], row["algorithm"])]["marker"]
    assert comparison["counts"]["FDO"] == {"+": 0, "=": 0, "-": 2}


def json_key(block):
    return block["block"]["function"]


@pytest.mark.parametrize("looks", [None, []], ids=["every-round", "no-looks"])
def test_an_extended_race_reuses_its_runs_and_goes_on(tmp_path, looks):
    """The default design's looks every round are the old job's rounds' in the extended job
    (its looks at 20 runs decide as they did); without looks, the closing look's decisions of
    the old job are not carried over (the new closing look is at 60)."""
    racing = SPEC["racing"] if looks is None else {**SPEC["racing"], "looks": looks}
    short = {**SPEC, "runs": 30, "racing": racing}
    with Store(tmp_path) as store:
        job = store.create_job(short, now=T0)
        drain(store, job)
        old = store.race(job)
        assert store.job_status(job).state == "done"
        new, reused = store.extend_job(job, 60, now=T0)
        assert reused == store.job_status(job).runs_done
        extended = store.job_spec(new).racing
        # the copied runs replay the old race: the sequence's and the looks' decisions stay,
        # the others go on
        race = store.race(new)
        carried = at_look = looked = 0
        for before, after in zip(old["blocks"], race["blocks"], strict=True):
            for a, b in zip(before["duels"], after["duels"], strict=True):
                if a["decision"] != "open" and not a["final"]:
                    assert (b["decision"], b["round"], b["look"]) == (
                        a["decision"], a["round"], a["look"])
                    carried += 1
                    at_look += a["look"] is not None
                elif a["final"]:
                    assert b["decision"] == "open" and not b["final"]
                    looked += 1
        leased = drain(store, new)
        status = store.job_status(new)
        assert status.state == "done" and leased == status.runs_total - reused
        # as if it had raced to 60 from the start with the extended spec's looks
        check_race_against_direct_runs(store, new, {**SPEC, "racing": {
            **racing, "looks": extended.looks, "look_share": extended.look_share}})
    assert carried
    if looks is None:
        assert extended.looks == [20] and at_look and old["settings"]["looks"] == "every-round"
    else:
        assert extended.looks == [] and looked


def test_an_unraced_job_extended_keeps_its_runs_and_adds_the_rest(tmp_path):
    plain = {k: v for k, v in SPEC.items() if k != "racing"} | {"runs": 4}
    with Store(tmp_path) as store:
        job = store.create_job(plain, now=T0)
        drain(store, job)
        new, reused = store.extend_job(job, 6, now=T0)
        assert reused == 24 and store.job_status(new).runs_total == 36
        assert drain(store, new) == 12
        items = store.runs(new, limit=100)
        assert [(i["cell"], i["run"]) for i in items] == [
            (c["key"], r) for c in store.cells(new) for r in range(6)]
        for item in items:
            a, f, _ = item["cell"].split("/")
            one = minimize(a, f, 5, 8, 30, seed=3, run_ids=[item["run"]]).best_fitness[0]
            assert item["best_fitness"] == one
        with pytest.raises(ExtendError, match="at least"):
            store.extend_job(new, 5)
        running = store.create_job(plain, now=T0)
        with pytest.raises(ExtendError, match="queued"):
            store.extend_job(running, 8)
        with pytest.raises(KeyError):
            store.extend_job("nope", 8)
