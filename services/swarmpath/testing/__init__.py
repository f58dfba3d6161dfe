"""The conformance gate, as pytest helpers for a plugin's own test suite.

>>> from swarmpath.testing import check_optimizer
>>> check_optimizer("GWO", processes=False, bias=False).ok
True

``check_optimizer(cls_or_name)``, ``check_function(fn_or_name)`` and
``check_planner(cls_or_name)`` raise :class:`ConformanceError` (an AssertionError) naming every
property that fails, and return the :class:`Report` otherwise; ``swarmpath check optimizer|
function|planner NAME`` prints the same report (exit 0 when every property holds, 1 otherwise).
The properties are listed in :mod:`.optimizer`, :mod:`.function` and :mod:`.planner`.
"""

from swarmpath.testing.function import check_function
from swarmpath.testing.optimizer import check_optimizer
from swarmpath.testing.planner import check_planner
from swarmpath.testing.report import ConformanceError, Property, Report

__all__ = ["ConformanceError", "Property", "Report", "check_function", "check_optimizer",
           "check_planner"]
