"""Recycling within a race's block (RaceSettings.recycle): the looks' share of a comparison
declared different goes to the block's open ones, Holm's step-down. Blocks where some
algorithms differ and others do not keep the error rate with it, and an allocation that does
not divide the passed share breaks it; it decides no less and no later than without."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmpath.evidence.race_report import study_race
from swarmpath.evidence.race_settings import default_design
from swarmpath.evidence.racing import RaceSettings, race_block
from test_racing_looks import LOOKS

#: Two algorithms far better than the reference R, three that are R under other names.
NAMES = ["D1", "D2", "N1", "N2", "N3", "R"]
NULLS = ("N1", "N2", "N3")


def _blocks(studies: int, seed: int) -> list[dict[str, np.ndarray]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(studies):
        values = {n: rng.normal(size=100) for n in NAMES}
        out.append({n: v - 3.0 if n.startswith("D") else v for n, v in values.items()})
    return out


def _raced(blocks, settings):
    """Each block raced as a study of its 5 comparisons: its duels and runs."""
    out = []
    for values in blocks:
        race = race_block(values, NAMES, settings, 5, intervals=False)
        doc = study_race(settings, 5, [({}, race, list(enumerate(NAMES)))])
        out.append(({d["a"]: d for d in doc["blocks"][0]["duels"]}, race.runs_used()))
    return out


def _false_rate(raced) -> float:
    return float(np.mean([any(duels[n]["decision"] == "different" for n in NULLS)
                          for duels, _ in raced]))


def test_recycled_shares_keep_the_error_rate_and_an_undivided_share_does_not(monkeypatch):
    """250 blocks at alpha 0.2 (the sequence 0.01, 8 looks 0.16, the closing look 0.03): the
    studies with a false difference among the three that do not differ stay within alpha plus
    3 standard errors (0.276) with recycling (measured 0.128; without it 0.08: the share passed
    on is used). Passing the whole block's share to each open comparison instead of dividing it
    (Holm's step-down ignored) errs at 0.344, above the bound: the check can fail."""
    blocks = _blocks(250, 3)
    settings = RaceSettings(max_runs=100, alpha=0.2, recycle=True, **LOOKS)
    bound = 0.2 + 3 * math.sqrt(0.2 * 0.8 / len(blocks))
    plain = _raced(blocks, RaceSettings(max_runs=100, alpha=0.2, **LOOKS))
    recycled = _raced(blocks, settings)
    assert _false_rate(plain) < _false_rate(recycled) <= bound
    undivided = RaceSettings.look_levels
    monkeypatch.setattr(RaceSettings, "look_levels", lambda self, comparisons, weight=1.0:
                        undivided(self, comparisons, 5.0 if weight > 1.0 else 1.0))
    assert _false_rate(_raced(blocks, settings)) > bound


def test_recycling_decides_no_less_and_no_later():
    """Without futility, every comparison declared different without recycling is declared
    with it, on the same side, after as many runs or fewer, and no block uses more runs; some
    are decided earlier."""
    rng = np.random.default_rng(9)
    blocks = [{"D1": rng.normal(size=100) - 3.0, "D2": rng.normal(size=100) - 0.6,
               "N1": rng.normal(size=100) - 0.45, "N2": rng.normal(size=100) + 0.5,
               "N3": rng.normal(size=100), "R": rng.normal(size=100)} for _ in range(60)]
    plain = _raced(blocks, RaceSettings(max_runs=100, alpha=0.05, **LOOKS))
    recycled = _raced(blocks, RaceSettings(max_runs=100, alpha=0.05, recycle=True, **LOOKS))
    earlier = 0
    for (duels0, runs0), (duels, runs) in zip(plain, recycled, strict=True):
        assert runs <= runs0
        for name, d0 in duels0.items():
            if d0["decision"] == "different":
                d = duels[name]
                assert d["decision"] == "different" and d["better"] == d0["better"]
                assert d["decided_after"] <= d0["decided_after"]
                earlier += d["decided_after"] < d0["decided_after"]
    assert earlier > 10


def test_recycling_is_the_default_with_looks_and_needs_them():
    assert default_design("rank-sum")["recycle"] is True
    assert default_design("rank-sum", looks=())["recycle"] is False
    assert default_design("none", looks=(20,))["recycle"] is True
    assert RaceSettings(max_runs=100).recycle is False
    with pytest.raises(ValueError, match=r"^recycle"):
        RaceSettings(max_runs=100, recycle=True)
    settings = RaceSettings(max_runs=100, recycle=True, **LOOKS)
    assert settings.look_levels(10, 2.5)[20] > settings.look_levels(10)[20]
    assert settings.look_levels(10, 2.0) == RaceSettings(
        max_runs=100, alpha=0.1, **LOOKS).look_levels(10)  # the share doubled
