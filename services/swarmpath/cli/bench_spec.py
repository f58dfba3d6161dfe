"""The options of ``swarmpath bench`` validated into a :class:`BenchSpec`.

:func:`make_spec` checks every option (raising :class:`InputError` naming the bad one) and
returns the frozen study description that :mod:`swarmpath.cli.bench` runs;
:mod:`swarmpath.cli.audit` and :mod:`swarmpath.cli.reproduce` build their studies through it too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from swarmpath.cli.core import InputError, parse_params_option, resolve_names
from swarmpath.functions import expand_function_names, get_function
from swarmpath.functions.suites.base import MAX_INSTANCE, with_instances
from swarmpath.optimizers import ParameterError, get_optimizer, list_optimizers
from swarmpath.optimizers.api import (
    MAX_AGENTS,
    MAX_DIM,
    MAX_ITERATIONS,
    check_backend,
    resolve_transform,
)
from swarmpath.optimizers.budget import (
    budget_at,
    check_compiled_budget,
    parse_budget,
    study_iterations,
)
from swarmpath.optimizers.registry import BASELINES

MAX_RUNS = 10_000

@dataclass(frozen=True)
class BenchSpec:
    algorithms: list[str]
    functions: list[str]
    dims: list[int]
    runs: int = 30
    agents: int = 30
    iterations: int = 500
    seed: int = 1
    shifted: bool = False  # "shift" in transform (kept for readers of the settings)
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: the algorithm the statistical tests compare against (None: the last of ``algorithms``)
    reference: str | None = None
    #: none, shift, rotate or shift+rotate (swarmpath.functions.transforms)
    transform: str = "none"
    #: auto, numpy (the reference) or numba (swarmpath.optimizers.api.BACKENDS)
    backend: str = "auto"
    #: suite instances of the study (None: instance 1); ``functions`` already lists them
    instances: list[int] | None = None
    #: evaluations per run: "N" or "NxD" (N times the dimension); None: agents x iterations
    budget_evals: str | None = None
    #: pool the instances of each function into one cell (evidence.instances)
    pool_instances: bool = False

    def cells(self) -> list[tuple[str, int, str]]:
        """(function, dim, algorithm) in table order."""
        return [(f, d, a) for f in self.functions for d in self.dims for a in self.algorithms]

    def evaluations(self, dim: int) -> int | None:
        """The evaluation budget of one run at ``dim`` (None: no budget)."""
        return budget_at(self.budget_evals, dim)

    def iterations_for(self, algorithm: str, dim: int) -> int:
        """Iterations of ``algorithm`` at ``dim``: ``iterations``, or those spending the budget."""
        return study_iterations(algorithm, self.budget_evals, self.iterations, self.agents, dim,
                                self.params.get(algorithm))

    def settings(self) -> dict[str, Any]:
        return asdict(self)


# ------------------------------------------------------------------------------ input parsing
def _names(spec: str) -> list[str]:
    return [p.strip() for p in spec.split(",") if p.strip()]


def resolve_algorithms(spec: str) -> list[str]:
    """'ICOOT,coot,GWO' -> registered names (case-insensitive, duplicates dropped); 'all' = all."""
    return resolve_names(spec, list_optimizers(), "--algorithms", "algorithm")


def resolve_functions(spec: str) -> list[str]:
    try:
        names = expand_function_names(spec)
    except KeyError as exc:
        raise InputError("--functions", str(exc.args[0])) from None
    names = list(dict.fromkeys(names))
    if not names:
        raise InputError("--functions", "no function given")
    return names


def parse_dims(spec: str) -> list[int]:
    dims: list[int] = []
    for part in _names(spec):
        try:
            d = int(part)
        except ValueError:
            raise InputError("--dims", f"{part!r} is not an integer") from None
        check_range("--dims", d, 1, MAX_DIM)
        if d not in dims:
            dims.append(d)
    if not dims:
        raise InputError("--dims", "no dimension given")
    return dims


def parse_budget_option(spec: str | None) -> str | None:
    """``--budget-evals``: N or NxD (optimizers.budget.parse_budget), InputError naming it."""
    try:
        return parse_budget(spec)
    except ParameterError as exc:
        raise InputError("--budget-evals", str(exc)) from None


def parse_instances(spec: str | None) -> list[int] | None:
    """``--instances``: '1-15', '1,3,5', '1-5,71-80' -> instance ids (each >= 1)."""
    if spec is None:
        return None
    out: list[int] = []
    for part in _names(spec):
        lo, dash, hi = part.partition("-")
        try:
            a, b = (int(lo), int(hi)) if dash else (int(part), int(part))
        except ValueError:
            raise InputError("--instances", f"{part!r} is not an instance or a range a-b") from None
        if not 1 <= a <= b <= MAX_INSTANCE:
            raise InputError("--instances", f"{part!r}: instances are 1..{MAX_INSTANCE}, "
                             "ranges run upwards")
        out.extend(i for i in range(a, b + 1) if i not in out)
    if not out:
        raise InputError("--instances", "no instance given")
    return out


def instances_of(functions: list[str], instances: list[int] | None) -> list[str]:
    """``functions`` with each suite function once per instance (suites.base.with_instances);
    InputError naming ``--instances``."""
    try:
        return with_instances(functions, instances)
    except ValueError as exc:
        raise InputError("--instances", str(exc)) from None


def check_range(option: str, value: int, low: int, high: int) -> int:
    if not low <= value <= high:
        raise InputError(option, f"{value} is not in [{low}, {high}]")
    return value


def parse_params(text: str | None, algorithms: Sequence[str]) -> dict[str, dict[str, Any]]:
    """'{"ICOOT": {"p": 0.5}}' -> params per algorithm, each checked by the algorithm itself."""
    return parse_params_option(
        text, algorithms, "--algorithms", '{"GWO": {"a_max": 2}}',
        lambda name, values: get_optimizer(name).resolve_params(values),
    )


def make_spec(
    algorithms: str,
    functions: str,
    dims: str,
    runs: int = 30,
    agents: int = 30,
    iterations: int = 500,
    seed: int = 1,
    shifted: bool = False,
    params: str | None = None,
    reference: str | None = None,
    transform: str | None = None,
    backend: str = "auto",
    instances: str | None = None,
    budget_evals: str | None = None,
    pool_instances: bool = False,
    baselines: bool = False,
) -> BenchSpec:
    """Validate the command's options; raises :class:`InputError` naming the bad one.
    ``baselines`` appends the strong baselines (:data:`~swarmpath.optimizers.registry.BASELINES`)
    not already listed; the reference stays the last algorithm the user named."""
    kind = resolve_transform_option(shifted, transform)
    algos = resolve_algorithms(algorithms)
    from swarmpath.evidence.stats import resolve_reference

    try:
        ref = resolve_reference(algos, reference)
    except ValueError as exc:
        raise InputError("--reference", str(exc)) from None
    if baselines:
        algos += [b for b in BASELINES if b not in algos]
    ids = parse_instances(instances)
    fns = instances_of(resolve_functions(functions), ids)
    if pool_instances and ids is None:
        raise InputError("--pool-instances", "needs --instances")
    budget = parse_budget_option(budget_evals)
    ds = parse_dims(dims)
    check_range("--runs", runs, 1, MAX_RUNS)
    check_range("--agents", agents, 1, MAX_AGENTS)
    check_range("--iterations", iterations, 1, MAX_ITERATIONS)
    if seed < 0:
        raise InputError("--seed", f"{seed} is negative")
    for a in algos:
        need = get_optimizer(a).min_agents
        if agents < need:
            raise InputError("--agents", f"{a} needs at least {need} agents, got {agents}")
    for f in fns:  # e.g. F5, F12, F13 need 2 dimensions: ask the function itself
        for d in ds:
            try:
                get_function(f).check_study(d, kind)
            except ValueError as exc:
                option = "--transform" if "transform" in str(exc) else "--dims"
                raise InputError(option, f"{d}: {exc}") from None
    checked = parse_params(params, algos)
    try:
        check_backend(backend, algos, kind, checked, fns)
    except ParameterError as exc:
        raise InputError("--backend", str(exc)) from None
    for a in algos:
        for d in ds:
            try:
                study_iterations(a, budget, iterations, agents, d, checked.get(a))
            except ParameterError as exc:
                raise InputError("--budget-evals", str(exc)) from None
    try:
        check_compiled_budget(backend, algos, budget, iterations, agents, ds, checked)
    except ParameterError as exc:
        raise InputError("--backend", str(exc)) from None
    return BenchSpec(
        algorithms=algos,
        functions=fns,
        dims=ds,
        runs=runs,
        agents=agents,
        iterations=iterations,
        seed=seed,
        shifted="shift" in kind,
        params=checked,
        reference=ref,
        transform=kind,
        backend=backend,
        instances=ids,
        budget_evals=budget,
        pool_instances=pool_instances,
    )


def resolve_transform_option(shifted: bool, transform: str | None) -> str:
    """``--transform`` (``--shifted`` is its alias for ``shift``); InputError naming the option."""
    try:
        return resolve_transform(shifted, transform)
    except ParameterError as exc:
        raise InputError("--transform", str(exc)) from None
