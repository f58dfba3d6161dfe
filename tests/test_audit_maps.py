"""swarmpath audit --maps: symmetric copies of a map and the invariance certificate, which holds
for a planner without a preferred place and fails for one pulled towards the world's centre."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.evidence.map_audit import certify
from swarmpath.planners.base import REGISTRY, Decision, Planner
from swarmpath.world import get_map
from swarmpath.world.optimum import shortest_path
from swarmpath.world.scenario_io import save_scenario, scenario_from_dict
from swarmpath.world.symmetry import TRANSFORMS, symmetric_copy

runner = CliRunner()
OPEN = {"name": "open", "size": [10, 10], "start": [1, 2], "goal": [9, 3],
        "robot": {"model": "omni", "radius": 0.2},
        "obstacles": [{"shape": "circle", "center": [2, 8], "radius": 0.5}]}


class CentreSeeker(Planner):
    """Deliberately biased: drives through the centre of its world, then to the goal."""

    name = "TEST-CentreSeeker"
    kind = "global"
    description = "test only: via the world's centre"

    def __init__(self, scenario, params, rng, static_map=None):
        super().__init__(scenario, params, rng, static_map)
        self.leg = 0

    def decide(self, obs):
        w, h = obs.world_size
        self.leg += 1
        if self.leg == 1:
            return Decision(np.array([w / 2.0, h / 2.0]), 1)
        if self.leg == 2:
            return Decision(np.asarray(obs.goal, dtype=float), 1, finish=True, align=True)
        return Decision(None, 0, None, "no more legs")


@pytest.mark.parametrize("kind", TRANSFORMS)
def test_copies_keep_the_exact_optimum(kind):
    s = get_map("mfb-static")
    c = symmetric_copy(s, kind)
    assert c.problems() == []
    optimum = shortest_path(np.array(c.start), np.array(c.goal), c.static_obstacles(),
                            c.robot.radius, world=(0.0, 0.0, *c.size)).length
    # mfb-static's start sits on the world's corner: the box binds, but every copy keeps it
    # (the translated one adds room outside the old box, so its optimum may only shrink)
    if kind == "translate":
        assert optimum <= 14.482999744658636 + 1e-9
    else:
        assert optimum == pytest.approx(14.482999744658636, abs=1e-9)
    if kind == "swap":
        assert (c.start, c.goal) == (s.goal, s.start)


def test_dynamic_maps_have_no_copies():
    with pytest.raises(ValueError, match="only static maps"):
        symmetric_copy(get_map("mfb-dynamic"), "rot90")


def test_certify_by_hand():
    ok = [{"success": True, "gap": 0.01 * (1 + i % 3), "length": 10.0, "optimum": 9.0}
          for i in range(8)]
    same = [dict(r) for r in ok]
    worse = [{**r, "gap": r["gap"] + 0.05} for r in ok]
    lost = [{**r, "success": False} for r in ok]
    cert = certify("P", "m", ok, {"rot90": same, "translate": worse, "mirror": lost})
    assert cert.verdict == "biased" and cert.moved == ["translate", "mirror"]
    by = {c.transform: c for c in cert.copies}
    assert not by["rot90"].moved and by["rot90"].p_gap_holm == 1.0
    assert "median gap 2.00 % -> 7.00 %" in by["translate"].why
    assert "success 8/8 -> 0/8" in by["mirror"].why
    assert by["mirror"].p_gap is None and "mirror" in cert.note
    # a difference below the tolerance never moves it, however regular
    nudged = [{**r, "gap": r["gap"] + 1e-9} for r in ok]
    assert certify("P", "m", ok, {"rot90": nudged}).verdict == "invariant"


def test_the_certificate_holds_for_a_planner_without_bias_and_fails_for_a_centre_seeker(
        tmp_path):
    path = save_scenario(scenario_from_dict(OPEN), tmp_path / "open.json")
    REGISTRY.register(CentreSeeker)
    try:
        result = runner.invoke(app, [
            "audit", "--maps", str(path), "-p", "TEST-CentreSeeker,OMPL-BITstar", "--runs",
            "8", "-j", "1", "--params", json.dumps({"OMPL-BITstar": {"iterations": 500}}),
            "--json"])
    finally:
        REGISTRY.unregister("TEST-CentreSeeker")
    assert result.exit_code == 0, result.stderr
    certs = {c["planner"]: c for c in json.loads(result.stdout)["certificates"]}
    seeker = certs["TEST-CentreSeeker"]
    # rotations and the mirror keep the centre where it was with respect to the map: only the
    # translated copy, whose world centre moved, changes what the seeker drives
    assert seeker["verdict"] == "biased" and seeker["moved"] == ["translate"]
    base = seeker["original"]
    via_centre = math.dist((1, 2), (5, 5)) + math.dist((5, 5), (9, 3))
    assert base["length_median"] == pytest.approx(via_centre, abs=1e-6)
    assert base["gap_median"] == pytest.approx(via_centre / math.dist((1, 2), (9, 3)) - 1,
                                               abs=1e-6)
    moved = next(c for c in seeker["copies"] if c["transform"] == "translate")
    assert moved["p_gap_holm"] < 0.05 and moved["gap_median"] < base["gap_median"] - 0.1
    # the straight line needs no bias to be found: BIT* is invariant on the same map
    assert certs["OMPL-BITstar"]["verdict"] == "invariant"
    assert all(c["successes"] == 8 for c in certs["OMPL-BITstar"]["copies"])


def test_map_audit_refuses_a_moving_map():
    result = runner.invoke(app, ["audit", "--maps", "mfb-dynamic", "-p", "OMPL-BITstar",
                                 "--runs", "1", "-j", "1"])
    assert result.exit_code == 2 and "--maps" in result.stderr
