"""Futility in a race (RaceSettings.futility): a comparison whose predictive power at a planned
look is below the threshold stops. The predictive power is the posterior predictive
probability it claims to be; stopping only takes decisions away (the error rate cannot rise);
it saves runs where nothing differs and costs power that grows with the threshold."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from swarmpath.evidence.group_sequential import predictive_power
from swarmpath.evidence.race_report import race_legend, race_line, study_race
from swarmpath.evidence.racing import FUTILE, RaceSettings, default_design, race_block
from test_racing_looks import LOOKS, _duels

ALPHA = 0.05 / 13  # one comparison at the level of a 13-comparison study


@pytest.mark.parametrize(("p", "t", "level"), [(0.3, 0.2, 0.0075), (0.01, 0.5, 0.0075),
                                                (0.0005, 0.7, 0.001), (0.9, 0.4, 0.05)])
def test_predictive_power_is_the_posterior_predictive_probability(p, t, level):
    """Against a simulation built from the model, not the formula: the drift drawn from its
    flat-prior posterior given the look (S(t) = z sqrt(t) on the Brownian scale), the rest of
    the path drawn, and the final two-sided test counted; within 4 Monte Carlo errors."""
    rng = np.random.default_rng(7)
    n = 400_000
    s = stats.norm.isf(p / 2) * math.sqrt(t)
    drift = rng.normal(s / t, math.sqrt(1 / t), n)
    final = s + drift * (1 - t) + rng.normal(0.0, math.sqrt(1 - t), n)
    simulated = float(np.mean(np.abs(final) >= stats.norm.isf(level / 2)))
    ours = predictive_power(p, t, level)
    assert abs(ours - simulated) <= 4 * math.sqrt(simulated * (1 - simulated) / n) + 1e-4
    # a look that shows nothing, half-way: the final statistic is N(0, 1), so the level itself
    assert predictive_power(1.0, 0.5, level) == pytest.approx(level)
    assert predictive_power(p / 10, t, level) > ours  # a stronger look, a better chance


def _samples(theta: float, races: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Races whose P(A's run beats B's) is theta: normal runs, A shifted."""
    rng = np.random.default_rng(seed)
    shift = math.sqrt(2.0) * stats.norm.ppf(theta)
    return [(rng.normal(size=100) - shift, rng.normal(size=100)) for _ in range(races)]


def test_futility_only_takes_decisions_away_and_saves_runs_where_nothing_differs():
    """The same races with and without futility 0.05: every difference declared with it is
    declared without it, on the same side at the same run count, and no race uses more runs;
    what it changes is races stopped as futile (marker =, the look and its predictive power
    below the threshold recorded). Null races: none declared different, and well under half
    the runs (measured 42 %)."""
    null, effect = _samples(0.5, 150, 41), _samples(0.64, 150, 42)
    for samples in (null, effect):
        without = _duels(samples, RaceSettings(max_runs=100, alpha=ALPHA, **LOOKS))
        with_ = _duels(samples, RaceSettings(max_runs=100, alpha=ALPHA, futility=0.05, **LOOKS))
        for (d, runs), (d0, runs0) in zip(with_, without, strict=True):
            assert runs <= runs0
            if d["decision"] == "different":
                assert (d0["decision"], d0["better"], d0["decided_after"]) == (
                    "different", d["better"], d["decided_after"])
            elif d["decision"] == FUTILE:
                assert d["marker"] == "=" and d["better"] is None and not d["final"]
                assert d["decided_after"] == d["look"] < 100 and d["power"] < 0.05
            else:
                assert d == {**d0, "power": None}
    nulls = _duels(null, RaceSettings(max_runs=100, alpha=ALPHA, futility=0.05, **LOOKS))
    assert not any(d["decision"] == "different" for d, _ in nulls)
    assert sum(r for _, r in nulls) < 0.5 * 200 * len(null)
    assert sum(d["decision"] == FUTILE for d, _ in nulls) > 0.9 * len(null)


def test_futility_costs_power_that_grows_with_its_threshold():
    """theta = 0.6 at 100 runs (measured over these 200 races: 41 declared without futility,
    40 with 0.05, 30 with 0.2, 18 with 0.5): a low threshold keeps nearly every verdict, a
    high one loses most of them; the check can fail (a futility rule that ignored its
    threshold would not lose more at 0.5)."""
    samples = _samples(0.6, 200, 44)

    def declared(futility: float) -> int:
        settings = RaceSettings(max_runs=100, alpha=ALPHA, futility=futility, **LOOKS)
        return sum(d["decision"] == "different" for d, _ in _duels(samples, settings))

    full, low, high = declared(0.0), declared(0.05), declared(0.5)
    assert full > 30
    assert low >= full - 0.1 * full
    assert high < 0.6 * full


def test_the_default_design_stops_for_futility_and_earlier_designs_do_not():
    assert default_design("rank-sum")["futility"] == 0.05
    assert default_design("rank-sum", looks=())["futility"] == 0.0  # the race without looks
    assert default_design("rank-sum", looks=(20,))["futility"] == 0.05
    assert default_design("sign")["futility"] == 0.0 == default_design("none")["futility"]
    assert default_design("rank-sum", futility=0.0)["futility"] == 0.0
    assert RaceSettings(max_runs=100).futility == 0.0  # the settings' own default: none


@pytest.mark.parametrize("bad", [
    dict(futility=1.0, **LOOKS),
    dict(futility=-0.1, **LOOKS),
    dict(futility=0.1),  # no looks to judge it at
    dict(futility=0.1, final_test="none", looks=(20,), look_share=0.5),  # no closing look
])
def test_bad_futility_names_the_field(bad):
    with pytest.raises(ValueError, match=r"^futility"):
        RaceSettings(max_runs=100, **bad)


def test_the_race_document_names_its_futility():
    """A futile comparison in the document and the words on it: the race line and the legend
    name the threshold, and the settings read back."""
    settings = RaceSettings(max_runs=100, futility=0.05, **LOOKS)
    runs = np.random.default_rng(5).normal(size=100)  # B's runs are A's: nothing to find
    race = race_block({"A": runs, "B": runs.copy()}, ["A", "B"], settings, 1)
    doc = study_race(settings, 1, [({"function": "F1", "dim": 2}, race, [(0, "A"), (1, "B")])])
    (duel,) = doc["blocks"][0]["duels"]
    assert duel["decision"] == FUTILE and 0.0 <= duel["power"] < 0.05
    assert race.runs_used() == 2 * duel["look"] < 200
    assert RaceSettings(**doc["settings"]) == settings
    assert "futility below 0.05" in race_line(doc) and "futile" in race_legend(doc, "B")
