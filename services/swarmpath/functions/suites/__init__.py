"""The standard suites: ``bbob`` (COCO's 24 noiseless functions and instances), ``cec2017``
(30 functions, D = 10, 30, 50, 100) and ``cec2022`` (12 functions, D = 10, 20).

Each suite registers itself with :func:`swarmpath.functions.registry.register_suite`, the way a
plugin registers a suite; the registry loads this package on the first lookup of a name it does
not know. Definitions, sources, data and the golden-value procedure: docs/functions.md.
"""

from __future__ import annotations

from functools import partial

from swarmpath.functions.registry import Suite, register_suite
from swarmpath.functions.suites import bbob, cec
from swarmpath.functions.suites.base import (
    SuiteFunction,
    instance_name,
    make_suite_function,
    split_instance,
)

#: CEC's rule: "error values smaller than 1e-8 are taken as zero" (both competitions)
CEC_ERROR_FLOOR = 1e-8


def _bbob() -> Suite:
    functions = tuple(
        make_suite_function(
            "bbob", k, f"f{k}", bbob.BOUND, bbob.NAMES[k], partial(bbob.values, k),
            partial(bbob.optimum, k))
        for k in range(1, 25))
    return Suite("bbob", functions, tuple(f.name for f in functions),
                 "COCO's 24 noiseless BBOB functions, any dimension >= 2, instances 1, 2, ...")


def _cec(suite: str, count: int, excluded: tuple[int, ...] = ()) -> Suite:
    def description(k: int) -> str:
        return cec.CEC2017[k][1] if suite == "cec2017" else cec.CEC2022[k][1]

    functions = tuple(
        make_suite_function(
            suite, k, f"F{k}", cec.BOUND, description(k), partial(cec.values, suite, k),
            partial(cec.optimum, suite, k), dimensions=cec.DIMENSIONS[suite], instances=(1,),
            error_floor=CEC_ERROR_FLOOR)
        for k in range(1, count + 1))
    members = tuple(f.name for f in functions if f.number not in excluded)
    dims = ", ".join(map(str, cec.DIMENSIONS[suite]))
    return Suite(suite, functions, members,
                 f"the official {suite.upper()} functions with the organisers' data, D = {dims}")


SUITES: tuple[Suite, ...] = (
    register_suite(_bbob()),
    # F2 (sum of different power) was excluded by the organisers: not in the suite's set
    register_suite(_cec("cec2017", 30, excluded=(2,))),
    register_suite(_cec("cec2022", 12)),
)

__all__ = ["SUITES", "SuiteFunction", "instance_name", "split_instance"]
