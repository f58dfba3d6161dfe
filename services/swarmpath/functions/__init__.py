"""Benchmark test functions: F1-F13 (Yao et al. 1999, as coded by Mirjalili et al. 2014) and
the standard suites ``bbob``, ``cec2017`` and ``cec2022`` (:mod:`swarmpath.functions.suites`)."""

from swarmpath.functions.registry import (
    BenchmarkFunction,
    Suite,
    expand_function_names,
    get_function,
    get_suite,
    list_functions,
    list_names,
    list_suites,
    register_suite,
)

__all__ = ["BenchmarkFunction", "Suite", "expand_function_names", "get_function", "get_suite",
           "list_functions", "list_names", "list_suites", "register_suite"]
