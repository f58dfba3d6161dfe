"""Benchmark test functions: F1-F13 (Yao et al. 1999, as coded by Mirjalili et al. 2014), the
standard suites ``bbob``, ``cec2017`` and ``cec2022`` (:mod:`swarmpath.functions.suites`), and
plugins' functions and suites, all in one registry.

Extension point (kept stable for plugins): build a :class:`BenchmarkFunction` and register it with
:func:`register_function`, or a whole :class:`Suite` with :func:`register_suite`; an installed
package declares them as entry points of the group ``swarmpath.functions`` (docs/extending.md).

>>> from swarmpath.functions import expand_function_names
>>> expand_function_names("F1-F3,F6-floor")
['F1', 'F2', 'F3', 'F6-floor']
"""

from swarmpath.functions.base import BenchmarkFunction
from swarmpath.functions.expand import expand_function_names
from swarmpath.functions.registry import (
    Suite,
    get_function,
    get_suite,
    list_functions,
    list_names,
    list_suites,
    register_function,
    register_suite,
)

__all__ = [
    "BenchmarkFunction",
    "Suite",
    "expand_function_names",
    "get_function",
    "get_suite",
    "list_functions",
    "list_names",
    "list_suites",
    "register_function",
    "register_suite",
]
