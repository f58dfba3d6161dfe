"""swarm:<optimizer>: the seeds' swarm local planner driven by any registered optimizer, named
that way in runs, tables and job specs."""

from __future__ import annotations

import numpy as np
import pytest

from swarmpath.optimizers import register
from swarmpath.optimizers.gwo import GWO
from swarmpath.optimizers.registry import REGISTRY as OPTIMIZERS
from swarmpath.planners import Episode, PlannerError, get_planner, list_planners
from swarmpath.testing import check_planner
from swarmpath.testing.planner import scenario


def _path(planner: str, params: dict | None = None, seed: int = 2) -> np.ndarray:
    out = Episode(scenario(), planner, seed, 0, params=params).run()
    assert out.planner == planner
    return np.asarray(out.path)


@pytest.mark.parametrize("optimizer", ["GWO", "PSO"])
def test_swarm_family_is_the_preset_of_the_same_optimizer_run_for_run(optimizer):
    # the GWO and PSO presets are the seeds' framework with that optimizer: the same runs
    assert np.array_equal(_path(f"swarm:{optimizer}"), _path(optimizer))


def test_a_plugin_optimizer_drives_the_planner_with_its_own_parameters():
    @register
    class Cosine(GWO):
        name = "family-test-gwo"

    try:
        cls = get_planner("swarm:family-test-gwo")
        assert cls.defaults["optimizer.a_max"] == 2.0 and "optimizer.leaders" in cls.choices
        default = _path("swarm:family-test-gwo")
        assert np.array_equal(default, _path("GWO"))  # a GWO under another name
        steeper = _path("swarm:family-test-gwo", {"optimizer.a_max": 2.6})
        assert not np.array_equal(default, steeper)  # the optimizer's parameter is used
        assert "swarm:family-test-gwo" not in list_planners()  # a family: not listed
        with pytest.raises(PlannerError, match="a_max"):
            cls.resolve_params({"optimizer.a_max": "steep"})
    finally:
        OPTIMIZERS.unregister("family-test-gwo")


def test_a_preset_refuses_another_optimizer_and_names_the_family():
    with pytest.raises(PlannerError, match="planner 'swarm:PSO'"):
        get_planner("GWO").resolve_params({"optimizer": "PSO"})
    with pytest.raises(PlannerError, match="unknown optimizer 'NOPE'"):
        get_planner("swarm:NOPE")
    with pytest.raises(PlannerError, match=r"swarm:<name>"):
        get_planner("NOPE")


def test_swarm_family_passes_the_gate():
    assert check_planner("swarm:SSA").ok


def test_job_spec_takes_swarm_planners_and_names_a_bad_one():
    from pydantic import ValidationError

    from swarmpath.service.protocol import parse_job_spec

    spec = parse_job_spec({"kind": "map", "planners": ["swarm:GWO", "ICOOT"],
                           "maps": ["mfb-static"], "runs": 1})
    assert spec.planners == ["swarm:GWO", "ICOOT"]
    with pytest.raises(ValidationError) as err:
        parse_job_spec({"kind": "map", "planners": ["swarm:NOPE"], "maps": ["mfb-static"],
                        "runs": 1})
    assert "unknown optimizer 'NOPE'" in str(err.value) and "planners" in str(err.value)


def test_cli_names_it_swarm_in_runs_and_tables(tmp_path):
    from typer.testing import CliRunner

    from swarmpath.cli import app

    out = CliRunner().invoke(app, ["plan", "-p", "swarm:RFO", "-m", "mfb-static", "--runs",
                                   "1", "--json"])
    assert out.exit_code == 0, out.output
    import json

    doc = json.loads(out.stdout)
    assert [r["planner"] for r in doc["runs"]] == ["swarm:RFO"]
    assert [s["planner"] for s in doc["summary"]] == ["swarm:RFO"]
    bad = CliRunner().invoke(app, ["plan", "-p", "swarm:NOPE", "-m", "mfb-static"])
    assert bad.exit_code == 2 and "unknown optimizer 'NOPE'" in bad.stderr
