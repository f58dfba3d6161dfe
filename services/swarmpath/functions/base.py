"""The benchmark function: what a test function (built-in, suite or plugin) is made of.

A :class:`BenchmarkFunction` is a vectorized ``kernel`` (an array of shape (..., d) in, shape
(...) out) on a box, with its known minimum. Plugins build one and register it
(:func:`swarmpath.functions.register_function`); the fields cover the classical cases:

* the box: ``lower``/``upper`` scalars (every coordinate) or one value per coordinate (then the
  function has that one dimension);
* the dimensions it is defined for: ``dimensions`` (None: any d >= ``min_dim``);
* its minimum: ``f_min_constant + f_min_per_dim * d`` (:meth:`f_min_for`), at ``optimum``:
  ``optimum_coordinate`` on every coordinate, one value per coordinate, or None when no
  minimiser is given (a constrained design problem whose best known value is all the literature
  has; shifting it is then refused);
* ``noisy``: the kernel's value plus U[0, 1) noise drawn from the run's stream.

When the fields do not fit (a minimiser that depends on the dimension, as BBOB's), subclass it
and override :meth:`optimum`, :meth:`f_min_for`, :meth:`bounds`, :meth:`check_study` or
:meth:`report` (the suites' :class:`~swarmpath.functions.suites.base.SuiteFunction` does):
everything in swarmpath goes through these methods. Instances are frozen; the value at x
depends on x alone (and on the run's stream for a noisy function), never on the other points
evaluated with it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
Bound = float | tuple[float, ...]

# Fraction of the box (around its centre) inside which random shifts put the optimum.
SHIFT_FRACTION = 0.8


@dataclass(frozen=True)
class BenchmarkFunction:
    """A test function on a box, optionally shifted: value(x) = kernel(x - shift).

    ``lower``/``upper`` apply to every coordinate when scalars (a shift does not move the box).
    ``f_min`` is the known minimum inside the box for any dimension (F8's depends on it: see
    :meth:`f_min_for`); ``optimum_coordinate`` is the minimiser's coordinate value before
    shifting.
    """

    name: str
    kernel: Callable[[Array], Array]
    lower: Bound
    upper: Bound
    optimum_coordinate: Bound | None
    f_min_per_dim: float = 0.0
    f_min_constant: float = 0.0
    noisy: bool = False
    description: str = ""
    shift: Array | None = field(default=None, compare=False)
    # Wrap the shifted argument into the box: needed where the kernel is unbounded below outside it.
    wrap_shifted: bool = False
    #: Smallest dimension the kernel is defined for.
    min_dim: int = 1
    #: The only dimensions it is defined for (None: any >= min_dim).
    dimensions: tuple[int, ...] | None = None
    #: Where it comes from (paper, equation), for catalogues.
    reference: str = ""

    def __post_init__(self) -> None:
        for label in ("lower", "upper", "optimum_coordinate"):
            value = getattr(self, label)
            if isinstance(value, list | np.ndarray):  # keep instances hashable and frozen
                object.__setattr__(self, label, tuple(float(v) for v in np.ravel(value)))
        sizes = {len(v) for v in (self.lower, self.upper, self.optimum_coordinate)
                 if isinstance(v, tuple)}
        if len(sizes) > 1:
            raise ValueError(f"function {self.name!r}: per-coordinate lower, upper and optimum "
                             "must have the same length")
        if sizes and self.dimensions is None:
            object.__setattr__(self, "dimensions", (sizes.pop(),))

    @property
    def origin_module(self) -> str:
        """The module its code lives in (its kernel's): where the registry says it comes from."""
        return str(getattr(self.kernel, "__module__", None) or type(self).__module__)

    @property
    def f_min(self) -> float:
        """Known minimum for dimension 1 per-dimension functions: use :meth:`f_min_for` for F8."""
        return self.f_min_constant + self.f_min_per_dim

    def f_min_for(self, dim: int) -> float:
        return self.f_min_constant + self.f_min_per_dim * dim

    def check_dim(self, dim: int) -> None:
        """ValueError naming the function unless it is defined in ``dim`` dimensions."""
        if self.dimensions is not None and dim not in self.dimensions:
            allowed = ", ".join(str(d) for d in self.dimensions)
            raise ValueError(f"{self.name} is defined for dim in {allowed}, got {dim}")
        if dim < self.min_dim:
            raise ValueError(f"{self.name} needs at least {self.min_dim} dimensions")

    def check_study(self, dim: int, transform: str) -> None:
        """ValueError naming what this function cannot run: a dimension it is not defined for,
        a transform without a known minimiser to move or turn about (a suite function: any
        transform on top of its instance)."""
        self.check_dim(dim)
        if transform != "none" and not self.has_optimum:
            raise ValueError(f"{self.name} has no known minimiser: transform must be 'none', "
                             f"got {transform!r}")

    def report(self, values: ArrayLike) -> Array:
        """The values as reported in results (a CEC function floors errors below 1e-8 to 0)."""
        return np.asarray(values, dtype=float)

    def bounds(self, dim: int) -> tuple[Array, Array]:
        """(lower, upper), each of shape (dim,)."""
        self.check_dim(dim)
        return (np.broadcast_to(np.asarray(self.lower, dtype=float), (dim,)).copy(),
                np.broadcast_to(np.asarray(self.upper, dtype=float), (dim,)).copy())

    @property
    def has_optimum(self) -> bool:
        """Whether the minimiser is known (:meth:`optimum` answers)."""
        return self.optimum_coordinate is not None

    def base_optimum(self, dim: int) -> Array:
        """The minimiser in ``dim`` dimensions before any shift."""
        if self.optimum_coordinate is None:
            raise ValueError(f"function {self.name} has no known minimiser")
        return np.broadcast_to(np.asarray(self.optimum_coordinate, dtype=float), (dim,)).copy()

    def optimum(self, dim: int) -> Array:
        """The minimiser in ``dim`` dimensions (moved by the shift, if any)."""
        base = self.base_optimum(dim)
        if self.shift is None:
            return base
        return base + self._shift_for(dim)

    def _shift_for(self, dim: int) -> Array:
        assert self.shift is not None
        if self.shift.shape[-1] != dim:
            raise ValueError(f"shift has {self.shift.shape[-1]} coordinates, x has {dim}")
        return self.shift

    def evaluate(self, X: ArrayLike, rng: np.random.Generator | None = None) -> Array:
        """Value at X of shape (..., d). F7's U[0,1) noise is drawn from ``rng``; without one the
        noise term is left out (the deterministic part, whose minimum is ``f_min``)."""
        x = np.asarray(X, dtype=float)
        if x.ndim == 0 or x.shape[-1] < 1:
            raise ValueError("X must have shape (..., d) with d >= 1")
        self.check_dim(x.shape[-1])
        if self.shift is not None:
            x = x - self._shift_for(x.shape[-1])
            if self.wrap_shifted:
                lower, upper = self.bounds(x.shape[-1])
                x = np.mod(x - lower, upper - lower) + lower
        value = self.kernel(x)
        if self.noisy and rng is not None:
            value = value + rng.random(value.shape)
        return np.asarray(value, dtype=float)

    def shifted(self, shift: ArrayLike) -> BenchmarkFunction:
        """This function with its optimum moved by ``shift`` (bounds unchanged)."""
        o = np.asarray(shift, dtype=float)
        if o.ndim != 1:
            raise ValueError("shift must be a 1-D vector")
        lower, upper = self.bounds(o.shape[0])
        moved = self.base_optimum(o.shape[0]) + o
        if np.any(moved < lower) or np.any(moved > upper):
            raise ValueError(f"shift moves the optimum of {self.name} outside its box")
        return replace(self, shift=o)

    def random_shift(self, dim: int, rng: np.random.Generator) -> Array:
        """A shift putting the optimum uniformly inside the central 80% of the box."""
        base = self.base_optimum(dim)
        lower: float | Array
        upper: float | Array
        if isinstance(self.lower, float | int) and isinstance(self.upper, float | int):
            lower, upper = float(self.lower), float(self.upper)  # the F1-F13 draws, as before
        else:
            lower, upper = self.bounds(dim)
        centre = 0.5 * (lower + upper)
        half = 0.5 * SHIFT_FRACTION * (upper - lower)
        target = rng.uniform(centre - half, centre + half, size=dim)
        return np.asarray(target - base, dtype=float)
