"""Benchmark test functions F1-F13 (Yao et al. 1999, as coded by Mirjalili et al. 2014)."""

from swarmpath.functions.registry import (
    BenchmarkFunction,
    expand_function_names,
    get_function,
    list_functions,
)

__all__ = ["BenchmarkFunction", "expand_function_names", "get_function", "list_functions"]
