"""The conformance gate (swarmpath.testing, swarmpath check): every built-in passes it, and
deliberately broken plugins fail it naming the property they break."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from swarmpath.functions import BenchmarkFunction, get_function, list_functions, list_suites
from swarmpath.optimizers import list_optimizers
from swarmpath.optimizers.gwo import GWO
from swarmpath.planners import Decision, list_planners
from swarmpath.planners.base import Planner
from swarmpath.testing import (
    ConformanceError,
    check_function,
    check_optimizer,
    check_planner,
)
from swarmpath.testing.optimizer import check_optimizers

BROKEN = Path(__file__).parent / "data" / "plugins" / "broken.py"
ALL_FUNCTIONS = list_functions(builtin=True) + [n for s in list_suites(builtin=True)
                                                for n in list_functions(s)]


@pytest.mark.parametrize("name", list_optimizers(builtin=True))
def test_every_builtin_optimizer_passes(name):
    report = check_optimizer(name, processes=False, bias=False)
    assert report.ok and len(report.properties) == 7


def test_every_builtin_optimizer_is_the_same_in_children_and_in_a_worker_slot():
    reports = check_optimizers(list_optimizers(builtin=True), bias=False, raise_on_failure=False)
    for report in reports:
        by_name = {p.name: p for p in report.properties}
        for name in ("process-independent", "worker-slot"):
            assert by_name[name].ok, (report.name, by_name[name].detail)


@pytest.mark.parametrize("name", ALL_FUNCTIONS)
def test_every_builtin_function_passes(name):
    assert check_function(name).ok


@pytest.mark.parametrize("name", list_planners(builtin=True))
def test_every_builtin_planner_passes(name):
    report = check_planner(name)
    assert [p.name for p in report.properties] == [
        "parameters", "episode", "collision-free-success", "reproducible"]


# --------------------------------------------------------------------------- broken plugins
EXPECTED = {  # each broken optimizer and the property it must be caught on
    "broken-global-rng": "no-hidden-random-state",
    "broken-over-budget": "budget",
    "broken-batch-dependent": "batch-independent",
    "broken-out-of-box": "bounds",
}


def test_swarmpath_check_names_the_broken_property_of_each_plugin():
    env = {k: v for k, v in os.environ.items() if k != "SWARMPATH_PLUGINS"}
    out = subprocess.run(
        [sys.executable, "-m", "swarmpath.cli", "check", "optimizer", *EXPECTED, "--no-bias",
         "--json", "--plugin", str(BROKEN)],
        capture_output=True, text=True, env=env, timeout=600)
    assert out.returncode == 1, out.stderr
    reports = {r["name"]: r for r in json.loads(out.stdout)}
    for name, prop in EXPECTED.items():
        failing = {p["name"] for p in reports[name]["properties"] if not p["ok"]}
        assert prop in failing, (name, failing)
        assert name in out.stderr and prop in out.stderr
    # the ones that break one thing break only that
    assert {p["name"] for p in reports["broken-over-budget"]["properties"] if not p["ok"]} == {
        "budget"}
    assert {p["name"] for p in reports["broken-out-of-box"]["properties"] if not p["ok"]} == {
        "bounds"}
    ok = subprocess.run([sys.executable, "-m", "swarmpath.cli", "check", "optimizer", "GWO",
                         "--no-processes", "--no-bias"], capture_output=True, text=True,
                        env=env, timeout=600)
    assert ok.returncode == 0 and "FAIL" not in ok.stdout, ok.stdout + ok.stderr
    unknown = subprocess.run([sys.executable, "-m", "swarmpath.cli", "check", "optimizer",
                              "NOPE"], capture_output=True, text=True, env=env, timeout=600)
    assert unknown.returncode == 2 and "unknown optimizer 'NOPE'" in unknown.stderr


def test_check_optimizer_raises_naming_the_property_for_an_unregistered_class():
    class Lazy(GWO):
        """Evaluates one wolf a unit above the box each iteration (declaring the evaluations,
        not the box)."""

        name = "lazy-test-gwo"

        def expected_evaluations(self):
            return self.N * (2 * self.T + 1), self.N * (2 * self.T + 1)

        def _iterate(self):
            super()._iterate()
            X = self.X.copy()
            X[:, 0] = self.ub[:, 0] + 1.0
            self.evaluate(X)

    with pytest.raises(ConformanceError) as err:
        check_optimizer(Lazy, processes=False, bias=False)
    assert "bounds" in str(err.value) and "lazy-test-gwo" in str(err.value)
    assert "lazy-test-gwo" not in list_optimizers()  # registered only while checked


def _sphere(x):
    return np.einsum("...i,...i->...", x, x)


def test_broken_functions_fail_naming_the_property():
    batchy = BenchmarkFunction("batchy", lambda x: _sphere(x) - _sphere(x).mean(), -1.0, 1.0,
                               0.0)  # a value depends on every point of the batch
    assert [p.name for p in check_function(batchy, raise_on_failure=False).failures] == [
        "deterministic", "minimum"]
    wrong_min = BenchmarkFunction("wrong-min", _sphere, -1.0, 1.0, 0.0, f_min_constant=1.0)
    failures = check_function(wrong_min, raise_on_failure=False).failures
    assert [p.name for p in failures] == ["minimum"] and "f_min_for" in failures[0].detail
    flat = BenchmarkFunction("flat", lambda x: np.zeros(x.shape[:-1], dtype=np.float32), -1.0,
                             1.0, 0.0)
    assert [p.name for p in check_function(flat, raise_on_failure=False).failures] == ["shape"]
    with pytest.raises(ConformanceError, match="deterministic"):
        check_function(replace(get_function("F1"), name="noisy-global",
                               kernel=lambda x: _sphere(x) + np.random.random(x.shape[:-1])))  # noqa: NPY002


class _Wild(Planner):
    name = "wild-test-planner"
    kind = "global"

    def decide(self, obs):  # a target that is no point
        return Decision(np.asarray(obs.goal) + np.nan, 0, None)


class _Jittery(Planner):
    name = "jittery-test-planner"
    kind = "global"

    def decide(self, obs):
        jitter = np.random.normal(0, 1e-3, 2)  # noqa: NPY002 - the global state, on purpose
        return Decision(np.asarray(obs.goal, dtype=float) + jitter, 0,
                        None, finish=True)


def test_broken_planners_fail_naming_the_property():
    failures = check_planner(_Wild, raise_on_failure=False).failures
    assert [p.name for p in failures] == ["episode"] and "finite" in failures[0].detail
    failures = check_planner(_Jittery, raise_on_failure=False).failures
    assert "reproducible" in [p.name for p in failures]
    assert "wild-test-planner" not in list_planners()
