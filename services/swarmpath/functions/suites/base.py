"""Functions of the standard suites (BBOB, CEC 2017, CEC 2022) as registered functions.

A suite function is one test function of a suite bound to one instance: its optimum, its offset
and its rotations come from the instance (BBOB: COCO's generator; CEC: the organisers' data
files), for any dimension the suite defines. It is a :class:`BenchmarkFunction` whose
``kernel`` returns the **error** f(x) - f_opt, so that every table, curve and statistic of a
study reports errors as the field does (COCO's "precision", the CEC competitions' error values);
:meth:`SuiteFunction.value` gives f(x) itself (what the golden values compare).

Names: ``<suite>:<function>`` is instance 1 (``bbob:f3``, ``cec2017:F5``), and
``<suite>:<function>@i<k>`` instance k (``bbob:f3@i7``). A study's ``instances`` expand a suite
function into its instances; the instance is part of the function's name from there on, so the
job spec, the cells, the results, the store and the MCAP files carry it unchanged.

``<name>@centre`` (``bbob:f3@i7@centre``) is the same instance translated so that its optimum
is the origin, the centre of the suite's symmetric box: x -> f(x + x_opt). Its landscape,
rotations and f_opt are the instance's; only where the optimum sits changes. It is the control
``swarmpath audit`` compares an instance with (Kudela's centre bias on BBOB and CEC: how much
an optimizer gains when the optimum is put back at the centre). Every BBOB and CEC function is
defined on all of R^d, so the translated one is too (BBOB's boundary penalty f_pen stays where
the instance has it, in the untranslated coordinates).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmpath.functions.registry import BenchmarkFunction

Array = NDArray[np.float64]

#: (X (..., d), dim, instance) -> f (...,): the suite's values, f_opt included.
Values = Callable[[Array, int], Array]
#: (dim, instance) -> (x_opt (d,), f_opt)
Optimum = Callable[[int, int], tuple[Array, float]]

INSTANCE_SEPARATOR = "@i"
#: the suffix naming an instance translated so that its optimum is the origin
CENTRE_SUFFIX = "@centre"
#: the largest instance id a study may name (COCO's seeds are f + 10000 i: far from overflow)
MAX_INSTANCE = 1_000_000
_INSTANCE = re.compile(r"^(?P<base>.+)@i(?P<instance>[0-9]+)$")


def split_instance(name: str) -> tuple[str, int | None]:
    """('bbob:f3', 7) for 'bbob:f3@i7'; (name, None) for a name without an instance (a
    centred name too: pooling instances never mixes it with the instance it was made from)."""
    m = _INSTANCE.match(name)
    if m is None:
        return name, None
    return m["base"], int(m["instance"])


def instance_name(base: str, instance: int) -> str:
    """The registered name of instance ``instance`` of suite function ``base``."""
    return f"{base}{INSTANCE_SEPARATOR}{int(instance)}"


@dataclass(frozen=True)
class SuiteError:
    """The kernel of a suite function: f(x) - f_opt for the instance, per dimension."""

    values: Callable[[Array, int, int], Array]
    optimum: Callable[[int, int], tuple[Array, float]]
    instance: int
    check: Callable[[int], None] = field(compare=False)  # a bound method: not the identity
    centred: bool = False  # evaluated at x + x_opt: the optimum at the origin

    def __call__(self, x: Array) -> Array:
        d = int(x.shape[-1])
        self.check(d)
        x_opt, f_opt = self.optimum(d, self.instance)
        if self.centred:
            x = x + x_opt
        return np.asarray(self.values(x, d, self.instance) - f_opt)


@dataclass(frozen=True)
class SuiteFunction(BenchmarkFunction):
    """One function of a suite, bound to one instance (see the module docstring).

    ``dimensions``: the dimensions the suite defines (None: any d >= ``min_dim``);
    ``instances``: the instance ids it defines (None: any k >= 1). ``number`` is the function's
    number within its suite. ``error_floor``: errors below it are reported as 0 (CEC's 1e-8 rule;
    0.0: none), applied to reported values only, never to what an optimizer compares.
    """

    suite: str = ""
    number: int = 0
    instance: int = 1
    dimensions: tuple[int, ...] | None = None
    min_dim: int = 2
    instances: tuple[int, ...] | None = None
    error_floor: float = 0.0
    centred: bool = False  # the instance translated so that its optimum is the origin
    values_of: Callable[[Array, int, int], Array] | None = field(default=None, compare=False)
    optimum_of: Callable[[int, int], tuple[Array, float]] | None = field(
        default=None, compare=False)

    @property
    def base_name(self) -> str:
        return split_instance(self.name.removesuffix(CENTRE_SUFFIX))[0]

    @property
    def objective_name(self) -> str:
        """The name its compiled objective is registered under (the backends'
        ``objectives``): the base name, the instance being the objective's data; a centred
        copy (which adds x_opt first) keeps its own name, which has none."""
        return self.name if self.centred else self.base_name

    def check_dim(self, dim: int) -> None:
        if self.dimensions is not None and dim not in self.dimensions:
            raise ValueError(f"{self.base_name} is defined for dim in "
                             f"{', '.join(map(str, self.dimensions))}, got {dim}")
        if dim < self.min_dim:
            raise ValueError(f"{self.base_name} needs dim >= {self.min_dim}, got {dim}")

    def check_instance(self, instance: int) -> None:
        if isinstance(instance, bool) or not isinstance(instance, int | np.integer) or (
                instance < 1):
            raise ValueError(f"instance of {self.base_name} must be an integer >= 1, "
                             f"got {instance!r}")
        if self.instances is not None and instance not in self.instances:
            raise ValueError(f"{self.suite} has instances {', '.join(map(str, self.instances))}"
                             f" (the official data), got {instance}")

    def with_instance(self, instance: int) -> SuiteFunction:
        """This function on instance ``instance`` (ValueError if the suite has no such one)."""
        self.check_instance(instance)
        assert self.values_of is not None and self.optimum_of is not None
        name = self.base_name if instance == 1 else instance_name(self.base_name, instance)
        kernel = SuiteError(self.values_of, self.optimum_of, int(instance), self.check_dim)
        return replace(self, name=name, instance=int(instance), kernel=kernel, centred=False)

    def centred_copy(self) -> SuiteFunction:
        """This instance translated so that its optimum is the origin, named
        ``<name>@centre`` (see the module docstring)."""
        if self.centred:
            return self
        assert self.values_of is not None and self.optimum_of is not None
        kernel = SuiteError(self.values_of, self.optimum_of, self.instance, self.check_dim,
                            centred=True)
        return replace(self, name=self.name + CENTRE_SUFFIX, kernel=kernel, centred=True)

    def value(self, X: ArrayLike) -> Array:
        """f(X) itself (f_opt included) for X of shape (..., d): the reference's number."""
        x = np.asarray(X, dtype=float)
        d = int(x.shape[-1])
        self.check_dim(d)
        assert self.values_of is not None and self.optimum_of is not None
        if self.centred:
            x = x + self.optimum_of(d, self.instance)[0]
        return np.asarray(self.values_of(x, d, self.instance), dtype=float)

    def f_opt(self, dim: int) -> float:
        self.check_dim(dim)
        assert self.optimum_of is not None
        return float(self.optimum_of(dim, self.instance)[1])

    def x_opt(self, dim: int) -> Array:
        self.check_dim(dim)
        assert self.optimum_of is not None
        x_opt = np.array(self.optimum_of(dim, self.instance)[0], dtype=float)
        return np.zeros_like(x_opt) if self.centred else x_opt

    # BenchmarkFunction's view: the kernel is the error, so the minimum is 0 at x_opt.
    def f_min_for(self, dim: int) -> float:
        return 0.0

    def optimum(self, dim: int) -> Array:
        return self.x_opt(dim)

    def check_study(self, dim: int, transform: str) -> None:
        self.check_dim(dim)
        if transform != "none":
            raise ValueError(f"{self.base_name} is shifted and rotated by its instance; "
                             f"transform must be 'none', got {transform!r}")

    def report(self, errors: ArrayLike) -> Array:
        """Errors as reported: below ``error_floor`` they count as 0 (CEC's rule)."""
        e = np.array(errors, dtype=float)
        if self.error_floor > 0.0:
            e[e < self.error_floor] = 0.0
        return e


