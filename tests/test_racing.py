"""Racing's statistics (swarmpath.evidence.sequential, swarmpath.evidence.racing): the betting
confidence sequence against a plain loop, its error rate under optional stopping (and the naive
repeated rank-sum test failing the same check), and the rounds of a block."""

import math

import numpy as np
import pytest
from scipy import stats

from swarmpath.evidence.race_report import close_race, study_race
from swarmpath.evidence.racing import (
    RaceSettings,
    closing_rejections,
    comparisons_per_block,
    race_block,
)
from swarmpath.evidence.sequential import (
    BET_CAP,
    confidence_sequence,
    decide,
    pair_scores,
    rejection_times,
    sign_test,
)
from swarmpath.optimizers import minimize


def test_pair_scores_pair_runs_by_index_ties_half_and_drop_failed_runs():
    z = pair_scores([1.0, 2.0, 3.0, np.nan, 5.0, np.inf, 7.0], [2.0, 2.0, 1.0, 0.0, np.nan, 9.0])
    # pairs 0..5 (the shorter sample); pair 3 and 4 have a NaN; inf is a value (worst)
    assert z.tolist() == [1.0, 0.5, 0.0, 0.0]


def _capital_loop(z, m, alpha):
    """W-S & R's hedged capital (half the larger of the two bets' capitals) with the predictable
    plug-in bets, one pair at a time."""
    up = down = 1.0
    total = sq = 0.0
    s2_prev = 0.25
    out = []
    for t, x in enumerate(z, start=1):
        lam = math.sqrt(2 * math.log(2 / alpha) / (s2_prev * t * math.log(1 + t)))
        up *= 1 + min(lam, BET_CAP / m) * (x - m)
        down *= 1 - min(lam, BET_CAP / (1 - m)) * (x - m)
        out.append(0.5 * max(up, down))
        total += x
        mu = (0.5 + total) / (t + 1)
        sq += (x - mu) ** 2
        s2_prev = (0.25 + sq) / (t + 1)
    return np.array(out)


@pytest.mark.parametrize("m", [0.3, 0.5, 0.62])
def test_rejection_times_are_where_the_plain_loop_capital_first_reaches_one_over_alpha(m):
    rng = np.random.default_rng(4)
    z = pair_scores(rng.normal(size=80) - 0.4, rng.normal(size=80))
    capital = _capital_loop(z, m, 0.05)
    hits = np.flatnonzero(capital >= 20.0)
    expected = hits[0] + 1 if hits.size else 0
    assert rejection_times(z, [m], 0.05)[0] == expected


