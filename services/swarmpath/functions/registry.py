"""Registry of benchmark functions: the single source of their names, bounds and optima."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmpath.functions import definitions as d

Array = NDArray[np.float64]

# Minimiser of F8 (Schwefel 2.26) per coordinate and its value per dimension.
SCHWEFEL_ARGMIN = 420.968746
SCHWEFEL_MIN_PER_DIM = -418.98288727243374
# Fraction of the box (around its centre) inside which random shifts put the optimum.
SHIFT_FRACTION = 0.8


@dataclass(frozen=True)
class BenchmarkFunction:
    """A test function on a box, optionally shifted: value(x) = kernel(x - shift).

    ``lower``/``upper`` are scalars applied to every coordinate (a shift does not move the box).
    ``f_min`` is the known minimum inside the box for any dimension (F8's depends on it: see
    :meth:`f_min_for`); ``optimum`` is the minimiser's coordinate value before shifting.
    """

    name: str
    kernel: Callable[[Array], Array]
    lower: float
    upper: float
    optimum_coordinate: float
    f_min_per_dim: float = 0.0
    f_min_constant: float = 0.0
    noisy: bool = False
    description: str = ""
    shift: Array | None = field(default=None, compare=False)
    # Wrap the shifted argument into the box: needed where the kernel is unbounded below outside it.
    wrap_shifted: bool = False

    @property
    def f_min(self) -> float:
        """Known minimum for dimension 1 per-dimension functions: use :meth:`f_min_for` for F8."""
        return self.f_min_constant + self.f_min_per_dim

    def f_min_for(self, dim: int) -> float:
        return self.f_min_constant + self.f_min_per_dim * dim

    def optimum(self, dim: int) -> Array:
        """The minimiser in ``dim`` dimensions (moved by the shift, if any)."""
        base = np.full(dim, self.optimum_coordinate)
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
        if self.name.startswith("F5") or self.name.startswith("F12") or self.name.startswith("F13"):
            if x.shape[-1] < 2:
                raise ValueError(f"{self.name} needs at least 2 dimensions")
        if self.shift is not None:
            x = x - self._shift_for(x.shape[-1])
            if self.wrap_shifted:
                span = self.upper - self.lower
                x = np.mod(x - self.lower, span) + self.lower
        value = self.kernel(x)
        if self.noisy and rng is not None:
            value = value + rng.random(value.shape)
        return np.asarray(value, dtype=float)

    def check_study(self, dim: int, transform: str) -> None:
        """ValueError naming what this function cannot run (a suite function: a dimension its
        suite does not define, a transform on top of its instance)."""

    def report(self, values: ArrayLike) -> Array:
        """The values as reported in results (a CEC function floors errors below 1e-8 to 0)."""
        return np.asarray(values, dtype=float)

    def shifted(self, shift: ArrayLike) -> BenchmarkFunction:
        """This function with its optimum moved by ``shift`` (bounds unchanged)."""
        o = np.asarray(shift, dtype=float)
        if o.ndim != 1:
            raise ValueError("shift must be a 1-D vector")
        moved = self.optimum_coordinate + o
        if np.any(moved < self.lower) or np.any(moved > self.upper):
            raise ValueError(f"shift moves the optimum of {self.name} outside its box")
        return replace(self, shift=o)

    def random_shift(self, dim: int, rng: np.random.Generator) -> Array:
        """A shift putting the optimum uniformly inside the central 80% of the box."""
        centre = 0.5 * (self.lower + self.upper)
        half = 0.5 * SHIFT_FRACTION * (self.upper - self.lower)
        target = rng.uniform(centre - half, centre + half, size=dim)
        return np.asarray(target - self.optimum_coordinate, dtype=float)


def _fn(name: str, kernel: Callable[[Array], Array], bound: float, desc: str, **kw: object) -> (
    BenchmarkFunction
):
    return BenchmarkFunction(name=name, kernel=kernel, lower=-bound, upper=bound, description=desc,
                             **kw)  # type: ignore[arg-type]


_FUNCTIONS: dict[str, BenchmarkFunction] = {
    f.name: f
    for f in [
        _fn("F1", d.sphere, 100.0, "sphere", optimum_coordinate=0.0),
        _fn("F2", d.schwefel_2_22, 10.0, "Schwefel 2.22", optimum_coordinate=0.0),
        _fn("F3", d.schwefel_1_2, 100.0, "Schwefel 1.2", optimum_coordinate=0.0),
        _fn("F4", d.schwefel_2_21, 100.0, "Schwefel 2.21", optimum_coordinate=0.0),
        _fn("F5", d.rosenbrock, 30.0, "Rosenbrock", optimum_coordinate=1.0),
        _fn("F6", d.step, 100.0, "step, sum((x+0.5)^2) as in the GWO code",
            optimum_coordinate=-0.5),
        _fn("F6-floor", d.step_floor, 100.0, "step, sum(floor(x+0.5)^2) as in Yao et al.",
            optimum_coordinate=0.0),
        _fn("F7", d.quartic, 1.28, "quartic with U[0,1) noise", optimum_coordinate=0.0,
            noisy=True),
        _fn("F8", d.schwefel_2_26, 500.0, "Schwefel 2.26", optimum_coordinate=SCHWEFEL_ARGMIN,
            f_min_per_dim=SCHWEFEL_MIN_PER_DIM, wrap_shifted=True),
        _fn("F9", d.rastrigin, 5.12, "Rastrigin", optimum_coordinate=0.0),
        _fn("F10", d.ackley, 32.0, "Ackley", optimum_coordinate=0.0),
        _fn("F11", d.griewank, 600.0, "Griewank", optimum_coordinate=0.0),
        _fn("F12", d.penalized_1, 50.0, "generalized penalized 1", optimum_coordinate=-1.0),
        _fn("F13", d.penalized_2, 50.0, "generalized penalized 2", optimum_coordinate=1.0),
    ]
}


@dataclass(frozen=True)
class Suite:
    """A named family of registered functions (``bbob``, ``cec2017``, a plugin's suite).

    ``functions``: its members in table order, named ``<suite>:<name>``. ``members``: the names
    the suite's name and its ranges expand to (a member left out, such as CEC 2017's F2 that the
    organisers excluded, is still registered and can be named on its own).
    """

    name: str
    functions: tuple[BenchmarkFunction, ...]
    members: tuple[str, ...]
    description: str = ""


_SUITES: dict[str, Suite] = {}
_SUITE_FUNCTIONS: dict[str, BenchmarkFunction] = {}
_suites_loaded = False


def register_suite(suite: Suite) -> Suite:
    """Register a suite and its functions (ValueError if a name is taken)."""
    if suite.name in _SUITES or suite.name in _FUNCTIONS:
        raise ValueError(f"suite {suite.name!r} is already registered")
    names = [f.name for f in suite.functions]
    for name in names:
        if not name.startswith(f"{suite.name}:"):
            raise ValueError(f"{name!r}: a function of suite {suite.name!r} is named "
                             f"'{suite.name}:<name>'")
        if name in _FUNCTIONS or name in _SUITE_FUNCTIONS:
            raise ValueError(f"function {name!r} is already registered")
    unknown = set(suite.members) - set(names)
    if unknown:
        raise ValueError(f"suite {suite.name!r} lists members it does not have: {sorted(unknown)}")
    _SUITES[suite.name] = suite
    _SUITE_FUNCTIONS.update({f.name: f for f in suite.functions})
    return suite


def _load_suites() -> None:
    """Import the built-in suites (they register themselves) on first use."""
    global _suites_loaded
    if not _suites_loaded:
        _suites_loaded = True
        import swarmpath.functions.suites  # noqa: F401 - registers bbob, cec2017, cec2022


def list_suites() -> list[str]:
    """Registered suite names."""
    _load_suites()
    return list(_SUITES)


def get_suite(name: str) -> Suite:
    _load_suites()
    try:
        return _SUITES[name]
    except KeyError:
        from swarmpath.names import unknown

        raise KeyError(unknown("suite", name, _SUITES)) from None


def list_functions(suite: str | None = None) -> list[str]:
    """Registered names in table order: without ``suite`` the stand-alone functions (F1..F13,
    with F6-floor after F6), else that suite's functions (all of them, its excluded members
    too)."""
    if suite is None:
        return list(_FUNCTIONS)
    return [f.name for f in get_suite(suite).functions]


def list_names() -> list[str]:
    """Every name a study may list without a range or an instance: the stand-alone functions,
    each suite's functions, then the suite names."""
    _load_suites()
    return [*_FUNCTIONS, *_SUITE_FUNCTIONS, *_SUITES]


