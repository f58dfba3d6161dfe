"""Registry of benchmark functions: the single source of their names, bounds and optima.

Two kinds of names, in one space:

* stand-alone functions: the built-in F1-F13 (and F6-floor), and plugins' functions
  (:func:`register_function`), listed by :func:`list_functions`;
* suites (:func:`register_suite`): a named family whose functions are named ``<suite>:<name>``
  (``bbob:f3``, ``cec2017:F5``; instance k of a function with instances: ``bbob:f3@i7``). The
  built-in suites (:mod:`swarmpath.functions.suites`) register themselves the way a plugin's do,
  on the first lookup that needs them.

Every name has an origin (built-in, distribution, file) with a digest of its code; a name taken
by other code is refused naming both (:class:`~swarmpath.registry.ExtensionClash`). The names
users type (ranges, suites) are read by :mod:`swarmpath.functions.expand`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions import definitions as d
from swarmpath.functions.base import SHIFT_FRACTION, BenchmarkFunction
from swarmpath.registry import ExtensionClash, Registry, caller_module, origin_for

if TYPE_CHECKING:
    from swarmpath.plugins.origin import Origin

Array = NDArray[np.float64]

# Minimiser of F8 (Schwefel 2.26) per coordinate and its value per dimension.
SCHWEFEL_ARGMIN = 420.968746
SCHWEFEL_MIN_PER_DIM = -418.98288727243374

__all__ = ["BUILTIN", "SHIFT_FRACTION", "BenchmarkFunction", "Suite", "get_function",
           "get_suite", "list_functions", "list_suites", "register_function", "register_suite"]


def _fn(name: str, kernel: Callable[[Array], Array], bound: float, desc: str, **kw: object) -> (
    BenchmarkFunction
):
    return BenchmarkFunction(name=name, kernel=kernel, lower=-bound, upper=bound, description=desc,
                             **kw)  # type: ignore[arg-type]


BUILTIN: tuple[BenchmarkFunction, ...] = (
    _fn("F1", d.sphere, 100.0, "sphere", optimum_coordinate=0.0),
    _fn("F2", d.schwefel_2_22, 10.0, "Schwefel 2.22", optimum_coordinate=0.0),
    _fn("F3", d.schwefel_1_2, 100.0, "Schwefel 1.2", optimum_coordinate=0.0),
    _fn("F4", d.schwefel_2_21, 100.0, "Schwefel 2.21", optimum_coordinate=0.0),
    _fn("F5", d.rosenbrock, 30.0, "Rosenbrock", optimum_coordinate=1.0, min_dim=2),
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
    _fn("F12", d.penalized_1, 50.0, "generalized penalized 1", optimum_coordinate=-1.0,
        min_dim=2),
    _fn("F13", d.penalized_2, 50.0, "generalized penalized 2", optimum_coordinate=1.0,
        min_dim=2),
)

REGISTRY: Registry[BenchmarkFunction] = Registry(
    "function", "swarmpath.functions", (), KeyError, group="swarmpath.functions"
)
for _f in BUILTIN:
    REGISTRY.register(_f)


@dataclass(frozen=True)
class Suite:
    """A named family of registered functions (``bbob``, ``cec2017``, a plugin's suite).

    ``functions``: its members in table order, named ``<suite>:<name>``. ``members``: the names
    the suite's name and its ranges expand to (empty: all of ``functions``; a member left out,
    such as CEC 2017's F2 that the organisers excluded, is still registered and can be named on
    its own).
    """

    name: str
    functions: tuple[BenchmarkFunction, ...]
    members: tuple[str, ...] = ()
    description: str = ""
    reference: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "functions", tuple(self.functions))
        if not self.functions:
            raise ValueError(f"suite {self.name!r} has no function")
        bad = [f for f in self.functions if not isinstance(f, BenchmarkFunction)]
        if bad:
            raise TypeError(f"suite {self.name!r}: {bad[0]!r} is not a BenchmarkFunction")
        if not self.members:
            object.__setattr__(self, "members", tuple(f.name for f in self.functions))
        object.__setattr__(self, "members", tuple(self.members))


#: Built-in suites load on first use (the ``suites`` package registers bbob, cec2017, cec2022).
SUITES: Registry[Suite] = Registry("suite", "swarmpath.functions", ("suites",), KeyError,
                                   group="swarmpath.functions")
_SUITE_FUNCTIONS: dict[str, tuple[BenchmarkFunction, str]] = {}  # name -> (function, suite)


def register_function(
    function: BenchmarkFunction, origin: Origin | None = None
) -> BenchmarkFunction:
    """Add a stand-alone function under its name (a name already taken by other code is
    refused, naming both origins); returns it. ``origin``: where it comes from (default: the
    calling code's module)."""
    if not isinstance(function, BenchmarkFunction):
        raise TypeError(f"register_function takes a BenchmarkFunction, got {function!r}")
    if ":" in function.name:
        raise ValueError(f"{function.name!r}: names with ':' belong to suites (register_suite)")
    return REGISTRY.register(function, origin or origin_for(caller_module()))


def register_suite(suite: Suite, origin: Origin | None = None) -> Suite:
    """Register a suite and its functions; returns it. Its functions must be named
    ``<suite>:<name>``; a name taken by other code is refused naming both origins.
    ``origin``: as for :func:`register_function`."""
    if not isinstance(suite, Suite):
        raise TypeError(f"register_suite takes a Suite, got {suite!r}")
    origin = origin or origin_for(caller_module())
    names = [f.name for f in suite.functions]
    for name in names:
        if not name.startswith(f"{suite.name}:"):
            raise ValueError(f"{name!r}: a function of suite {suite.name!r} is named "
                             f"'{suite.name}:<name>'")
    unknown = set(suite.members) - set(names)
    if unknown:
        raise ValueError(f"suite {suite.name!r} lists members it does not have: {sorted(unknown)}")
    if REGISTRY.registered(suite.name):
        raise ExtensionClash(f"suite {suite.name!r} from {origin.describe()} has the name of "
                             f"the function from {REGISTRY.origin(suite.name).describe()}")
    SUITES.register(suite, origin)  # a suite of that name from other code: ExtensionClash
    for fn in suite.functions:
        _SUITE_FUNCTIONS[fn.name] = (fn, suite.name)
    return suite


def unregister_suite(name: str) -> None:
    """Remove a suite and its functions (tests, notebooks re-running a cell)."""
    suite = SUITES.get(name)
    SUITES.unregister(name)
    for fn in suite.functions:
        _SUITE_FUNCTIONS.pop(fn.name, None)


def list_suites(builtin: bool | None = None) -> list[str]:
    """Registered suite names, built-ins first (``builtin``: only one of the two)."""
    return SUITES.names(builtin)


def get_suite(name: str) -> Suite:
    return SUITES.get(name)


def list_functions(suite: str | None = None, builtin: bool | None = None) -> list[str]:
    """Registered names in table order: without ``suite`` the stand-alone functions (the
    built-ins F1..F13, with F6-floor after F6, then plugins' in registration order;
    ``builtin``: only one of the two), else that suite's functions (all of them, its excluded
    members too)."""
    if suite is None:
        return REGISTRY.names(builtin)
    return [f.name for f in get_suite(suite).functions]


def list_names() -> list[str]:
    """Every name a study may list without a range or an instance: the stand-alone functions,
    each suite's functions, then the suite names."""
    suites = SUITES.names()
    return [*REGISTRY.names(), *_SUITE_FUNCTIONS, *suites]


def get_function(name: str) -> BenchmarkFunction:
    """The function registered as ``name``; a suite function's instance k is
    ``<suite>:<name>@i<k>`` (instance 1 without the suffix)."""
    if name in REGISTRY:
        return REGISTRY.get(name)
    SUITES.names()  # the suites (built-in and plugins') are loaded
    if name in _SUITE_FUNCTIONS:
        return _SUITE_FUNCTIONS[name][0]
    from swarmpath.functions.suites.base import CENTRE_SUFFIX

    if name.endswith(CENTRE_SUFFIX):  # an instance translated to the origin
        centred = getattr(get_function(name.removesuffix(CENTRE_SUFFIX)), "centred_copy", None)
        if centred is not None:
            return centred()
    base, sep, instance = name.rpartition("@i")
    if sep and base in _SUITE_FUNCTIONS and instance.isdigit():
        with_instance = getattr(_SUITE_FUNCTIONS[base][0], "with_instance", None)
        if with_instance is not None:
            try:
                return with_instance(int(instance))
            except ValueError as exc:
                raise KeyError(f"function {name!r}: {exc}") from None
    from swarmpath.names import unknown

    raise KeyError(unknown("function", name, [*REGISTRY.names(), *_SUITE_FUNCTIONS,
                                              *SUITES.names()]))


def suite_of(name: str) -> str | None:
    """The suite a function name belongs to (None for a stand-alone function)."""
    from swarmpath.functions.suites.base import CENTRE_SUFFIX

    name = name.removesuffix(CENTRE_SUFFIX)
    base = name.rpartition("@i")[0] if "@i" in name else name
    SUITES.names()
    entry = _SUITE_FUNCTIONS.get(name) or _SUITE_FUNCTIONS.get(base)
    return None if entry is None else entry[1]


def function_origin(name: str) -> Origin:
    """Where a function name comes from: its own origin, or its suite's."""
    suite = suite_of(name)
    if suite is not None:
        return SUITES.origin(suite)
    return REGISTRY.origin(name)
