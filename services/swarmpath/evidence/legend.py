"""What the result columns mean, in one place: printed under the CLI tables and shown by the
dashboard (``legend(columns)``), so that both say the same thing."""

from __future__ import annotations

from collections.abc import Iterable

#: Column name -> one sentence. Keys are the summary's column names (``failed``, ``collisions``,
#: ``gap_mean``, ...) and the CLI's spellings of the same columns.
NOTES: dict[str, str] = {
    "failed": "runs that crashed (an exception in the optimizer, planner or worker); a run that "
              "did not reach the goal is not failed, it counts against success_rate",
    "success_rate": "share of finished runs that reached the goal without touching an obstacle",
    "collisions": "simulated steps in which the robot body touched an obstacle, summed over the "
                  "runs (one run grazing an obstacle for 3 steps counts 3)",
    "gap_mean": "mean excess of the path length over the exact shortest path, over successful "
                "runs; blank on maps with moving obstacles or a moving goal (no exact optimum "
                "exists there), when no run succeeded, and when the exact optimum gave up "
                "(its time budget, 30 s by default, ran out: swarmpath plan prints why; a "
                "service job's summary says it in the row's optimum_reason)",
    "length_mean": "mean executed path length of the successful runs (m)",
    "error_mean": "mean final distance to the goal over all runs (m)",
    "seconds_mean": "mean wall time per run (s): a map run's planning, a benchmark run's share "
                    "of the batch that computed it",
    "cpu_seconds_mean": "mean CPU time per run (s; the planner's, or a benchmark run's share of "
                        "its batch): unlike the wall time, not inflated by other processes "
                        "sharing the machine; blank when no run has one (stored before CPU "
                        "times were measured)",
    "travel_time_mean": "mean simulated time from start to goal of the successful runs (s)",
    "min_clearance": "least body gap (clearance minus robot radius) over every step of every "
                     "run, failed runs included (m; exact and swept against moving obstacles; "
                     "<= 0: the body touched an obstacle)",
    "clearance_mean": "mean body gap (clearance minus robot radius) sampled every 5 cm along "
                      "the path, mean over successful runs (m; Bench-MR, OMPL)",
    "curvature_max": "largest curvature of the circles through three path points 0.3 m apart "
                     "(1/m; Bench-MR), mean over successful runs",
    "curvature_mean": "mean of the same curvature along the path (1/m), mean over successful "
                      "runs",
    "cusps": "vertices of the path turning by more than 60 degrees (Bench-MR), mean over "
             "successful runs",
    "danger_share": "share of the travel time spent within 0.1 m (body gap) of an obstacle "
                    "(MRPB's safety), mean over successful runs",
    "velocity_smoothness": "mean |change of speed| per second (m/s^2; MRPB), mean over "
                           "successful runs",
    "angular_smoothness": "mean |change of the turn rate of the direction of travel| per "
                          "second (rad/s^2), mean over successful runs",
    "costmap_cost_mean": "nav2 maps: mean and largest cost (0-254) of nav2's inflated costmap "
                         "(inflation radius 0.55 m, cost scaling 3.0) along the path, as nav2's "
                         "planner benchmark reports them; means over successful runs",
    "jerk": "mean magnitude of the jerk, the rate of change of acceleration (m/s^3), mean over "
            "successful runs",
    "failure_classes": "why the runs that did not reach the goal failed (docs/planners.md, "
                       "\"Why runs fail\"): collision, gave-up, short-of-goal, or, at a time or "
                       "step limit, progressing (still getting closer), blocked-by-mover, "
                       "boxed-in (hardly moved), oscillating (back and forth within 2 m) or "
                       "wandering (moved far without getting closer)",
    "rank": "rank of avg among the algorithms on this function and dimension (1 = best)",
    "origin_suspect": "true when runs reached exact zeros or values below 1e-100 on a function "
                      "whose optimum is at the origin (usually a move that scales positions "
                      "toward 0, not search; rerun with transform shift); blank for "
                      "transformed jobs",
    "marker": "+ / = / -: significantly better / no significant difference / worse than the "
              "reference algorithm (two-sided Wilcoxon rank-sum test, Holm-adjusted over the "
              "table, alpha 0.05; blank for the reference itself; docs/statistics.md)",
    "p": "two-sided p-value of that test, before the correction",
    "p_holm": "the p-value after Holm's correction over every test of the table",
    "race_runs": "runs the race gave this cell (a raced job: it stops a cell once its "
                 "comparisons are decided; docs/statistics.md, Racing); its marker is the "
                 "race's decision, not a rank-sum test",
    "race_state": "racing (more rounds to come), decided (every comparison of the cell was "
                  "decided) or max_runs (the cell reached the job's runs undecided)",
    "race_round": "the round (0 = the first, min_runs) in which the cell stopped",
    "race_decision": "the race's decision against the reference: different (the marker says "
                     "which is better), equivalent (within the race's margin), futile "
                     "(stopped at a look where the closing look would hardly call it: not a "
                     "verdict) or open",
    "race_theta": "the share of paired runs (run r against the reference's run r) this "
                  "algorithm won, ties half: the race's estimate of P(its run beats the "
                  "reference's)",
    "race_low": "lower end of that probability's anytime-valid interval (the race's confidence "
                "sequence at alpha over the study's comparisons)",
    "race_high": "upper end of that interval",
    "success_marker": "+/=/- against the reference planner's success rate (Fisher's exact test, "
                      "Holm-adjusted over the table, alpha 0.05)",
    "length_marker": "+/=/- against the reference planner's path lengths (Wilcoxon rank-sum "
                     "test over successful runs, Holm-adjusted over the table, alpha 0.05)",
    "seconds_marker": "+/=/- against the reference planner's planning times (Wilcoxon "
                      "rank-sum test, Holm-adjusted over the table, alpha 0.05)",
    "gap_marker": "+/=/- against the reference planner's gaps to the exact optimum (Wilcoxon "
                  "rank-sum test over successful runs, Holm-adjusted over the table, alpha 0.05)",
    "iqr": "interquartile range q3 - q1 of the runs' best fitness (numpy's linear quartiles)",
    "a12": "Vargha-Delaney effect size: the probability that a run of this algorithm beats a "
           "run of the reference, ties half (0.5: no effect; |A12 - 0.5| >= 0.06 small, 0.14 "
           "medium, 0.21 large)",
    "shift": "Hodges-Lehmann shift: median of the differences (this run - reference run) over "
             "all pairs of runs, in the function's units (negative: lower than the reference)",
    "shift_low": "lower end of the shift's 95 % interval (the rank-sum test inverted)",
    "shift_high": "upper end of the shift's 95 % interval",
    "p_better": "posterior probability that the mean is lower than the reference's by more than "
                "the rope (Bayesian bootstrap; rope 1 % of the larger distance to the optimum)",
    "p_equivalent": "posterior probability that the means differ by less than the rope",
    "p_worse": "posterior probability that the mean is higher than the reference's by more "
               "than the rope",
    "verdict": "better / equivalent / worse when that probability reaches 0.95, else undecided",
    "best": "true for the lowest average of the function and dimension (ties all)",
    "similar": "true when not the best but not significantly worse than it (rank-sum test "
               "against the best, Holm-adjusted over the table): bold in the papers' tables",
}
for _measure in ("length", "gap", "seconds"):
    NOTES[f"{_measure}_a12"] = f"A12 of the {_measure} (see a12)"
    NOTES[f"{_measure}_shift"] = f"Hodges-Lehmann shift of the {_measure} (see shift)"
    for _p in ("p_better", "p_equivalent", "p_worse"):
        NOTES[f"{_measure}_{_p}"] = f"{_p} of the {_measure} (relative rope 1 % of the larger)"
ALIASES = {"gap": "gap_mean", "gap (%)": "gap_mean", "collision": "collisions",
           "cpu time (s)": "cpu_seconds_mean"}


def legend(columns: Iterable[str]) -> list[tuple[str, str]]:
    """(column, meaning) for the columns that have a note, in the columns' order."""
    out: list[tuple[str, str]] = []
    for c in columns:
        key = ALIASES.get(c.lower(), c.lower())
        if key in NOTES and all(k != c for k, _ in out):
            out.append((c, NOTES[key]))
    return out


def legend_text(columns: Iterable[str]) -> str:
    """The legend as lines ``column: meaning`` (empty when no column has a note)."""
    return "\n".join(f"{c}: {text}" for c, text in legend(columns))
