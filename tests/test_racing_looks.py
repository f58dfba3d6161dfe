"""Planned looks of a race (RaceSettings.looks, a group-sequential design): null races keep the
error rate and a deliberately unspent allocation does not; a small effect is decided at a look,
with fewer runs than without looks; bad designs are refused naming the field."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from swarmpath.evidence import race_settings, racing
from swarmpath.evidence.race_report import race_legend, race_line, study_race
from swarmpath.evidence.racing import RaceSettings, race_block

LOOKS = dict(looks=(20, 30, 40, 50, 60, 70, 80, 90), look_share=0.8, sequence_share=0.05,
             spending="pocock")


def _duels(pairs, settings):
    """Each pair (A's runs, B's runs) raced alone (one comparison), the closing look taken."""
    out = []
    for a, b in pairs:
        race = race_block({"A": a, "B": b}, ["A", "B"], settings, 1, intervals=False)
        doc = study_race(settings, 1, [({}, race, [(0, "A"), (1, "B")])])
        out.append((doc["blocks"][0]["duels"][0], race.runs_used()))
    return out


def _rate(duels):
    return float(np.mean([d["decision"] == "different" for d, _ in duels]))


def test_null_races_with_looks_keep_alpha_and_an_unspent_allocation_does_not(monkeypatch):
    """500 null races at alpha 0.2 (the sequence 0.01, 8 looks 0.16 Pocock-spent, the closing
    rank-sum test 0.03): false differences at most alpha within 3 standard errors (measured
    0.154), most of them by the looks (the share is spent, not idle). The same races with every
    look at the looks' whole share (the allocation that ignores that a comparison is looked at
    8 times) break the bound (measured 0.43): the check can fail."""
    rng = np.random.default_rng(31)
    samples = [(rng.normal(size=100), rng.normal(size=100)) for _ in range(500)]
    settings = RaceSettings(max_runs=100, alpha=0.2, min_runs=10, batch=10, **LOOKS)
    bound = 0.2 + 3 * math.sqrt(0.2 * 0.8 / len(samples))
    ours = _duels(samples, settings)
    assert _rate(ours) <= bound
    assert sum(d["look"] is not None for d, _ in ours) > 0.5 * 0.2 * len(samples)
    monkeypatch.setattr(race_settings, "nominal_levels",
                        lambda looks, level, kind: (level,) * len(looks))
    assert _rate(_duels(samples, settings)) > bound


def test_a_small_effect_is_decided_at_a_look_with_fewer_runs_than_without():
    """theta = 0.64 at 100 runs, one comparison at the level of a 13-comparison study: with
    looks, many more races decided before max_runs, all for the better algorithm, most at a
    look (``look`` and ``decided_after`` its run count), and fewer runs in all (the price: the
    closing look at max_runs has a smaller share, docs/statistics.md, Racing)."""
    rng = np.random.default_rng(32)
    shift = math.sqrt(2.0) * stats.norm.ppf(0.64)
    samples = [(rng.normal(size=100) - shift, rng.normal(size=100)) for _ in range(100)]
    plain = _duels(samples, RaceSettings(max_runs=100, alpha=0.05 / 13))
    looked = _duels(samples, RaceSettings(max_runs=100, alpha=0.05 / 13, **LOOKS))

    def early(duels):
        return sum(d["decision"] == "different" and d["decided_after"] < 100 for d, _ in duels)

    assert early(looked) > early(plain) + 20
    assert sum(r for _, r in looked) < sum(r for _, r in plain)
    at_look = [d for d, _ in looked if d["look"] is not None]
    assert len(at_look) > 20
    assert all(d["better"] == "A" and d["decided_after"] == d["look"] < 100 and not d["final"]
               for d in at_look)
    assert all(d["better"] == "A" for d, _ in looked + plain if d["decision"] == "different")
    assert not any(d["look"] for d, _ in plain)


def test_the_race_document_names_its_looks():
    settings = RaceSettings(max_runs=100, **LOOKS)
    race = race_block({"A": np.arange(100.0), "B": np.arange(100.0) + 50}, ["A", "B"],
                      settings, 1)
    doc = study_race(settings, 1, [({"function": "F1", "dim": 2}, race, [(0, "A"), (1, "B")])])
    assert doc["settings"]["looks"] == list(LOOKS["looks"])
    assert RaceSettings(**doc["settings"]) == settings  # a stored document reads back
    assert "looks at 20,30" in race_line(doc) and "pocock" in race_legend(doc, "B")


@pytest.mark.parametrize(("bad", "field"), [
    (dict(looks=(25,), look_share=0.5, sequence_share=0.1), "looks"),  # not a round
    (dict(looks=(100,), look_share=0.5, sequence_share=0.1), "looks"),  # max_runs itself
    (dict(looks=(30, 20), look_share=0.5, sequence_share=0.1), "looks"),
    (dict(looks=(20,)), "looks"),  # no share
    (dict(look_share=0.3), "looks"),  # a share without looks
    (dict(looks=(20,), look_share=0.5), "sequence_share"),  # nothing left to the closing look
    (dict(looks=(20,), look_share=0.5, final_test="sign"), "looks"),
    (dict(sequence_share=0.3, final_test="none"), "sequence_share"),
    (dict(looks=(20,), look_share=0.4, sequence_share=0.1, spending="linear"), "spending"),
])
def test_bad_designs_name_the_field(bad, field):
    with pytest.raises(ValueError, match=f"^{field}"):
        RaceSettings(max_runs=100, **bad)


def test_without_looks_the_shares_are_those_of_earlier_races():
    plain = RaceSettings(max_runs=100)
    assert plain.levels(10) == (0.05 / 10 / 2, 0.0) and plain.closing_alpha == 0.025
    assert plain.look_levels(10) == {}
    none = RaceSettings(max_runs=100, final_test="none", looks=(50,), look_share=0.25)
    assert none.levels(10) == (0.05 / 10 * 0.75, 0.0) and none.closing_alpha == 0.0


def test_looks_every_round_follow_the_race_s_rounds():
    """looks 'every-round': each round's run count after the first below max_runs, from the
    race's own min_runs, batch and max_runs; the same boundaries as those run counts listed; a
    race with no such round gives the looks' share to the closing look."""
    every = dict(LOOKS, looks=racing.EVERY_ROUND)
    settings = RaceSettings(max_runs=100, **every)
    assert settings.look_runs == LOOKS["looks"]
    assert settings.look_levels(13) == RaceSettings(max_runs=100, **LOOKS).look_levels(13)
    assert RaceSettings(max_runs=57, min_runs=8, batch=8, **every).look_runs == (
        16, 24, 32, 40, 48, 56)
    short = RaceSettings(max_runs=20, **every)  # rounds at 10 and 20: no look between
    assert short.look_runs == () and short.look_levels(4) == {}
    assert short.closing_alpha == pytest.approx(0.05 * 0.95)
    doc = study_race(settings, 1, [({"function": "F1", "dim": 2}, race_block(
        {"A": np.arange(100.0), "B": np.arange(100.0) + 50}, ["A", "B"], settings, 1),
        [(0, "A"), (1, "B")])])
    assert doc["settings"]["looks"] == "every-round"
    assert RaceSettings(**doc["settings"]) == settings
    assert "looks every round from 20 (pocock)" in race_line(doc)
    with pytest.raises(ValueError, match=r"^looks"):
        RaceSettings(max_runs=100, **dict(LOOKS, looks="every-other"))


