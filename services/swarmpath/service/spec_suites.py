"""Suite instances and evaluation budgets in a benchmark job spec (its ``instances`` and
``budget_evals`` fields), checked with the pure layer's rules (``suites.base.with_instances``,
``optimizers.budget``) so that :mod:`.jobspec` stays a list of fields."""

from __future__ import annotations

from pydantic import ValidationInfo

from swarmpath.functions.suites.base import MAX_INSTANCE
from swarmpath.service.model import MAX_ITERATIONS
from swarmpath.service.spec_checks import _unique

__all__ = ["MAX_INSTANCE", "MAX_INSTANCES"]

#: the most instances a job may name
MAX_INSTANCES = 1000


def _with_instances(names: list[str], instances: list[int] | None) -> list[str]:
    """Each suite function once per instance; ValueError (naming ``instances``) if a suite
    lacks one of them or no function has instances."""
    from swarmpath.functions.suites.base import with_instances

    try:
        out = with_instances(names, instances)
    except ValueError as exc:
        raise ValueError(f"instances: {exc}") from None
    _unique(out, "function")
    return out


def _check_budget(v: str | None, info: ValidationInfo) -> str | None:
    """'N' or 'NxD', normalised; ValueError if it is malformed, is too small for an
    algorithm's initialization and first iteration, takes too many iterations, or asks the numba
    backend for a budget a kernel cannot count (``check_compiled_budget``)."""
    from swarmpath.optimizers import ParameterError
    from swarmpath.optimizers.budget import (
        check_compiled_budget,
        parse_budget,
        study_iterations,
    )

    try:
        norm = parse_budget(v)
    except ParameterError as exc:
        raise ValueError(str(exc)) from None
    if norm is None:
        return None
    for a in info.data.get("algorithms") or ():
        for d in info.data.get("dims") or ():
            try:
                t = study_iterations(a, norm, 1, info.data.get("agents") or 1, d,
                                     (info.data.get("params") or {}).get(a))
            except ParameterError as exc:
                raise ValueError(str(exc)) from None
            if t > MAX_ITERATIONS:
                raise ValueError(f"{norm} evaluations take {a} {t} iterations at dim {d}; "
                                 f"at most {MAX_ITERATIONS}")
    try:
        check_compiled_budget(info.data.get("backend", "numpy"), info.data.get("algorithms") or (),
                              norm, 1, info.data.get("agents") or 1, info.data.get("dims") or (),
                              info.data.get("params"))
    except ParameterError as exc:
        raise ValueError(str(exc)) from None
    return norm