def make_suite_function(
    suite: str, number: int, label: str, bound: float, description: str,
    values_of: Callable[[Array, int, int], Array],
    optimum_of: Callable[[int, int], tuple[Array, float]],
    dimensions: tuple[int, ...] | None = None, instances: tuple[int, ...] | None = None,
    error_floor: float = 0.0,
) -> SuiteFunction:
    """Instance 1 of a suite function on the box [-bound, bound]^d, named ``suite:label``."""
    base = SuiteFunction(
        name=f"{suite}:{label}", kernel=_unbound, lower=-bound, upper=bound,
        optimum_coordinate=float("nan"), description=description, suite=suite, number=number,
        dimensions=dimensions, instances=instances, error_floor=error_floor,
        values_of=values_of, optimum_of=optimum_of)
    return base.with_instance(1)


def _unbound(x: Array) -> Array:  # replaced by with_instance
    raise RuntimeError("suite function without an instance")


#: the instance part of a bound name (``@i7`` in ``bbob:f3@i7`` and ``bbob:f3@i7@centre``)
_NAMED_INSTANCE = re.compile(r"@i\d+")


def with_instances(names: list[str], instances: list[int] | None) -> list[str]:
    """Each suite function of ``names`` once per instance (``bbob:f3``, ``bbob:f3@i2``, ...;
    ``bbob:f3@centre``: ``bbob:f3@centre``, ``bbob:f3@i2@centre``, ...),
    the other functions once, duplicates dropped; ValueError if a suite lacks one of the
    instances, none of ``names`` has instances, or a name fixes its instance already
    (``bbob:f3@i7``: re-instancing it would run other functions than the one named, so it is
    refused, not rewritten)."""
    from swarmpath.functions.registry import get_function

    if instances is None:
        return names
    out: list[str] = []
    suites = 0
    for name in names:
        fn = get_function(name)
        if not isinstance(fn, SuiteFunction):
            out.append(name)
            continue
        if _NAMED_INSTANCE.search(name):
            raise ValueError(f"{name} names its instance already; list "
                             f"{_NAMED_INSTANCE.sub('', name)} with instances, or {name} "
                             "without them")
        suites += 1
        for i in instances:  # a centred copy stays centred: its instances' centred copies
            bound = fn.with_instance(i)
            out.append((bound.centred_copy() if fn.centred else bound).name)
    if not suites:
        raise ValueError("only suite functions (bbob:..., cec2017:..., cec2022:...) have "
                         "instances, and none is listed")
    return list(dict.fromkeys(out))