def _stepped(values, names, settings, memo):
    """The block's race as the store replays it: from the first round, once per completed
    round, each cell holding the runs its allowance gave it; every step's race."""
    steps = []
    have = {a: settings.min_runs for a in names}
    while True:
        race = race_block({a: values[a][:have[a]] for a in names}, names, settings, 13,
                          memo=memo)
        steps.append(race)
        if race.finished or race.allowance == have:
            return steps
        have = dict(race.allowance)


def _state(race):
    return (race.rounds, race.allowance, race.racing, race.stopped_round, race.stop_reason,
            [d.to_json() for d in race.duels])


@pytest.mark.parametrize("entries", [100_000, 7])
def test_the_look_memo_changes_no_decision_at_any_round(entries):
    """The store's replays with the looks' tests kept in a memo (race_tests.LookMemo) decide
    exactly as without it, at every round of every block (small, medium and no effects, ties,
    failed runs, a memo so small it empties itself); the memo is used: later replays find the
    past looks' tests, so each step tests only its own round's looks."""
    from swarmpath.evidence.race_tests import LookMemo

    rng = np.random.default_rng(33)
    settings = RaceSettings(max_runs=300, **dict(LOOKS, looks=racing.EVERY_ROUND))
    names = ["A", "B", "C", "R"]
    memo = LookMemo(entries)
    looked = 0
    for shift in (0.0, 0.15, 0.3, 0.6):  # A, B and C better than R by 1, 2 and 3 shifts
        values = {a: rng.normal(size=300) - shift * {"A": 1, "B": 2, "C": 3, "R": 0}[a]
                  for a in names}
        values["B"][::17] = np.inf  # runs without a number count as the worst
        values["C"] = np.round(values["C"], 1)  # ties
        with_memo = _stepped(values, names, settings, memo)
        without = _stepped(values, names, settings, None)
        assert [_state(r) for r in with_memo] == [_state(r) for r in without]
        looked += sum(d.look is not None for d in without[-1].duels)
    assert looked >= 2  # looks decided something
    if entries > 7:
        assert memo.hits > 4 * memo.misses > 0  # past looks found, not tested again
    else:
        assert len(memo) <= 7


def test_a_memo_hit_is_the_test_s_own_result():
    """A look read from the memo is the very (p, side) the test gives for those samples, whatever
    else was tested with it in one vectorized call."""
    from swarmpath.evidence.race_tests import LookMemo, rank_sum_tests

    rng = np.random.default_rng(34)
    pairs = [(rng.normal(size=n) - 0.2, rng.normal(size=n)) for n in (5, 40, 40, 120)]
    memo = LookMemo()
    assert memo.tests(pairs[:3]) == rank_sum_tests(pairs[:3])
    assert memo.tests(pairs[::-1]) == [rank_sum_tests([p])[0] for p in pairs[::-1]]
    assert (memo.hits, memo.misses) == (3, 4)
    other = (pairs[1][0].copy(), pairs[1][1].copy())
    other[0][-1] += 1e-12  # one value differs: another key
    assert LookMemo.key(*other) != LookMemo.key(*pairs[1])
