"""The global random states (``numpy.random``'s legacy one and the ``random`` module's): the
conformance gate sets them, and checks that the code under test neither reads nor moves them.
swarmpath itself never touches them; this is the one place that does, on purpose."""

from __future__ import annotations

import random
from typing import Any

import numpy as np


def seed_globals(seed: int) -> tuple[Any, Any]:
    """Seed both global states; returns them as they now are."""
    np.random.seed(seed)  # noqa: NPY002 - the global state is what is being checked
    random.seed(seed)
    return states()


def states() -> tuple[Any, Any]:
    return np.random.get_state(), random.getstate()  # noqa: NPY002


def moved(before: tuple[Any, Any]) -> str | None:
    """Which global state differs from ``before`` (None: neither)."""
    now_np, now_py = states()
    if now_py != before[1]:
        return "random"
    if not all(np.array_equal(a, b) for a, b in zip(before[0], now_np, strict=True)):
        return "numpy.random"
    return None
