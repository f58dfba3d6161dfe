"""The rank-sum tests a race takes (its planned looks and its closing look), and a memo of the
looks' results.

A race is replayed from its first round whenever a round completes (:func:`swarmpath.evidence.
racing.race_block`: a pure function of the runs, so a restarted coordinator decides the same).
With a look at every round, that replay would test every past look's comparisons again: at the
1000 runs of a Table 2 block, 98 rounds of rank-sum tests for one step. The result of a look is a
pure function of the two samples it tests (the first n runs of both cells, which never change
once stored), so :class:`LookMemo` keeps it keyed by a digest of exactly those values: a later
replay finds the past looks' results and tests only the new round's. A hit returns the very
numbers the test gave (the decisions are bit-identical with and without the memo:
tests/test_racing_looks.py), and the memo is bounded (cleared when full: a miss only costs the
test again).
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence

import numpy as np

__all__ = ["LOOK_MEMO_ENTRIES", "LookMemo", "rank_sum_tests"]

#: Looks a memo keeps: about 100 bytes each. A Table 2 job (65 comparisons, 98 looks) has
#: 6,370; beyond the bound the memo starts again empty.
LOOK_MEMO_ENTRIES = 100_000

Test = tuple[float, "str | None"]


def rank_sum_tests(samples: Sequence[tuple[np.ndarray, np.ndarray]]) -> list[Test]:
    """The full study's test of each pair of samples (:func:`swarmpath.evidence.compare.
    rank_sum`, NaN dropped): its two-sided p and the side whose runs tend lower ("a", "b"; None
    on a perfect balance); the large ones in one vectorized call (:func:`swarmpath.evidence.
    compare.rank_sum_many`: the same p as one call each)."""
    if not samples:
        return []
    from swarmpath.evidence.compare import rank_sum_many  # scipy.stats: only when a test happens

    out: list[Test] = []
    for (a, b), res in zip(samples, rank_sum_many(samples), strict=True):
        if res is None:
            out.append((1.0, None))
            continue
        u, p = res
        half = np.count_nonzero(~np.isnan(a)) * np.count_nonzero(~np.isnan(b)) / 2.0
        out.append((p, None if u == half else ("a" if u < half else "b")))
    return out


class LookMemo:
    """Results of :func:`rank_sum_tests` by the samples tested (module text). One per store or
    per raced study; not thread-safe (the store calls it under its lock)."""

    def __init__(self, entries: int = LOOK_MEMO_ENTRIES) -> None:
        self.entries = entries
        self._results: dict[bytes, Test] = {}
        self.hits = self.misses = 0

    def __len__(self) -> int:
        return len(self._results)

    @staticmethod
    def key(a: np.ndarray, b: np.ndarray) -> bytes:
        """A digest of both samples' values and sizes (float64, in run order)."""
        h = hashlib.blake2b(digest_size=16)
        a64, b64 = np.ascontiguousarray(a, dtype=np.float64), np.ascontiguousarray(b, np.float64)
        h.update(np.array([a64.size, b64.size], dtype=np.int64).tobytes())
        h.update(a64.tobytes())
        h.update(b64.tobytes())
        return h.digest()

    def tests(self, samples: Sequence[tuple[np.ndarray, np.ndarray]]) -> list[Test]:
        """:func:`rank_sum_tests` of ``samples``, those already tested read from the memo."""
        keys = [self.key(a, b) for a, b in samples]
        missing = [i for i, k in enumerate(keys) if k not in self._results]
        computed = rank_sum_tests([samples[i] for i in missing])
        self.hits += len(keys) - len(missing)
        self.misses += len(missing)
        out = [self._results.get(k) for k in keys]
        if len(self._results) + len(missing) > self.entries:
            self._results.clear()
        for i, result in zip(missing, computed, strict=True):
            out[i] = result
            self._results[keys[i]] = result
        return out  # type: ignore[return-value]
