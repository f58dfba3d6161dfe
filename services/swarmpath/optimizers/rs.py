"""Uniform random search: the floor every optimizer must clear.

Each iteration draws ``agents`` points uniformly in the box from the run's own stream and
evaluates them; the result is the best point ever drawn. Evaluations: ``agents`` at
initialization and ``agents`` per iteration, ``agents * (T + 1)`` (the frame's default), so a
budget of N evaluations is exactly N uniform samples (Brooks, "A discussion of random methods for
seeking maxima", Oper. Res. 6 (1958) 244-251; the baseline of COCO and of every CEC comparison).
"""

from __future__ import annotations

from swarmpath.optimizers.base import Optimizer
from swarmpath.optimizers.registry import register


@register
class RS(Optimizer):
    name = "RS"
    summary = "Uniform random search (baseline): agents uniform points per iteration"
    reference = "Brooks, Oper. Res. 6 (1958) 244-251 (pure random search)"
    min_agents = 1

    def _initialize(self) -> None:
        self.evaluate(self.random_population())

    def _iterate(self) -> None:
        self.evaluate(self.random_population())