def test_the_confidence_set_is_an_interval_after_every_pair():
    """What an equivalence decided from its two end points relies on: no m inside the set's
    hull has been rejected (checked on a grid, for sequences with ties, after every prefix)."""
    rng = np.random.default_rng(5)
    grid = np.linspace(0.005, 0.995, 199)
    for _ in range(60):
        n = int(rng.integers(5, 120))
        z = rng.choice([0.0, 0.5, 1.0], size=n, p=rng.dirichlet([1.0, 1.0, 1.0]))
        alpha = float(10 ** rng.uniform(-4, -1))
        for t in (n // 3, n):
            alive = np.flatnonzero(rejection_times(z[:t], grid, alpha) == 0)
            assert alive.size and alive[-1] - alive[0] + 1 == alive.size


def test_a_sweep_is_decided_for_the_winner_in_twenty_pairs_at_the_table_level():
    # K_t(1/2) = 1.5^t / 2 once the bets hit their cap: 1/alpha = 1300 at t = 20
    d = decide(np.ones(40), 0.05 / 65)
    assert (d.decision, d.better, d.at) == ("different", "a", 20)
    d = decide(np.zeros(40), 0.05 / 65)
    assert (d.decision, d.better) == ("different", "b")


def test_identical_runs_are_equivalent_with_a_margin_and_never_different():
    z = np.full(300, 0.5)  # the same algorithm under two names: every pair ties
    assert decide(z, 0.01).decision == "open"
    d = decide(z, 0.01, margin=0.1)
    assert d.decision == "equivalent" and 0 < d.at < 300
    assert d.low < 0.5 < d.high and d.high - d.low < 0.2


def test_the_confidence_sequence_covers_theta_and_narrows():
    rng = np.random.default_rng(7)
    theta = 0.7  # Z ~ Bernoulli(0.7)
    covered = 0
    for _ in range(200):
        z = (rng.random(200) < theta).astype(float)
        low, high = confidence_sequence(z, 0.1)
        covered += low <= theta <= high
    assert covered >= 200 * 0.9 - 3 * math.sqrt(200 * 0.09)
    low, high = confidence_sequence(np.ones(10), 0.05)
    assert high == pytest.approx(1.0, abs=1e-3) and low > 0.5


def _false_difference_rates(samples, alpha, looks):
    """Share of null races declared different by the confidence sequence, and by the rank-sum
    test repeated at every look (the naive race)."""
    ours = naive = 0
    for a, b in samples:
        ours += decide(pair_scores(a, b), alpha, interval=False).decision == "different"
        naive += any(stats.mannwhitneyu(a[:n], b[:n]).pvalue < alpha for n in looks)
    return ours / len(samples), naive / len(samples)


def test_optional_stopping_keeps_the_error_rate_where_a_repeated_rank_sum_test_loses_it():
    rng = np.random.default_rng(11)
    samples = [(rng.normal(size=200), rng.normal(size=200)) for _ in range(300)]
    ours, naive = _false_difference_rates(samples, 0.05, range(20, 201, 20))
    sd = math.sqrt(0.05 * 0.95 / 300)
    assert ours <= 0.05 + 3 * sd
    assert naive > 0.05 + 3 * sd  # the check can fail: the naive race fails it


def test_one_optimizer_raced_against_itself_on_other_streams_rarely_differs():
    """Two seeds of PSO on every function: exchangeable runs, so differences are false ones."""
    samples = []
    for f in [f"F{i}" for i in range(1, 14)]:
        for s in range(12):
            a = minimize("PSO", f, dim=3, agents=6, iterations=8, runs=60, seed=100 + s)
            b = minimize("PSO", f, dim=3, agents=6, iterations=8, runs=60, seed=500 + s)
            samples.append((a.best_fitness, b.best_fitness))
    ours, _ = _false_difference_rates(samples, 0.05, [])
    assert ours <= 0.05 + 3 * math.sqrt(0.05 * 0.95 / len(samples))


def _raced(pairs, final_test, max_runs, alpha=0.05, step=20):
    """Each pair (A's runs, B's runs) raced alone (one comparison), its closing look taken: the
    duel as the race document shows it."""
    settings = RaceSettings(max_runs=max_runs, alpha=alpha, min_runs=step, batch=step,
                            final_test=final_test)
    return [study_race(settings, 1, [({}, race_block({"A": a, "B": b}, ["A", "B"], settings, 1,
                                                     intervals=False),
                                      [(0, "A"), (1, "B")])])["blocks"][0]["duels"][0]
            for a, b in pairs]


def _rate(duels):
    return float(np.mean([d["decision"] == "different" for d in duels]))


def test_the_closing_sign_test_keeps_the_error_rate_under_optional_stopping():
    """Null races (one distribution) with the sign look of earlier jobs: the sequence at
    alpha/2 over 10 rounds, then one sign test at alpha/2 at max_runs."""
    rng = np.random.default_rng(12)
    samples = [(rng.normal(size=200), rng.normal(size=200)) for _ in range(400)]
    duels = _raced(samples, "sign", 200)
    assert _rate(duels) <= 0.05 + 3 * math.sqrt(0.05 * 0.95 / 400)
    assert any(d["final"] for d in duels)  # the look did fire (its alpha is spent, not idle)


def test_the_closing_rank_sum_look_keeps_the_error_rate_and_needs_the_union_bound():
    """400 null races (two independent samples of one distribution) at alpha 0.2, the
    sequence at 0.1 over 10 rounds, the rank-sum test at 0.1 at max_runs: false differences
    at most alpha. The same races with each part at the whole 0.2 (no union bound: a race at
    alpha 0.4) break the bound: the check can fail."""
    rng = np.random.default_rng(21)
    samples = [(rng.normal(size=100), rng.normal(size=100)) for _ in range(400)]
    bound = 0.2 + 3 * math.sqrt(0.2 * 0.8 / 400)
    ours = _raced(samples, "rank-sum", 100, alpha=0.2, step=10)
    assert _rate(ours) <= bound  # measured: 0.16; with each part at 0.2, 0.30
    assert sum(d["final"] for d in ours) > 20  # the look's share is spent, not idle
    assert _rate(_raced(samples, "rank-sum", 100, alpha=0.4, step=10)) > bound


def test_the_rank_sum_look_holds_the_study_error_rate_with_holm_over_open_comparisons():
    """Studies of 4 blocks, each a strong effect (A) and a null (B) against the reference R:
    the sequence declares the A's, Holm's family is what it left (the B's, which share R with
    the A's); a false difference anywhere in the study at most alpha (0.2 here, 300 studies),
    the look firing on the nulls (Holm at 0.1 over the 4 B's: about 0.1 of the studies)."""
    rng = np.random.default_rng(22)
    settings = RaceSettings(max_runs=80, alpha=0.2, min_runs=10, batch=10)
    false = by_look = 0
    for _ in range(300):
        blocks = []
        for _ in range(4):
            v = {"A": rng.normal(size=80) - 2.0, "B": rng.normal(size=80),
                 "R": rng.normal(size=80)}
            blocks.append(({}, race_block(v, ["A", "B", "R"], settings, 8, intervals=False),
                           [(0, "A"), (1, "B"), (2, "R")]))
        duels = [d for b in study_race(settings, 8, blocks)["blocks"] for d in b["duels"]]
        assert all(d["decision"] == "different" and not d["final"] for d in duels
                   if d["a"] == "A")
        null = [d for d in duels if d["a"] == "B"]
        false += any(d["decision"] == "different" for d in null)
        by_look += any(d["final"] for d in null)
    assert false / 300 <= 0.2 + 3 * math.sqrt(0.2 * 0.8 / 300)
    assert by_look >= 10


def test_the_closing_looks_decide_a_small_effect_the_sequence_leaves_open():
    """theta = 0.6 at 200 runs: the sequence alone decides some races; each closing look
    decides most of the rest, the rank-sum look more than the sign test, always for the better
    algorithm, and only at max_runs."""
    rng = np.random.default_rng(13)
    shift = math.sqrt(2.0) * stats.norm.ppf(0.6)
    samples = [(rng.normal(size=200) - shift, rng.normal(size=200)) for _ in range(100)]
    looks = {look: _raced(samples, look, 200) for look in ("none", "sign", "rank-sum")}
    decided = {look: sum(d["decision"] == "different" for d in r) for look, r in looks.items()}
    assert decided["sign"] >= decided["none"] + 20
    assert decided["rank-sum"] >= decided["sign"] + 10
    for look in ("sign", "rank-sum"):
        final = [d for d in looks[look] if d["final"]]
        assert final and all(d["better"] == "A" and d["decided_after"] == 200 for d in final)
    assert not any(d["final"] for d in looks["none"])


def test_closing_rejections_are_holm_over_the_family_with_the_unknown_at_one():
    assert closing_rejections([0.012, 0.02], 2, 0.025) == [True, True]
    assert closing_rejections([0.012, 0.02], 4, 0.025) == [False, False]  # 0.048
    assert closing_rejections([0.004, 0.02], 4, 0.025) == [True, False]
    assert closing_rejections([], 3, 0.025) == []
    with pytest.raises(ValueError, match="family"):
        closing_rejections([0.01, 0.01], 1, 0.05)


def _doc(look, p_open, declared):
    """A race document of one block: ``declared`` duels the sequence decided, one open at
    max_runs per p in ``p_open`` (B's runs lower)."""
    settings = RaceSettings(max_runs=100, final_test=look).to_json()
    duels = [{"a": f"D{i}", "b": "R", "decision": "different", "better": "R", "marker": "-",
              "round": 1, "pairs": 20, "decided_after": 20, "final": False,
              "closing_p": None, "closing_better": None} for i in range(declared)]
    duels += [{"a": f"O{i}", "b": "R", "decision": "open", "better": None, "marker": "=",
               "round": None, "pairs": 100, "decided_after": 0, "final": False,
               "closing_p": p, "closing_better": "R"} for i, p in enumerate(p_open)]
    return {"settings": settings, "comparisons": declared + len(p_open),
            "blocks": [{"block": {}, "rounds": 10, "finished": True, "cells": [],
                        "duels": duels}]}


def test_close_race_decides_what_holm_rejects_and_only_for_the_rank_sum_look():
    doc = _doc("rank-sum", [0.012, 0.02], 2)
    closed = close_race(doc)
    opened = [d for d in closed["blocks"][0]["duels"] if d["a"].startswith("O")]
    assert [(d["decision"], d["better"], d["marker"], d["final"], d["round"],
             d["decided_after"]) for d in opened] == [("different", "R", "-", True, 9, 100)] * 2
    assert doc == _doc("rank-sum", [0.012, 0.02], 2)  # the input is left as it was
    assert close_race(closed) == closed  # its own decisions do not shrink the family again
    for look in ("sign", "none"):
        assert close_race(_doc(look, [1e-9], 0)) == _doc(look, [1e-9], 0)


def test_sign_test_drops_ties_and_names_the_side_that_wins_more_pairs():
    assert sign_test(np.full(500, 0.5), 0.05) is None  # all ties: nothing to test
    z = np.r_[np.ones(40), np.zeros(20), np.full(100, 0.5)]
    assert sign_test(z, 0.05) == "a"  # 40 of 60: p = 0.013
    assert sign_test(1.0 - z, 0.05) == "b"
    assert sign_test(z, 0.01) is None


def test_comparisons_are_against_the_reference_listed_last_or_every_pair():
    assert comparisons_per_block(["A", "B", "R"], "reference") == [("A", "R"), ("B", "R")]
    assert comparisons_per_block(["A", "B", "R"], "all") == [("A", "B"), ("A", "R"), ("B", "R")]


def _block_values(n):
    rng = np.random.default_rng(3)
    return {"A": rng.normal(size=n) - 3, "B": rng.normal(size=n), "R": rng.normal(size=n)}


def test_a_block_races_in_rounds_and_stops_a_cell_once_its_comparisons_are_decided():
    settings = RaceSettings(max_runs=60, min_runs=10, batch=10)
    full = _block_values(60)
    race = race_block({k: v[:5] for k, v in full.items()}, ["A", "B", "R"], settings, 2)
    assert race.rounds == 0 and race.allowance == {"A": 10, "B": 10, "R": 10}
    race = race_block(full, ["A", "B", "R"], settings, 2)
    a, b = race.duels
    assert a.result.decision == "different" and a.marker == "+" and a.round is not None
    assert race.stop_reason["A"] == "decided" and race.allowance["A"] == settings.allowance(
        a.round)
    assert b.result.decision == "open" and b.marker == "="  # B and R do not differ
    assert race.stop_reason == {"A": "decided", "B": "max_runs", "R": "max_runs"}
    assert race.finished and race.runs_used() == race.allowance["A"] + 120


def test_a_race_is_a_function_of_the_runs_only_and_an_extension_continues_it():
    settings = RaceSettings(max_runs=30, min_runs=10, batch=10)
    full = _block_values(200)
    # the runs a finished race used, and nothing more, give the same race
    race = race_block(full, ["A", "B", "R"], settings, 2)
    used = {k: v[: race.allowance[k]] for k, v in full.items()}
    again = race_block(used, ["A", "B", "R"], settings, 2)
    assert again.allowance == race.allowance and again.duels == race.duels
    # extended to 200 runs: A's decision stands, B and R go on from their 30 runs
    longer = race_block(used, ["A", "B", "R"], RaceSettings(max_runs=200, batch=10), 2)
    assert longer.duels[0] == race.duels[0]
    assert longer.racing == {"A": False, "B": True, "R": True}
    assert longer.allowance["B"] == 40 and longer.rounds == 3


def test_the_same_algorithm_under_two_names_is_declared_equivalent_and_stops():
    runs = np.random.default_rng(1).normal(size=400)
    settings = RaceSettings(max_runs=400, min_runs=10, batch=10, margin=0.1)
    race = race_block({"A": runs, "A2": runs.copy()}, ["A", "A2"], settings, 1)
    (duel,) = race.duels
    assert duel.result.decision == "equivalent" and duel.marker == "="
    assert race.finished and race.allowance["A"] < 400


@pytest.mark.parametrize("bad", [dict(alpha=0), dict(min_runs=0), dict(batch=0),
                                 dict(pairs="some"), dict(margin=0.5), dict(max_runs=5)])
def test_bad_race_settings_name_the_parameter(bad):
    kwargs = dict(max_runs=100) | bad
    with pytest.raises(ValueError, match=next(iter(bad)).split("_")[0]):
        RaceSettings(**kwargs)