def get_function(name: str) -> BenchmarkFunction:
    """The function registered as ``name``; a suite function's instance k is
    ``<suite>:<name>@i<k>`` (instance 1 without the suffix)."""
    if name in _FUNCTIONS:
        return _FUNCTIONS[name]
    _load_suites()
    if name in _SUITE_FUNCTIONS:
        return _SUITE_FUNCTIONS[name]
    base, sep, instance = name.rpartition("@i")
    if sep and base in _SUITE_FUNCTIONS and instance.isdigit():
        with_instance = getattr(_SUITE_FUNCTIONS[base], "with_instance", None)
        if with_instance is not None:
            try:
                return with_instance(int(instance))
            except ValueError as exc:
                raise KeyError(f"function {name!r}: {exc}") from None
    from swarmpath.names import unknown

    raise KeyError(unknown("function", name, {**_FUNCTIONS, **_SUITE_FUNCTIONS, **_SUITES}))


def _suite_range(part: str) -> list[str] | None:
    """'bbob:f1-f5', 'cec2017:F3-F10' -> the suite's members numbered in the range (inclusive);
    None if ``part`` is not such a range."""
    suite_name, colon, span = part.partition(":")
    lo, dash, hi = span.partition("-")
    if not (colon and dash) or suite_name not in _SUITES:
        return None
    suite = _SUITES[suite_name]
    prefix = f"{suite_name}:"
    first = get_function(prefix + lo) if prefix + lo in _SUITE_FUNCTIONS else None
    last = get_function(prefix + hi) if prefix + hi in _SUITE_FUNCTIONS else None
    if first is None or last is None:
        return None
    names = [f.name for f in suite.functions]
    a, b = names.index(first.name), names.index(last.name)
    if a > b:
        raise KeyError(f"function range {part!r} runs backwards")
    return [n for n in names[a:b + 1] if n in suite.members]


def expand_function_names(spec: str) -> list[str]:
    """Parse 'F1-F13', 'F1,F5,F9', a suite name ('bbob': its members), a suite range
    ('bbob:f1-f5', 'cec2017:F1-F10': the suite's members in it) or mixtures into registered
    names."""
    names: list[str] = []
    for part in (p.strip() for p in spec.split(",")):
        if not part:
            continue
        if part in _FUNCTIONS:
            names.append(part)
            continue
        lo, sep, hi = part.partition("-")
        if sep and lo.upper().startswith("F") and hi.upper().startswith("F"):
            try:
                a, b = int(lo[1:]), int(hi[1:])
            except ValueError:
                a, b = 0, -1
            if 1 <= a <= b <= 13:
                names.extend(f"F{i}" for i in range(a, b + 1))
                continue
        _load_suites()
        if part in _SUITES:
            names.extend(_SUITES[part].members)
            continue
        expanded = _suite_range(part)
        if expanded is not None:
            names.extend(expanded)
            continue
        get_function(part)  # raises with the list of valid names
        names.append(part)
    return names
