"""Swarm optimizers vectorized over agents and independent runs.

>>> from swarmpath.optimizers import minimize, list_optimizers
>>> res = minimize("GWO", "F1", dim=5, agents=10, iterations=20, runs=2, seed=1)
>>> res.best_fitness.shape, res.curve.shape
((2,), (2, 20))
"""

from swarmpath.optimizers.api import Result, create, minimize, minimize_many
from swarmpath.optimizers.base import Optimizer, ParameterError
from swarmpath.optimizers.problem import BenchmarkProblem, Problem
from swarmpath.optimizers.registry import get_optimizer, list_optimizers, register
from swarmpath.optimizers.streams import RunStreams, run_generator

__all__ = [
    "BenchmarkProblem",
    "Optimizer",
    "ParameterError",
    "Problem",
    "Result",
    "RunStreams",
    "create",
    "get_optimizer",
    "list_optimizers",
    "minimize",
    "minimize_many",
    "register",
    "run_generator",
]
