"""Suite instances and evaluation budgets in a benchmark job spec (its ``instances`` and
``budget_evals`` fields): checked and expanded here, so that :mod:`.jobspec` stays a list of
fields."""

from __future__ import annotations

from pydantic import ValidationInfo

from swarmpath.service.model import MAX_ITERATIONS
from swarmpath.service.spec_checks import _unique

#: the largest suite instance id, and the most instances, a job may name
MAX_INSTANCE = 1_000_000
MAX_INSTANCES = 1000


def _with_instances(names: list[str], instances: list[int] | None) -> list[str]:
    """Each suite function once per instance; ValueError if a suite lacks one of them or no
    function has instances."""
    if instances is None:
        return names
    from swarmpath.functions import get_function

    out: list[str] = []
    for name in names:
        fn = get_function(name)
        if not hasattr(fn, "with_instance"):
            out.append(name)
            continue
        for i in instances:
            try:
                out.append(fn.with_instance(i).name)
            except ValueError as exc:
                raise ValueError(f"instances: {exc}") from None
    if out == names and not any(hasattr(get_function(n), "with_instance") for n in names):
        raise ValueError("instances apply to suite functions (bbob:..., cec2017:..., "
                         "cec2022:...) and none is listed")
    _unique(out, "function")
    return out


def _budget_at(spec: str | None, dim: int) -> int | None:
    if spec is None:
        return None
    number, _, per_dim = spec.partition("x")
    return int(number) * (dim if per_dim else 1)


def _check_budget(v: str | None, info: ValidationInfo) -> str | None:
    """'N' or 'NxD', normalised; ValueError if it is malformed, needs numba, or is too small
    for an algorithm's initialization and first iteration."""
    if v is None:
        return None
    text = v.strip().replace("*", "x")
    number, sep, per_dim = text.partition("x")
    if (sep and per_dim.strip().upper() != "D") or not number.strip().isdigit() or not (
            1 <= int(number) <= 10**9):
        raise ValueError(f"{v!r} is not a positive integer N or NxD (e.g. '10000xD')")
    norm = f"{int(number)}xD" if sep else str(int(number))
    if info.data.get("backend", "numpy") != "numpy":
        raise ValueError("an evaluation budget runs on backend 'numpy' only")
    from swarmpath.optimizers import ParameterError
    from swarmpath.optimizers.budget import iterations_for_budget

    agents = info.data.get("agents")
    for a in info.data.get("algorithms") or ():
        for d in info.data.get("dims") or ():
            try:
                t = iterations_for_budget(a, _budget_at(norm, d) or 0, agents or 1, d,
                                          (info.data.get("params") or {}).get(a))
            except ParameterError as exc:
                raise ValueError(str(exc)) from None
            if t > MAX_ITERATIONS:
                raise ValueError(f"{norm} evaluations take {a} {t} iterations at dim {d}; "
                                 f"at most {MAX_ITERATIONS}")
    return norm


