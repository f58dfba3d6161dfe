"""Deliberately broken optimizers: each breaks one property of the conformance gate
(tests/test_conformance.py checks that ``swarmpath check`` names it)."""

import numpy as np

from swarmpath.optimizers import register
from swarmpath.optimizers.gwo import GWO


@register
class GlobalRngGWO(GWO):
    """Perturbs its wolves with the global numpy.random state."""

    name = "broken-global-rng"

    def _iterate(self):
        super()._iterate()
        self.X = self.clip(self.X + 1e-3 * np.random.standard_normal(self.X.shape))  # noqa: NPY002


@register
class OverBudgetGWO(GWO):
    """Evaluates an extra random population every iteration without declaring it."""

    name = "broken-over-budget"

    def _iterate(self):
        super()._iterate()
        self.evaluate(self.random_population())


@register
class BatchDependentGWO(GWO):
    """Moves every run's wolves toward the mean of all runs' leaders: a run depends on the
    others in its batch."""

    name = "broken-batch-dependent"

    def _iterate(self):
        super()._iterate()
        pull = self.best_position.mean(axis=0)
        self.X = self.clip(0.9 * self.X + 0.1 * pull)


@register
class OutOfBoxGWO(GWO):
    """Evaluates points a box-width outside the box (and does not say so)."""

    name = "broken-out-of-box"

    def expected_evaluations(self):  # its extra points are declared: only the box is broken
        return self.N * (2 * self.T + 1), self.N * (2 * self.T + 1)

    def _iterate(self):
        super()._iterate()
        self.evaluate(self.X + (self.ub - self.lb))
