"""What a published table's print can and cannot be: checks that hold for any set of runs.

A printed cell [min, max, avg, std] of n runs contradicts itself when no n numbers have those
statistics, whatever the printed values were rounded from (:func:`contradiction`). Used to mark
published cells ``not comparable`` (:mod:`swarmpath.evidence.reproduction`) and by the tests of
the transcribed tables.
"""

from __future__ import annotations

import math
from collections.abc import Mapping


def printed_half_unit(value: float) -> float:
    """Half a unit in the last printed digit of a transcribed value (printed as d.dddd x 10^e;
    trailing zeros are taken as not printed: 7.7000e-03 may be 7.7e-03 rounded)."""
    if value == 0.0:
        return 0.0
    mantissa, exponent = f"{abs(value):.4e}".split("e")
    digits = mantissa.replace(".", "").rstrip("0") or "0"
    return 0.5 * 10.0 ** (int(exponent) - (len(digits) - 1))


def contradiction(cell: Mapping[str, float | None], runs: int, f_min: float) -> str | None:
    """How the printed [min, max, avg, std] of ``runs`` runs contradict each other, whatever
    the values were rounded from (None: they do not). Checks that hold for any ``runs`` numbers
    >= ``f_min``: min <= avg <= max; avg >= (max + (runs - 1) min) / runs and the mirror bound;
    the sample std at most sqrt(runs / (runs - 1) (max - avg)(avg - min)) (Bhatia and Davis,
    Amer. Math. Monthly 107, 2000), or sqrt(runs) (avg - min) without a max."""
    lo, hi, avg, std = (cell.get(k) for k in ("min", "max", "avg", "std"))
    if avg is None:
        return None
    h = printed_half_unit
    a_lo, a_hi = avg - h(avg), avg + h(avg)
    low = f_min if lo is None else lo - h(lo)
    high = None if hi is None else hi + h(hi)
    if lo is not None and a_hi < low:
        return f"avg {avg:.4e} below the min {lo:.4e}"
    if high is not None and a_lo > high:
        return f"avg {avg:.4e} above the max {hi:.4e}"
    n = runs
    if hi is not None and a_hi < (hi - h(hi) + (n - 1) * low) / n:
        return f"avg {avg:.4e} below max / {n} (every run is at least the min)"
    if lo is not None and high is not None and a_lo > (lo + h(lo) + (n - 1) * high) / n:
        return f"avg {avg:.4e} above what {n} runs up to the max can average beside the min"
    if std is None:
        return None
    if high is not None:
        bound = math.sqrt(n / (n - 1) * max(high - a_lo, 0.0) * max(a_hi - low, 0.0))
    else:
        bound = math.sqrt(n) * max(a_hi - low, 0.0)
    if std - h(std) > bound:
        return (f"std {std:.4e} above {bound:.4e}, the largest {n} runs with this avg "
                f"{'and range' if high is not None else 'above the min'} can have")
    return None
