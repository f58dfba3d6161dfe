"""The options of ``swarmpath bench`` validated into a :class:`BenchSpec`.

:func:`make_spec` checks every option (raising :class:`InputError` naming the bad one) and
returns the frozen study description that :mod:`swarmpath.cli.bench` runs;
:mod:`swarmpath.cli.audit` and :mod:`swarmpath.cli.reproduce` build their studies through it too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from swarmpath.cli.core import InputError, parse_params_option, resolve_names
from swarmpath.functions import expand_function_names, get_function
from swarmpath.optimizers import ParameterError, get_optimizer, list_optimizers
from swarmpath.optimizers.api import (
    MAX_AGENTS,
    MAX_DIM,
    MAX_ITERATIONS,
    check_backend,
    resolve_transform,
)

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
    #: numpy (the reference) or numba (swarmpath.optimizers.api.BACKENDS)
    backend: str = "numpy"

    def cells(self) -> list[tuple[str, int, str]]:
        """(function, dim, algorithm) in table order."""
        return [(f, d, a) for f in self.functions for d in self.dims for a in self.algorithms]

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
    backend: str = "numpy",
) -> BenchSpec:
    """Validate the command's options; raises :class:`InputError` naming the bad one."""
    kind = resolve_transform_option(shifted, transform)
    algos = resolve_algorithms(algorithms)
    from swarmpath.evidence.stats import resolve_reference

    try:
        ref = resolve_reference(algos, reference)
    except ValueError as exc:
        raise InputError("--reference", str(exc)) from None
    fns = resolve_functions(functions)
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
                get_function(f).evaluate(np.zeros((1, d)))
            except ValueError as exc:
                raise InputError("--dims", f"{d}: {exc}") from None
    checked = parse_params(params, algos)
    try:
        check_backend(backend, algos, kind, checked)
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
    )


def resolve_transform_option(shifted: bool, transform: str | None) -> str:
    """``--transform`` (``--shifted`` is its alias for ``shift``); InputError naming the option."""
    try:
        return resolve_transform(shifted, transform)
    except ParameterError as exc:
        raise InputError("--transform", str(exc)) from None
