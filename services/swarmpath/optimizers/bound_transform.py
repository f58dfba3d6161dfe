"""pycma's box transformation (``BoundTransform``): any point onto the box, identity inside.

Defined in pycma's ``transformations.BoxConstraintsLinQuadTransformation`` docstring (N. Hansen,
pycma 4.x): per coordinate with bounds [lb, ub], margins al = min((ub - lb)/2, 0.05 max(|lb|, 1))
and au = min((ub - lb)/2, 0.05 max(|ub|, 1)); the map is periodic with period 2 (ub - lb + al +
au), mirrored about lb - al and ub + au, the identity on [lb + al, ub - au] and quadratic next to
the bounds: lb + (y - (lb - al))^2 / (4 al) on [lb - al, lb + al] and ub - (y - (ub + au))^2 /
(4 au) on [ub - au, ub + au] (value and slope continuous). A CMA-ES sampling its genotype freely
and evaluating this image never evaluates outside the box and keeps an optimum on a bound
reachable.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def margins(lower: Array, upper: Array) -> tuple[Array, Array]:
    half = (upper - lower) / 2
    return (np.minimum(half, 0.05 * np.maximum(np.abs(lower), 1.0)),
            np.minimum(half, 0.05 * np.maximum(np.abs(upper), 1.0)))


def box_transform(x: Array, lower: Array, upper: Array) -> Array:
    """The image of ``x`` in the box [lower, upper] (shapes broadcast)."""
    al, au = margins(lower, upper)
    start = lower - al
    length = upper - lower + al + au
    s = np.mod(x - start, 2 * length)
    s = np.where(s > length, 2 * length - s, s)  # mirrored into [start, start + length]
    y = start + s
    low = y < lower + al
    high = y > upper - au
    y = np.where(low, lower + (y - start) ** 2 / (4 * al), y)
    y = np.where(high, upper - (y - (upper + au)) ** 2 / (4 * au), y)
    return np.clip(y, lower, upper)  # rounding only: the map itself stays inside
