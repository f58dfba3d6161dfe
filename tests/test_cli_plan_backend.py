"""`swarmpath plan --backend`: the backend parameter of every selected planner that has one."""

import json
import sys

import pytest
from typer.testing import CliRunner

from swarmpath.cli import app, plan
from swarmpath.cli.core import InputError
from swarmpath.cli.plan_backend import BACKENDS
from swarmpath.planners import get_planner, list_planners
from swarmpath.planners.episode import TIMING_FIELDS

runner = CliRunner()
WITH_BACKEND = [n for n in list_planners() if "backend" in get_planner(n).defaults]
WITHOUT_BACKEND = [n for n in list_planners() if n not in WITH_BACKEND]


def invoke(*args: str):
    return runner.invoke(app, ["plan", "-j", "1", "-m", "mfb-static", *args])


def test_the_registry_has_planners_with_and_without_a_backend():
    assert WITH_BACKEND and WITHOUT_BACKEND  # else the tests below prove little
    for name in WITH_BACKEND:
        assert set(get_planner(name).choices["backend"]) == set(BACKENDS)


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_planner_with_a_backend_gets_it_and_the_others_nothing(backend):
    pytest.importorskip("numba")
    spec = plan.make_spec("all", "mfb-static", runs=1, backend=backend,
                          params=json.dumps({WITH_BACKEND[0]: {"agents": 12}}))
    for name in WITH_BACKEND:
        task = plan._task(spec, name, spec.maps[0], 0)
        assert task.params is not None and task.params["backend"] == backend
        assert get_planner(name).resolve_params(task.params)["backend"] == backend
    assert spec.params[WITH_BACKEND[0]]["agents"] == 12  # --params kept beside it
    for name in WITHOUT_BACKEND:
        assert "backend" not in spec.params.get(name, {})


def test_without_the_option_the_params_are_untouched():
    spec = plan.make_spec("all", "mfb-static", runs=1)
    assert spec.params == {}


def test_the_same_backend_in_params_is_accepted_a_different_one_refused():
    name = WITH_BACKEND[0]
    spec = plan.make_spec(name, "mfb-static", runs=1, backend="numpy",
                          params=json.dumps({name: {"backend": "numpy"}}))
    assert spec.params[name] == {"backend": "numpy"}
    pytest.importorskip("numba")  # --params' backend numba is checked by the planner
    with pytest.raises(InputError) as caught:
        plan.make_spec(name, "mfb-static", runs=1, backend="numpy",
                       params=json.dumps({name: {"backend": "numba"}}))
    assert caught.value.field == "--backend"
    assert "--params" in str(caught.value) and f"{name}.backend" in str(caught.value)


def _one_error_line(result) -> str:
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "error" in lines[0]
    return lines[0]


@pytest.mark.parametrize("value", ["cuda", "Numba", ""])
def test_a_bad_value_is_exit_2_naming_the_option(value):
    line = _one_error_line(invoke("-p", WITH_BACKEND[0], "--backend", value))
    assert "--backend" in line and "numpy" in line and "numba" in line


def test_a_conflict_with_params_is_exit_2_naming_both():
    pytest.importorskip("numba")
    name = WITH_BACKEND[0]
    line = _one_error_line(invoke("-p", name, "--backend", "numba", "--params",
                                  json.dumps({name: {"backend": "numpy"}})))
    assert "--backend" in line and "--params" in line and f"{name}.backend" in line


def test_only_planners_without_a_backend_is_exit_2():
    line = _one_error_line(invoke("-p", WITHOUT_BACKEND[0], "--backend", "numpy"))
    assert "--backend" in line and WITHOUT_BACKEND[0] in line


def test_numba_missing_is_exit_2_naming_the_option_and_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba raises ImportError
    line = _one_error_line(invoke("-p", WITH_BACKEND[0], "--backend", "numba"))
    assert "--backend" in line and "swarmpath[fast]" in line
    # numpy needs no numba
    spec = plan.make_spec(WITH_BACKEND[0], "mfb-static", runs=1, backend="numpy")
    assert spec.params[WITH_BACKEND[0]]["backend"] == "numpy"


def test_a_plan_with_backend_numpy_runs_as_the_default():
    small = json.dumps({"PSO": {"agents": 5, "iterations": 5}})
    docs = [json.loads(invoke("-p", "PSO", "--runs", "1", "--json", "--params", small,
                              *extra).stdout) for extra in ([], ["--backend", "numpy"])]
    for doc in docs:
        for run in doc["runs"]:
            for key in TIMING_FIELDS:
                run.pop(key)
    assert docs[0]["runs"] == docs[1]["runs"] and docs[0]["runs"][0]["success"]
