"""The names of why a map run failed (:mod:`swarmpath.planners.failures` decides them) and
their counts, importable without the planners (the coordinator's summaries and dashboard read
them from stored runs, where a name a worker sent is data, not trusted)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

FAILURE_CLASSES = ("collision", "gave-up", "error", "short-of-goal", "progressing",
                   "blocked-by-mover", "boxed-in", "oscillating", "wandering")


def known_class(value: Any) -> str | None:
    """``value`` when it names a failure class, else None."""
    return value if isinstance(value, str) and value in FAILURE_CLASSES else None


def count_classes(classes: Iterable[Any]) -> dict[str, int]:
    """How many failed runs fall in each class, in :data:`FAILURE_CLASSES` order; a run without
    a known class (recorded before the classes, or a name no classifier gives) counts as
    ``unclassified``."""
    counts: dict[str, int] = {}
    for c in classes:
        key = known_class(c) or "unclassified"
        counts[key] = counts.get(key, 0) + 1
    order = {name: i for i, name in enumerate((*FAILURE_CLASSES, "unclassified"))}
    return dict(sorted(counts.items(), key=lambda kv: order[kv[0]]))
