"""Instances in a study's statistics: kept apart (the default) or pooled per function.

A study with ``instances`` has one cell per (algorithm, function instance, dim): each instance
of a suite function is its own row, tested and ranked on its own, as in CEC-style tables.
Pooling (``--pool-instances``) follows COCO's practice instead: the instances of a function are
repetitions of one problem (Hansen et al., "COCO: performance assessment", 2022, section 2), so
the runs of all its instances form one cell of runs x instances values, named by the function
without the instance (``bbob:f3``), and the Wilcoxon markers, ranks and Friedman test are
computed on those pooled cells. Pooled run ids are ``instance_position * runs + run``.
"""

from __future__ import annotations

from collections.abc import Sequence

from swarmpath.evidence.report import Cell, assign_ranks, count_backends, cpu_total
from swarmpath.functions.suites.base import split_instance


def pool_instances(cells: Sequence[Cell]) -> list[Cell]:
    """The cells with every instance of a function merged into one cell per (algorithm,
    function, dim), in the order the functions first appear; cells without an instance are
    returned as they are. Ranks are assigned afresh."""
    groups: dict[tuple[str, str, int], list[Cell]] = {}
    for c in cells:
        base, _ = split_instance(c.function)
        groups.setdefault((c.algorithm, base, c.dim), []).append(c)
    out = []
    for (algorithm, base, dim), members in groups.items():
        if len(members) == 1 and members[0].function == base:
            out.append(members[0])
            continue
        runs = max(len(m.run_ids) for m in members)
        out.append(Cell(
            algorithm=algorithm, function=base, dim=dim,
            run_ids=[k * runs + r for k, m in enumerate(members) for r in m.run_ids],
            best_fitness=[v for m in members for v in m.best_fitness],
            evaluations=[e for m in members for e in m.evaluations],
            seconds=sum(m.seconds for m in members),
            params=dict(members[-1].params),
            curves=[c for m in members for c in m.curves],
            cpu_seconds=cpu_total(m.cpu_seconds for m in members),
            backends=count_backends(b for m in members for b in m.backends.items()),
        ))
    assign_ranks(out)
    return out
